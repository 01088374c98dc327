//! The ground without contact settings, held inside implicit Euler's linear solves. Clamped
//! only after the solve, a body pressed onto the ground at a frame's step went through it in
//! each solve and was lifted back by the clamp, which a gas body paid back as energy: a gas
//! ball at 1/30 s rose from 73 J to 151 J and still moved at 0.8 m/s after 10 s
//! (`docs/performance-log.md`, 2026-12-06).
//!
//! Here a particle whose end x0 + h v would lie at or under the ground has its vertical
//! velocity set to end on it, and that row filtered out of the solve ([`super::cg`]); the
//! ground is frictionless, as the clamp is. Which particles it holds is settled by an active
//! set, a few solves at most: a held particle lets go when the ground would have to pull it
//! down (its row's constraint impulse, (A Δv − b)_y, is negative), and a free one that the
//! solve put under the ground is held. The step's clamp (pass 4) still takes whatever the last
//! solve left under it.

use super::cg::{CgSettings, FREE, HELD, add_to_velocities, solve, times_a, unfiltered};
use crate::solver::methods::scratch::Scratch;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// The most solves a Newton step takes to settle which particles the ground holds. Most steps
/// need one: of the gas ball's 300 steps at 1/30 s, 296 took one solve, 3 two and 1 three
/// (its landing); of a 128 × 128 cloth's first 60 at 1/60 s, landing flat, 39 one, 17 two and
/// 4 three (2026-12-06, Intel Xeon). What the last solve leaves under the ground, the clamp
/// takes.
const ROUNDS: u32 = 4;

/// How far above the ground an iterate may end and still count as on it: a held particle's
/// end, x0 + h v, lands on the ground only to round-off.
const ON_GROUND: f64 = 1e-9;

/// Solves the Newton step's system (b in `sc.cg.z`) with the particles at or under `ground`
/// held on it, and adds the solution to the velocities.
pub(super) fn solve_on_ground(
    s: &mut State,
    sc: &mut Scratch,
    (dt, h2): (f64, f64),
    b_norm2: f64,
    settings: CgSettings,
    ground: f64,
    threads: &Threads,
) {
    let n = s.x.len();
    let cg = &mut sc.cg;
    cg.b.clear();
    cg.b.extend_from_slice(&cg.z);
    unfiltered(&mut cg.pins, &s.inv_mass);
    cg.filter.clone_from(&cg.pins);
    // The first set: the particles that the iterate already ends at or under the ground.
    for i in 0..n {
        if cg.filter[i] == FREE && s.x[i].y + dt * s.v[i].y <= ground + ON_GROUND {
            hold(
                &mut cg.filter[i],
                &mut cg.dv[i],
                s.x[i].y,
                s.v[i].y,
                ground,
                dt,
            );
        }
    }
    let mut rounds = 0;
    loop {
        sc.cg.z.copy_from_slice(&sc.cg.b);
        solve(s, sc, h2, b_norm2, settings, threads);
        rounds += 1;
        if rounds == ROUNDS || !settle(s, sc, (dt, h2), ground, threads) {
            break;
        }
    }
    add_to_velocities(s, &sc.cg.dv, threads);
}

/// Holds a particle on the ground: its row filtered, its Δv_y set so that x0 + h (v + Δv)
/// ends on the ground.
fn hold(filter: &mut DVec2, dv: &mut DVec2, y: f64, vy: f64, ground: f64, dt: f64) {
    *filter = HELD;
    dv.y = (ground - y) / dt - vy;
}

/// After a solve: lets go of the held particles the ground would pull down and holds the free
/// ones the solve put under it. Returns whether the set changed (so another solve is due).
fn settle(
    s: &State,
    sc: &mut Scratch,
    (dt, h2): (f64, f64),
    ground: f64,
    threads: &Threads,
) -> bool {
    let cg = &mut sc.cg;
    let mut changed = false;
    if cg.filter.contains(&HELD) {
        // The constraint impulses: (A Δv − b) in the held rows, A's rows unfiltered there.
        let matrix = (s, &sc.gas, &cg.blocks[..]);
        times_a(
            threads,
            matrix,
            &mut cg.buffers,
            &mut cg.ap,
            &cg.dv,
            &cg.pins,
            h2,
        );
    }
    for i in 0..s.x.len() {
        let f = &mut cg.filter[i];
        if *f == HELD {
            if cg.ap[i].y - cg.b[i].y < 0.0 {
                *f = FREE;
                changed = true;
            }
        } else if *f == FREE && s.x[i].y + dt * (s.v[i].y + cg.dv[i].y) < ground {
            hold(f, &mut cg.dv[i], s.x[i].y, s.v[i].y, ground, dt);
            changed = true;
        }
    }
    changed
}
