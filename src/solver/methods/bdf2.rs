//! BDF2, the second-order backward differentiation formula, solved by projective dynamics'
//! local/global iterations (the integrator `bdf2`).
//!
//! A step from (x₀, v₀), with the previous step's start (x₋₁, v₋₁), solves
//!
//! x₁ = (4x₀ − x₋₁)/3 + (2h/3) v₁,  v₁ = (4v₀ − v₋₁)/3 + (2h/3) M⁻¹ (f(x₁) − μ M v₁),
//!
//! which is backward Euler's variational problem with step ĥ = 2h/3 about x̂ = (4x₀ − x₋₁)/3
//! and v̂ = (4v₀ − v₋₁)/3 ([`super::projective::Target`]): the same local/global iterations
//! minimise it, and its matrix s M + ĥ² L is constant while the springs, masses, pins, dt and
//! μ are, so its factor is kept from step to step exactly as projective dynamics keeps its
//! own. The air drag μ is the force −μ M v inside the solve, not the factor exp(−μh) after it:
//! at 1/60 s, μh = 0.17, and that splitting alone is a first-order error.
//!
//! The first step, and the first after the history stops being the motion's (a position or
//! velocity set from outside — a drag, an undo, a paste —, a new dt, a repacking), is a
//! backward Euler step (ĥ = h, x̂ = x₀, v̂ = v₀), with its own factor, so that the BDF2 factor
//! survives the restart. A cut, a tear or a pin changes the forces, not the history: the
//! next step is a BDF2 step, on a refactored matrix.
//!
//! A particle moved after the solve (a contact or the ground stopped it, a bounce reversed it)
//! has its history shifted by the jumps Δx, Δv since the solve, as if they had happened just
//! before the step: x₋₁ + Δx − h Δv, v₋₁ + Δv (the previous step's acceleration kept). Without
//! that, the extrapolation (4v₀ − v₋₁)/3 across a bounce adds a third of the velocity jump: a
//! ball with restitution 0.6 bounced back higher than it was dropped.
//!
//! **Where contact acts, a backward Euler step.** A BDF2 step whose solve the contact acted in
//! (a projection pushed a particle) is solved again as a backward Euler step, and so is the step
//! after one the contact acted in: BDF2 is first order while anything touches, and second
//! order in free motion. Its backward Euler steps size their contact forces by projective
//! dynamics' line search (`contact::support`), and the contact pass after them spreads the
//! stopping of the touching particles through their bodies
//! ([`super::projective::Projective::spread`]). Why: with its own steps at a frame's step, a
//! strip of cloth two particles deep dropped flat landed with 43 of its 47 cells turned over
//! and its energy at 42 J from 3.9 J (all 47 and 291 J at 1/30 s), the `paddle` at 1/30 s rose
//! from 10.4 J to 180 J, and with the line search on its own steps resting bodies rocked with a
//! period of two steps: its extrapolation (4v₀ − v₋₁)/3 carries what alternates from step to
//! step 5/3 times over into the next (two stacked soft boxes still moved at 0.23 m/s after 6 s
//! at 1/60 s). The price is the order where bodies touch, and at the step where contact begins
//! a second solve (`docs/performance-log.md`, 2026-12-07).
//!
//! The step leaves v₁ in v and the drift (x₁ − x₀)/h that the position update moves with.
//! The ground clamps the end positions inside the step (as XPBD's substeps do): a free
//! particle whose x₁ is on or under it is put on it and loses its vertical velocity.

use super::projective::{Projective, Target};
use crate::solver::contact::inside::InSolve;
use crate::solver::state::State;
use crate::solver::threads::Threads;
use glam::DVec2;

