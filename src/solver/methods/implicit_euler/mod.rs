//! Implicit (backward) Euler: Newton's steps on M (v − v0) = h f(x0 + h v), each linear solve
//! by block-Jacobi-preconditioned conjugate gradients on the pool's threads. It computes the
//! end-of-step velocity v1 from the start-of-step state; the position update follows in the
//! step's drift pass ([`crate::solver::step`]). Beside this file: the linear solve with its
//! row filter ([`cg`]), the ground held inside it ([`ground`]) and the line search along the
//! Newton steps after the first ([`search`]).

mod cg;
mod ground;
mod search;

pub use cg::CgSettings;
pub use ground::Ground;

use super::evaluate::forces_at;
use super::scratch::Scratch;
use crate::solver::contact::inside::InSolve;
use crate::solver::contact::slide::{Contact, LEFT_ALONE, NO_CONTACT};
use crate::solver::forces::stiffness;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// Newton steps at least, when contact is kept inside the solve: with one, the step is a solve
/// and then a projection of its end, and the learned contact forces never reach a solve. On
/// the shipped pile at 1/60 s (2-core AMD EPYC, 2026-12-04): with 1, pairs closed to 49 % of 2r
/// and the energy rose from 181 J to 248 J; with 4, pairs at 77 % of 2r or more and the energy
/// never above its start (8 did no better: 72 %). With the ground held in the solves too
/// ([`ground`]; 2026-12-06, Intel Xeon), 4 leave pairs at 69 % and no cell turned.
pub const CONTACT_NEWTON: u32 = 4;

/// Passes over the particle pairs in each projection between Newton steps
/// ([`InSolve::with_pair_passes`]); a pair that meets within the step is pushed apart along
/// the line it met on ([`InSolve::holding_sides`]). With one pass along each pair's own line,
/// a fold of `folding_cloth` landing on the strip below it at 1/60 s ended the Newton steps
/// with pairs at half of 2r, and the pass after the step pushed them out into the springs:
/// its energy rose from 8.8 J to 52 J, against 8.8 J now from 1/120 to 1/50 s
/// (`docs/performance-log.md`, 2026-12-08).
const PAIR_PASSES: usize = 8;

