//! The explicit multi-stage methods' updates: velocity Verlet and RK4. Each computes, from the
//! start-of-step state (x0, v0) and force f0 = f(x0), the end-of-step velocity v1 and the drift
//! velocity u with which the position update moves the particle (x1 = x0 + dt u); the table of
//! what each computes is in [`crate::solver::step`], with the passes around them. The Euler
//! methods' kick is the step's own pass ([`crate::solver::step::kick`]).
//!
//! Every stage's force evaluation starts from the body forces ([`forces_at`]).

use super::evaluate::forces_at;
use super::scratch::Scratch;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// A stage's evaluation: f(x, v) at the positions in `scratch.x` and the stage velocities in
/// `scratch.stage_v`, into `scratch.f`.
fn stage_forces(s: &State, sc: &mut Scratch, g: DVec2, threads: &Threads) {
    forces_at(
        s,
        &mut sc.pairs,
        &mut sc.f,
        (&sc.x, &sc.stage_v),
        g,
        threads,
    );
}

/// Velocity Verlet, kick-drift-kick, with a second force evaluation at x0 + dt v½.
///
/// With dashpots the second half kick is implicit in the velocity, v1 = v½ + h/2 a(x1, v1):
/// it is evaluated at v½, then corrected once at the predicted v1 (the dashpot force is
/// linear in the velocity, so the correction is one dashpot pass over the difference). Each
/// correction gains a power of h, so the method stays second order; evaluated at v½ alone
/// it would be first order in the damping.
pub fn velocity_verlet(
    s: &mut State,
    sc: &mut Scratch,
    dt: f64,
    gravity: DVec2,
    threads: &Threads,
) {
    sc.fit(s.x.len());
    s.drift_buffer();
    let (half, springs) = (0.5 * dt, s.springs.len());
    let sc = &mut *sc;
    let data = (
        &mut s.drift[..],
        &mut sc.x[..],
        &mut sc.stage_v[..],
        &s.x[..],
        &s.v[..],
        &s.f[..],
        &s.inv_mass[..],
    );
    threads.each(springs, data, |(u, xs, vs, x, v, f, w)| {
        for i in 0..u.len() {
            let v_half = v[i] + f[i] * (half * w[i]);
            u[i] = v_half;
            vs[i] = v_half;
            xs[i] = x[i] + v_half * dt;
        }
    });
    stage_forces(s, sc, gravity, threads);
    if s.materials.has_dashpots() {
        // The predicted v1 − v½ = h/2 a(x1, v½), and the dashpot force of that difference.
        for ((dv, f), w) in sc.stage_v.iter_mut().zip(&sc.f).zip(&s.inv_mass) {
            *dv = *f * (half * w);
        }
        s.materials
            .add_dashpot_forces(&s.springs, &sc.x, &sc.stage_v, &mut sc.f);
    }
    let sc = &mut *sc;
    let data = (&mut s.v[..], &s.drift[..], &sc.f[..], &s.inv_mass[..]);
    threads.each(springs, data, |(v, u, f, w)| {
        for i in 0..v.len() {
            v[i] = u[i] + f[i] * (half * w[i]);
        }
    });
}

/// Classic RK4 on x' = v, v' = f(x)/m.
pub fn rk4(s: &mut State, sc: &mut Scratch, dt: f64, gravity: DVec2, threads: &Threads) {
    sc.fit(s.x.len());
    s.drift_buffer();
    let springs = s.springs.len();
    let sc = &mut *sc;
    // Stage 1: (v0, a0).
    let data = (
        &mut sc.sum_u[..],
        &mut sc.sum_a[..],
        &mut sc.stage_v[..],
        &mut sc.f[..], // holds the previous stage's acceleration
        &s.v[..],
        &s.f[..],
        &s.inv_mass[..],
    );
    threads.each(springs, data, |(sum_u, sum_a, stage_v, acc, v, f, w)| {
        for i in 0..v.len() {
            let a = f[i] * w[i];
            sum_u[i] = v[i];
            sum_a[i] = a;
            stage_v[i] = v[i];
            acc[i] = a;
        }
    });
    // Stages 2..4: evaluate at x0 + c dt k_x(prev), with k_v(prev) advancing the velocity.
    for (c, weight) in [(0.5, 2.0), (0.5, 2.0), (1.0, 1.0)] {
        let h = c * dt;
        let sc = &mut *sc;
        let data = (
            &mut sc.x[..],
            &mut sc.stage_v[..],
            &sc.f[..],
            &s.x[..],
            &s.v[..],
        );
        threads.each(springs, data, |(xs, stage_v, acc, x, v)| {
            for i in 0..x.len() {
                let (kx, ka) = (stage_v[i], acc[i]);
                xs[i] = x[i] + kx * h;
                stage_v[i] = v[i] + ka * h;
            }
        });
        stage_forces(s, sc, gravity, threads);
        let sc = &mut *sc;
        let data = (
            &mut sc.f[..],
            &mut sc.sum_u[..],
            &mut sc.sum_a[..],
            &sc.stage_v[..],
            &s.inv_mass[..],
        );
        threads.each(springs, data, |(acc, sum_u, sum_a, stage_v, w)| {
            for i in 0..acc.len() {
                acc[i] *= w[i];
                sum_u[i] += stage_v[i] * weight;
                sum_a[i] += acc[i] * weight;
            }
        });
    }
    let sc = &*sc;
    let data = (&mut s.drift[..], &mut s.v[..], &sc.sum_u[..], &sc.sum_a[..]);
    threads.each(springs, data, |(u, v, sum_u, sum_a)| {
        for i in 0..u.len() {
            u[i] = sum_u[i] / 6.0;
            v[i] += sum_a[i] * (dt / 6.0);
        }
    });
}