/// The factors, the history and the counters, kept from step to step.
#[derive(Debug, Default)]
pub struct Bdf2 {
    /// The factor of the BDF2 steps, s M + (2h/3)² L.
    pub(crate) main: Projective,
    /// The factor of the backward Euler steps that start the history, s M + h² L.
    pub(crate) startup: Projective,
    /// The start of the last step, and what it was taken under.
    history: Option<History>,
    xhat: Vec<DVec2>,
    vhat: Vec<DVec2>,
    /// Steps so far, and of them the backward Euler ones.
    pub steps: u64,
    pub startup_steps: u64,
    /// BDF2 steps solved again as backward Euler steps, since the contact acted in them.
    pub retaken_steps: u64,
    /// Whether the last step was a backward Euler step.
    backward_euler: bool,
}

#[derive(Debug)]
struct History {
    x: Vec<DVec2>,
    v: Vec<DVec2>,
    /// The end position and velocity the step's solve found (before the ground clamp): what
    /// differs from them at the next step's start was changed by a contact, the ground or a
    /// bounce, and shifts that particle's history.
    end_x: Vec<DVec2>,
    end_v: Vec<DVec2>,
    /// [`State::edits`] and dt's bits when it was taken.
    edits: u64,
    dt: u64,
    /// Whether the contact acted in the step's solve: the next step is then a backward Euler
    /// step too.
    contact_acted: bool,
}

impl Bdf2 {
    /// For a repacked state: the factors and counters carry on, the history does not (the
    /// particles' indices changed).
    pub(crate) fn repacked(mut self) -> Bdf2 {
        self.history = None;
        self
    }

    /// The last step's solve when it was a backward Euler step, which ends with its mean
    /// velocity over the step, (x₁ − x₀)/h: its factor spreads a landing body's stop
    /// ([`Projective::spread`]).
    pub(crate) fn backward_euler_solve(&mut self) -> Option<&mut Projective> {
        self.backward_euler.then_some(&mut self.startup)
    }

    /// Mean local/global iterations per step so far, both factors' steps together.
    pub fn iterations_per_step(&self) -> Option<f64> {
        let (pd, be) = (&self.main, &self.startup);
        let steps = pd.steps + be.steps;
        (steps > 0).then(|| (pd.iterations + be.iterations) as f64 / steps as f64)
    }
}