/// Backward Euler by Newton's method on M (v − v0) = h f(x0 + h v), `newton` steps, each linear
/// solve by block-Jacobi-preconditioned conjugate gradients.
///
/// The first step is the classic one (Baraff and Witkin), linearised at x0:
/// (M − h² K0 − h D0) Δv = h (f0 + h K0 v0), v1 = v0 + Δv, warm-started from the previous
/// step's Δv, with D = ∂f/∂v the dashpots' damping matrix and K0 the springs' Jacobian plus
/// the gas bodies' positive semi-definite part ([`GasJacobian`]).
/// Each further step linearises at x_k = x0 + h v_k: (M − h² K_k) δ = M (v0 − v_k) + h f(x_k),
/// v_{k+1} = v_k + α δ (α = 1 unless the full step overshoots, [`search`]), which converges to
/// the exact backward Euler step. K is the spring Jacobian
/// with the transverse term of compressed springs dropped (coefficient max(0, 1 − L/l)), which
/// keeps M − h² K symmetric positive definite; the residual is exact, so the iteration still
/// converges to the exact step, only the rate changes. Pinned particles are held (their rows
/// are projected out), and so is the vertical row of a particle that `ground` holds
/// ([`ground`]: the bare ground, or the contact's); `contact` (obstacles, pairs, the ground
/// with contact set) is kept by projections after each Newton step. K u and the vector
/// updates share the solver threads like the explicit passes; the reductions sum per chunk,
/// so the thread count changes the result by round-off.
#[allow(clippy::too_many_arguments)]
pub fn implicit_euler(
    s: &mut State,
    sc: &mut Scratch,
    dt: f64,
    settings: CgSettings,
    newton: u32,
    gravity: DVec2,
    (contact, ground): (Option<&InSolve>, Option<Ground>),
    threads: &Threads,
) {
    let n = s.x.len();
    let springs = s.springs.len();
    sc.fit(n);
    sc.cg.fit(n, springs);
    let h2 = dt * dt;
    if contact.is_some() {
        // The learned forces over-relaxed as projective dynamics' are, and searched body by
        // body ([`Support::search_by_body`]). Unrelaxed (g = 1), a fold of `folding_cloth`
        // landing at 1/60 s learned a tenth of the force that stops it in four Newton steps,
        // and the pass after the step pushed the rest out into its springs (8.8 J to 52 J).
        // That g once lifted resting particles off their contact (two soft boxes stacked at
        // 1/600 s kept 1.9e-5 J of jitter); that stack's test holds with it now.
        //
        // [`Support::search_by_body`]: crate::solver::contact::support::Support::search_by_body
        sc.support.start(s, &s.x, h2);
        sc.support.search_by_body(s);
    }
    // Contact in the solve needs Newton steps after the first: the contact forces learned from
    // one step's projection enter the next one's solve ([`CONTACT_NEWTON`]).
    let newton = if contact.is_some() {
        newton.max(CONTACT_NEWTON)
    } else {
        newton
    };
    if newton > 1 {
        sc.stage_v.copy_from_slice(&s.v); // v0
    }

    // Step 1: b = dt (f0 + dt K0 v0), zero on pinned particles, into z.
    let cg = &mut sc.cg;
    stiffness::blocks_threaded(threads, &s.springs, &s.x, &mut cg.blocks);
    stiffness::apply_threaded(threads, &mut cg.buffers, &mut cg.ap, &s.v, &cg.blocks); // K v0
    let gas = &mut sc.gas;
    gas.at(&s.materials, &s.x);
    gas.add_product(&s.v, &mut cg.ap);
    // The dashpots' damping matrix joins K in the Newton matrix, not in K v0.
    s.materials.add_dashpot_blocks(&mut cg.blocks, &s.x, dt);
    let data = (&mut cg.z[..], &s.f[..], &cg.ap[..], &s.inv_mass[..]);
    let b_norm2 = threads.chunked(
        springs,
        data,
        |(z, f, kv, w)| {
            let mut norm2 = DVec2::ZERO;
            for i in 0..z.len() {
                let b = if w[i] != 0.0 {
                    (f[i] - kv[i] * dt) * dt
                } else {
                    DVec2::ZERO
                };
                z[i] = b;
                norm2 += b * b;
            }
            norm2
        },
        |a, b| a + b,
    );
    let linear = (h2, b_norm2.element_sum(), settings);
    // The first step is the classic linearised one, whose right-hand side is not the residual
    // at its start: the line search serves the steps after it ([`search`]).
    newton_step(
        s,
        sc,
        dt,
        linear,
        (contact, ground),
        (newton > 1, None),
        threads,
    );
    if newton > 1 {
        // The first step's Δv warm-starts the next time step's first solve.
        let sc = &mut *sc;
        sc.sum_u.copy_from_slice(&sc.cg.dv);
    }

    let searched = Some(gravity);
    for k in 1..newton {
        // x_k = x0 + h v_k and f(x_k), into the stage buffers: the last step's line search left
        // them there where no contact moved the iterate since ([`search::along_step`]).
        let sc = &mut *sc;
        if k == 1 || contact.is_some() {
            threads.each(
                springs,
                (&mut sc.x[..], &s.x[..], &s.v[..]),
                |(xk, x, v)| {
                    for i in 0..xk.len() {
                        xk[i] = x[i] + v[i] * dt;
                    }
                },
            );
            // f(x_k, v_k): the dashpots see the iterate's velocity.
            forces_at(s, &mut sc.pairs, &mut sc.f, (&sc.x, &s.v), gravity, threads);
        }
        let sc = &mut *sc;
        let cg = &mut sc.cg;
        stiffness::blocks_threaded(threads, &s.springs, &sc.x, &mut cg.blocks);
        s.materials.add_dashpot_blocks(&mut cg.blocks, &sc.x, dt);
        sc.gas.at(&s.materials, &sc.x);
        // b = M (v0 − v_k) + h f(x_k); δ starts from 0.
        let data = (
            &mut cg.z[..],
            &mut cg.dv[..],
            &sc.f[..],
            &sc.stage_v[..],
            &s.v[..],
            &s.mass[..],
            &s.inv_mass[..],
        );
        let b_norm2 = threads.chunked(
            springs,
            data,
            |(z, dv, f, v0, v, m, w)| {
                let mut norm2 = DVec2::ZERO;
                for i in 0..z.len() {
                    let b = if w[i] != 0.0 {
                        (v0[i] - v[i]) * m[i] + f[i] * dt
                    } else {
                        DVec2::ZERO
                    };
                    z[i] = b;
                    dv[i] = DVec2::ZERO;
                    norm2 += b * b;
                }
                norm2
            },
            |a, b| a + b,
        );
        let linear = (h2, b_norm2.element_sum(), settings);
        newton_step(
            s,
            sc,
            dt,
            linear,
            (contact, ground),
            (k + 1 < newton, searched),
            threads,
        );
    }
    let sc = &mut *sc;
    if let Some(c) = contact {
        sc.support.note_reactions(c, &s.mass, dt);
    }
    if let Some(g) = ground {
        ground::rub(s, sc, h2, g.friction, threads);
    }
    if let Some(c) = contact {
        rub_surfaces(s, sc, c, dt);
        hold_out_after_rubbing(s, c, ground, dt);
    }
    if newton > 1 {
        sc.cg.dv.copy_from_slice(&sc.sum_u);
    }
    sc.newton_steps += newton.max(1) as u64;
    sc.newton_solves += 1;
}

