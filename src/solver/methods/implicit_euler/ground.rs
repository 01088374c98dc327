//! The ground held inside implicit Euler's linear solves. Clamped only after the solve (or,
//! with contact set, projected after each Newton step), a body pressed onto the ground at a
//! frame's step went through it in each solve and was lifted back, which a gas body paid back
//! as energy: a gas ball at 1/30 s rose from 73 J to 151 J and still moved at 0.8 m/s after
//! 10 s (148 J with contact set; `docs/performance-log.md`, 2026-12-06).
//!
//! Here a particle whose end x0 + h v would lie at or under the ground has its vertical
//! velocity set to end on it, and that row filtered out of the solve ([`super::cg`]). Which
//! particles it holds is settled by an active set, a few solves at most: a held particle lets
//! go when the ground would have to pull it down (its row's constraint impulse,
//! (A Δv − b)_y, is negative), and a free one that the solve put under the ground is held.
//! Without contact settings the ground is frictionless, as the step's clamp (pass 4) is, and
//! the clamp still takes whatever the last solve left under it. With contact set the ground is
//! the contact's, at its radius, still kept by the projection too, and its friction is
//! Coulomb's from the held rows' impulses ([`rub`]).

use super::cg::{CgSettings, FREE, HELD, add_to_velocities, solve, times_a, unfiltered};
use crate::solver::contact::slide::NO_GROUP;
use crate::solver::methods::scratch::Scratch;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// The ground the solves hold particles on: its height (plus the contact radius, with contact
/// set) and its friction coefficient (0 without contact settings, as the clamp has none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    pub height: f64,
    pub friction: f64,
}

/// The most solves a Newton step takes to settle which particles the ground holds. Without
/// contact most steps need one: of the gas ball's 300 steps at 1/30 s, 296 took one solve, 3 two
/// and 1 three (its landing); of a 128 × 128 cloth's first 60 at 1/60 s, landing flat, 39 one,
/// 17 two and 4 three. On the shipped pile at 1/60 s (contact set, pairs) most take two: 70
/// Newton steps one, 1,036 two, 331 three and 3 four. Capped at one solve, the pile rose from
/// 181 J to 224 J at 1/60 s and `folding_cloth` from 8.8 J to 1,169 J; capped at two,
/// `folding_cloth` at 1/30 s reached 167 J, against 88 J at four (2026-12-06, Intel Xeon).
/// What the last solve leaves under the ground, the clamp or the projection takes.
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
    ground: Ground,
    threads: &Threads,
) {
    let ground = ground.height;
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
    if sc.cg.filter.contains(&HELD) {
        impulses(s, sc, h2, threads);
    }
    let cg = &mut sc.cg;
    let mut changed = false;
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

/// Coulomb friction on the particles the ground held in the last solve (its right-hand side in
/// `cg.b`, its solution in `cg.dv`), after the step's last Newton step, body by body: each group of
/// particles joined by springs (`contact::slide::Slides`) that the ground holds somewhere has its
/// horizontal velocity slowed, every member alike, toward its held particles' mean (weighted by
/// their pushes) by up to μ J / M, J the ground's push on the group over the step, Σ (A Δv − b)_y
/// over its held rows, and M its mass. A particle whose group a pin holds is slowed alone, by up to
/// μ j / m. The contact's projection rubs only what it pushes, and the particles held here end on
/// the ground, where it pushes nothing.
///
/// Why whole bodies: slowed particle by particle, after a solve that had moved them with their
/// neighbours, the held particles were held still while the rest slid on, and the springs
/// between them stretched: a box sliding on the ground at 2 m/s with μ = 0.5 rose from 1.65 J
/// to 58.7 J at 1/30 s, and the `paddle`'s strip, its end landing first under the leaning strip's
/// push, rose from 10.4 J to 36.8 J at 1/60 s (`docs/performance-log.md`, 2026-12-07).
pub(super) fn rub(s: &mut State, sc: &mut Scratch, h2: f64, friction: f64, threads: &Threads) {
    if friction == 0.0 || !sc.cg.filter.contains(&HELD) {
        return;
    }
    impulses(s, sc, h2, threads);
    let cg = &sc.cg;
    let push = |i: usize| {
        if cg.filter[i] == HELD {
            (cg.ap[i].y - cg.b[i].y).max(0.0)
        } else {
            0.0
        }
    };
    sc.groups.ready(s);
    for (members, mass) in sc.groups.groups() {
        let (mut pushed, mut sliding) = (0.0, 0.0);
        for &i in members {
            let j = push(i as usize);
            pushed += j;
            sliding += j * s.v[i as usize].x;
        }
        if pushed == 0.0 {
            continue;
        }
        let sliding = sliding / pushed;
        let reach = friction * pushed / mass;
        let change = -sliding.signum() * sliding.abs().min(reach);
        for &i in members {
            s.v[i as usize].x += change;
        }
    }
    for i in 0..s.x.len() {
        if sc.groups.group_of(i) == NO_GROUP && cg.filter[i] == HELD {
            let slowed = friction * push(i) * s.inv_mass[i];
            let v = &mut s.v[i].x;
            *v = v.signum() * (v.abs() - slowed).max(0.0);
        }
    }
}

/// A Δv into `cg.ap` with the held rows unfiltered, so that (A Δv − b)_y in a held row is the
/// ground's push on that particle over the step (its constraint impulse, N·s).
fn impulses(s: &State, sc: &mut Scratch, h2: f64, threads: &Threads) {
    let cg = &mut sc.cg;
    let matrix = (s, &sc.gas, &cg.blocks[..]);
    let (out, dv, pins) = (&mut cg.ap, &cg.dv, &cg.pins);
    times_a(threads, matrix, &mut cg.buffers, out, dv, pins, h2);
}