/// One BDF2 step of `iterations` local/global iterations (see the module docs). `s.f` holds
/// the body forces; `drag` is the air damping μ, 1/s.
#[allow(clippy::too_many_arguments)]
pub fn step(
    s: &mut State,
    b: &mut Bdf2,
    dt: f64,
    drag: f64,
    iterations: u32,
    ground: Option<f64>,
    contact: Option<&InSolve>,
    threads: &Threads,
) -> Result<(), String> {
    let n = s.x.len();
    let springs = s.springs.len();
    s.drift_buffer();
    let usable = b.history.as_ref().is_some_and(|h| {
        h.edits == s.edits && h.dt == dt.to_bits() && h.x.len() == n && !h.contact_acted
    });
    // A BDF2 step whose solve the contact acted in is taken again as a backward Euler step
    // (see the module docs).
    let bdf2 = usable && {
        let h = b.history.as_ref().expect("checked above");
        b.xhat.resize(n, DVec2::ZERO);
        b.vhat.resize(n, DVec2::ZERO);
        let data = (
            (&mut b.xhat[..], &mut b.vhat[..]),
            (&s.x[..], &s.v[..]),
            (&h.x[..], &h.v[..], (&h.end_x[..], &h.end_v[..])),
            &s.inv_mass[..],
        );
        threads.each(
            springs,
            data,
            |((xh, vh), (x, v), (xp, vp, (ex, ev)), w)| {
                for i in 0..xh.len() {
                    if w[i] != 0.0 {
                        // The jumps since the solve (0 unless a contact, the ground or a bounce
                        // moved the particle), applied to the history as if they had happened
                        // just before this step: x₋₁ + Δx − h Δv, v₋₁ + Δv.
                        let (dx, dv) = (x[i] - ex[i], v[i] - ev[i]);
                        let (xp, vp) = (xp[i] + dx - dv * dt, vp[i] + dv);
                        xh[i] = (x[i] * 4.0 - xp) * (1.0 / 3.0);
                        vh[i] = (v[i] * 4.0 - vp) * (1.0 / 3.0);
                    } else {
                        // A pinned or held particle moves as it is moved: x₀ + h v₀.
                        (xh[i], vh[i]) = (x[i], v[i]);
                    }
                }
            },
        );
        let target = Target {
            h: dt * (2.0 / 3.0),
            drag,
            base: &b.xhat,
            velocity: &b.vhat,
        };
        // Its impulses on the obstacles that stand for bodies are noted by the step taken in
        // its place where the contact acts, and there are none where it does not.
        let quiet = contact.map(InSolve::without_notes);
        (b.main).solve(s, &target, dt, iterations, quiet.as_ref(), threads)?;
        let acted = b.main.contact_acted();
        b.retaken_steps += u64::from(acted);
        !acted
    };
    b.backward_euler = !bdf2;
    let solved = if bdf2 {
        (&b.main, dt * (2.0 / 3.0), &b.xhat[..])
    } else {
        let target = Target {
            h: dt,
            drag,
            base: &s.x,
            velocity: &s.v,
        };
        // Its contact forces sized by the line search, as projective dynamics' are.
        b.startup.line_search = true;
        b.startup
            .solve(s, &target, dt, iterations, contact, threads)?;
        b.startup_steps += 1;
        if contact.is_some() {
            // The velocity each particle came with, for the contact held ones below.
            b.vhat.clear();
            b.vhat.extend_from_slice(&s.v);
        }
        (&b.startup, dt, &s.x[..])
    };
    let (pd, h, base) = solved;
    // The history for the next step: this step's start.
    let history = b.history.get_or_insert_with(|| History {
        x: vec![],
        v: vec![],
        end_x: vec![],
        end_v: vec![],
        edits: 0,
        dt: 0,
        contact_acted: false,
    });
    // v₁ = (x₁ − x̂)/ĥ, and the drift (x₁ − x₀)/h, with the ground on x₁.
    let (inv_hat, inv_h) = (1.0 / h, 1.0 / dt);
    let floor = ground.unwrap_or(f64::NEG_INFINITY);
    history.x.clear();
    history.x.extend_from_slice(&s.x);
    history.v.clear();
    history.v.extend_from_slice(&s.v);
    history.end_x.resize(n, DVec2::ZERO);
    history.end_v.resize(n, DVec2::ZERO);
    let data = (
        (&mut s.v[..], &mut s.drift[..]),
        (&mut history.end_x[..], &mut history.end_v[..]),
        (pd.end(), base, &s.x[..]),
        &s.inv_mass[..],
    );
    threads.each(springs, data, |((v, u), (ex, ev), (z, xh, x), w)| {
        for i in 0..v.len() {
            if w[i] == 0.0 {
                u[i] = v[i];
                continue;
            }
            let mut end = z[i];
            v[i] = (end - xh[i]) * inv_hat;
            (ex[i], ev[i]) = (end, v[i]);
            // On the ground too: the solve holds a landing particle on it (`InSolve`), where
            // BDF2's own velocity, from its history, points up at half the landing speed.
            if end.y <= floor {
                end.y = floor;
                v[i].y = 0.0;
            }
            u[i] = (end - x[i]) * inv_h;
        }
    });
    if contact.is_some() {
        // A particle that contact held inside the solve records, along the contact's normal,
        // the velocity it came with (v̂) as its end velocity: the velocity pass after the step
        // then sets what contact leaves it there, and the history takes the difference as a
        // jump (BDF2's own velocity at a landing, from its history, points up at half the
        // landing speed).
        let (ev, came) = (&mut history.end_v, &b.vhat);
        for i in 0..n {
            if let Some(normal) = pd.held_along(i) {
                let own = ev[i];
                ev[i] = own + normal * (came[i] - own).dot(normal);
            }
        }
    }
    history.edits = s.edits;
    history.dt = dt.to_bits();
    history.contact_acted = pd.contact_acted();
    b.steps += 1;
    Ok(())
}