/// One Newton step's linear solve for the right-hand side in `sc.cg.z` (`linear`: h², |b|²
/// and the CG settings), with contact inside it: the contact forces added to b before the
/// solve, and the end positions held out of contact after it.
#[allow(clippy::too_many_arguments)]
fn newton_step(
    s: &mut State,
    sc: &mut Scratch,
    dt: f64,
    (h2, b_norm2, settings): (f64, f64, CgSettings),
    (contact, ground): (Option<&InSolve>, Option<Ground>),
    (more, searched): (bool, Option<DVec2>),
    threads: &Threads,
) {
    let b_norm2 = with_support(s, sc, dt, contact, b_norm2);
    match ground {
        Some(ground) => {
            ground::solve_on_ground(s, sc, (dt, h2), b_norm2, settings, ground, threads)
        }
        None => {
            cg::unfiltered(&mut sc.cg.filter, &s.inv_mass);
            if searched.is_some() {
                sc.cg.b.clone_from(&sc.cg.z);
            }
            cg::solve(s, sc, h2, b_norm2, settings, threads);
            cg::add_to_velocities(s, &sc.cg.dv, threads);
        }
    }
    if let Some(gravity) = searched {
        search::along_step(s, sc, dt, gravity, threads);
    }
    if let Some(c) = contact {
        hold_to_contact(s, sc, dt, c, ground, more.then_some((settings, threads)));
    }
}

/// The contact forces carried from the last solves
/// ([`crate::solver::contact::support::Support`]) added to the right-hand side in `sc.cg.z` as
/// their impulse over dt (free particles only); returns |b|², anew when they are there.
fn with_support(
    s: &State,
    sc: &mut Scratch,
    dt: f64,
    contact: Option<&InSolve>,
    b_norm2: f64,
) -> f64 {
    match contact {
        Some(_) => {
            let z = &mut sc.cg.z;
            sc.support.add_to(z, dt);
            let mut norm2 = 0.0;
            for (z, &w) in z.iter_mut().zip(&s.inv_mass) {
                if w == 0.0 {
                    *z = DVec2::ZERO;
                }
                norm2 += z.length_squared();
            }
            norm2
        }
        None => b_norm2,
    }
}

/// Contact inside the solve: the end positions x0 + h v that the Newton step found, kept out of
/// the surfaces and the other particles ([`InSolve`]), and the velocity set to where they
/// went, so that the next Newton step linearises where contact holds the particles. With
/// `search` (every Newton step but the last), the change of the forces the projection learned
/// is sized by projective dynamics' line search ([`answer_change`]) and the ends projected
/// again: learned particle by particle, the forces that stopped a landing ball's lowest
/// particles flung it (the `balloon` at 1/30 s rose from 117 J to 29,190 J). An obstacle's push
/// may put a particle under a bare ground that the solve held ([`ground`]): it goes back onto
/// it, as the clamp would.
fn hold_to_contact(
    s: &mut State,
    sc: &mut Scratch,
    dt: f64,
    c: &InSolve,
    ground: Option<Ground>,
    search: Option<(CgSettings, &Threads)>,
) {
    let n = s.x.len();
    let c = &c.holding_sides(&s.x).with_pair_passes(PAIR_PASSES);
    sc.x.resize(n, DVec2::ZERO);
    sc.contact.resize(c.pair_scratch(), DVec2::ZERO);
    for i in 0..n {
        sc.x[i] = s.x[i] + s.v[i] * dt;
    }
    let (m, w, scratch) = (&s.mass[..], &s.inv_mass[..], &mut sc.contact);
    let stiffness = 1.0 / (dt * dt);
    sc.support
        .project(c, &mut sc.x, &s.x, m, w, scratch, stiffness);
    if let Some((settings, threads)) = search
        && answer_change(s, sc, dt * dt, settings, threads)
    {
        sc.support.line_search(&mut sc.x, &s.mass, &sc.answer);
        let (m, w, scratch) = (&s.mass[..], &s.inv_mass[..], &mut sc.contact);
        sc.support
            .project(c, &mut sc.x, &s.x, m, w, scratch, stiffness);
    }
    let inv_h = 1.0 / dt;
    let floor = ground.map_or(f64::NEG_INFINITY, |g| g.height);
    for i in 0..n {
        if s.inv_mass[i] != 0.0 {
            sc.x[i].y = sc.x[i].y.max(floor);
            s.v[i] = (sc.x[i] - s.x[i]) * inv_h;
        }
    }
}

