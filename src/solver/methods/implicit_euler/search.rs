//! The line search along each Newton step after the first, where implicit Euler takes more than
//! one (always with contact: [`super::CONTACT_NEWTON`]).
//!
//! Why: the Newton matrix drops the transverse term of compressed springs (so that it stays
//! positive definite), and a chain bent and pressed by contact is far from its linearisation:
//! the full step can overshoot the backward Euler step by far. In the shipped `ropes` at 1/30 s
//! (hω = 15), rope particles lying on another rope over a peg were flung 9 cm up by a step's last
//! Newton step, their springs stretched to 6 times their rest length, and the scene's energy rose
//! from 51.2 J to 254 J (`docs/performance-log.md`, 2026-12-07).
//!
//! How: the step δ solves A δ = b with A positive definite, b the residual at the step's start,
//! so it descends the backward Euler step's objective Φ, whose gradient is the residual's
//! opposite: r(v) = M (v0 − v) + h f(x0 + h v) + h f_contact. Along the step, Φ's slope is
//! −g(α), g(α) = r(v + α δ)·δ, which starts at b·δ = δᵀ A δ. The full step is kept unless Φ is
//! already rising steeply where it ends, g(1) < −[`OVERSHOOT`] b·δ; then secant steps on g toward
//! its root, [`TRIES`] force evaluations at most. Only forces are evaluated (the step's own force
//! pass, dashpots and gas bodies included), so no potential of any force is needed. The ground's
//! held rows keep their way onto the ground.
//!
//! Not the first Newton step: it is the classic step linearised at x0, whose right-hand side is
//! not the residual at its start, so b·δ is no slope of Φ there; searched too, the shipped
//! `balloon` at 1/30 s rose from 117 J to 160 J.

use super::cg::PINNED;
use crate::solver::methods::evaluate::forces_at;
use crate::solver::methods::scratch::Scratch;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// How far past the objective's minimum along the step the full step may end, as the slope it
/// ends on over the model's slope at its start: on a quadratic objective the full step lands
/// on the minimum (g(1) = 0); g(1) = −b·δ would be twice the way to it. At 1/30 s, with 1 the
/// shipped `ropes` peaked at 95.7 J and the `crates` at 375 J, with 1/2 at 63.2 J and 211 J
/// (from 51.2 J and 48.7 J).
const OVERSHOOT: f64 = 0.5;

/// The most force evaluations past the full step's.
const TRIES: u32 = 3;

/// The shortest step the search takes, as a share of the full one.
const SHORTEST: f64 = 1.0 / 16.0;

/// Shortens the Newton step just added to the velocities (`sc.cg.dv`, the solution of
/// A δ = `sc.cg.b` in the rows `sc.cg.filter` lets through) where the full step overshoots (see
/// the module's notes); `sc.stage_v` holds v0. Leaves f(x0 + h v) in `sc.f` and x0 + h v in
/// `sc.x`, for the next Newton step.
pub(super) fn along_step(
    s: &mut State,
    sc: &mut Scratch,
    dt: f64,
    gravity: DVec2,
    threads: &Threads,
) {
    let n = s.x.len();
    let cg = &sc.cg;
    let mut start = 0.0;
    for i in 0..n {
        if cg.filter[i] != PINNED {
            start += cg.b[i].dot(cg.dv[i] * cg.filter[i]);
        }
    }
    if start <= 0.0 || !start.is_finite() {
        slope_at(s, sc, dt, gravity, threads);
        return;
    }
    let mut alpha = 1.0;
    let mut slope = slope_at(s, sc, dt, gravity, threads);
    for _ in 0..TRIES {
        if slope >= -OVERSHOOT * start || alpha <= SHORTEST {
            break;
        }
        // The secant between the model's slope at 0 and the slope here, at least a tenth
        // shorter.
        let next = (alpha * start / (start - slope))
            .max(SHORTEST)
            .min(alpha * 0.9);
        let cg = &sc.cg;
        for i in 0..n {
            s.v[i] += cg.dv[i] * cg.filter[i] * (next - alpha);
        }
        alpha = next;
        slope = slope_at(s, sc, dt, gravity, threads);
    }
}

/// g = r(v)·δ at the velocities `s.v` (the filtered rows' δ alone), the forces f(x0 + h v)
/// left in `sc.f`.
fn slope_at(s: &State, sc: &mut Scratch, dt: f64, gravity: DVec2, threads: &Threads) -> f64 {
    let n = s.x.len();
    for i in 0..n {
        sc.x[i] = s.x[i] + s.v[i] * dt;
    }
    forces_at(s, &mut sc.pairs, &mut sc.f, (&sc.x, &s.v), gravity, threads);
    let (cg, support) = (&sc.cg, &sc.support);
    let mut slope = 0.0;
    for i in 0..n {
        if cg.filter[i] == PINNED {
            continue;
        }
        let r = (sc.stage_v[i] - s.v[i]) * s.mass[i] + (sc.f[i] + support.force(i)) * dt;
        slope += r.dot(cg.dv[i] * cg.filter[i]);
    }
    slope
}