/// Each free particle's end x0 + h v put back out of the surfaces along their normals, where
/// the friction after the last Newton step moved it in: the ground's and the surfaces' rub
/// change a whole body's velocity along its surface alike, which for a member against a second
/// surface points into it (a soft box thrown at a wall at 1/60 s, on the ground as it bounced
/// back, ended 0.3 mm inside the wall; the `slope`'s box wedged at its foot 2 mm into the slope
/// every step). The pass after the step answers velocities alone.
fn hold_out_after_rubbing(s: &mut State, c: &InSolve, ground: Option<Ground>, dt: f64) {
    let floor = ground.map_or(f64::NEG_INFINITY, |g| g.height);
    for i in 0..s.x.len() {
        if s.inv_mass[i] != 0.0 {
            let mut end = s.x[i] + s.v[i] * dt;
            if c.push_out(i, &mut end, s.x[i]) || end.y < floor {
                end.y = end.y.max(floor);
                s.v[i] = (end - s.x[i]) / dt;
            }
        }
    }
}

/// Coulomb friction on the obstacles' surfaces, body by body, after the step's last Newton step
/// ([`crate::solver::contact::slide::Slides::rub`]): each group of particles joined by springs
/// that one still surface holds has its velocity along the surface slowed as a whole, within
/// Coulomb's cone at the contact forces the solves learned ([`Support::on_obstacle`]). Groups
/// the ground holds are its own friction's ([`ground`]'s `rub`); those on a moving surface, an
/// engine's body, or surfaces of two directions are left to the projections' friction.
///
/// Why: the projection takes back a particle's sliding by at most μ times its own push in that
/// projection, and once the solves carry the body's weight, the last projection pushes little.
/// The `slope` scene's gentle box (20°, tan 20° = 0.36 under μ = 0.5) crept down its slope at a
/// steady 2.6 cm/s at 1/60 s and 7.3 cm/s at 1/30 s (`docs/performance-log.md`, 2026-12-07).
///
/// [`Support::on_obstacle`]: crate::solver::contact::support::Support::on_obstacle
fn rub_surfaces(s: &mut State, sc: &mut Scratch, c: &InSolve, dt: f64) {
    let friction = c.friction();
    if friction == 0.0 || c.obstacles().is_empty() || !sc.support.acted() {
        return;
    }
    sc.groups.ready(s);
    let Scratch {
        groups,
        support,
        cg,
        ..
    } = sc;
    let feels = |o: usize| c.reactions().is_some_and(|r| r.feels(o));
    let mut any = false;
    for (i, contact) in groups.contacts.iter_mut().enumerate() {
        *contact = if cg.filter.get(i) == Some(&cg::HELD) {
            LEFT_ALONE
        } else {
            match support.on_obstacle(i, s.mass[i]) {
                None => NO_CONTACT,
                Some((o, _, _)) if c.obstacles()[o].moves() || feels(o) => LEFT_ALONE,
                Some((_, normal, force)) => Contact {
                    normal,
                    force: force.dot(normal).max(0.0),
                    along: force.dot(normal.perp()),
                    shift: DVec2::ZERO,
                },
            }
        };
        any |= *contact != NO_CONTACT;
    }
    if any {
        groups.rub(&groups.contacts, (&mut s.v, &s.mass), friction, dt);
    }
}

/// The Newton matrix's answer to the last projection's change δf of the contact forces,
/// (M − h² K)⁻¹ h² δf, into `sc.answer`: how the end positions would move under it, for the
/// line search ([`crate::solver::contact::support::Support::line_search`]). One more solve, in
/// the last solve's rows (the ground's held rows kept); its Δv is kept aside and put back.
/// Returns whether there was a change.
fn answer_change(
    s: &State,
    sc: &mut Scratch,
    h2: f64,
    settings: CgSettings,
    threads: &Threads,
) -> bool {
    let n = s.x.len();
    sc.cg.z.resize(n, DVec2::ZERO);
    if !sc.support.change_to_answer(h2, &mut sc.cg.z) {
        return false;
    }
    let mut norm2 = 0.0;
    for ((z, &w), &f) in sc.cg.z.iter_mut().zip(&s.inv_mass).zip(&sc.cg.filter) {
        if w == 0.0 {
            *z = DVec2::ZERO;
        }
        *z *= f;
        norm2 += z.length_squared();
    }
    sc.kept_dv.clone_from(&sc.cg.dv);
    sc.cg.dv.iter_mut().for_each(|d| *d = DVec2::ZERO);
    cg::solve(s, sc, h2, norm2, settings, threads);
    sc.answer.clone_from(&sc.cg.dv);
    std::mem::swap(&mut sc.cg.dv, &mut sc.kept_dv);
    true
}
