//! What the particles' contacts give back to the obstacles: the equal and opposite impulse of
//! every particle–obstacle contact, so that an obstacle standing for a body of another engine
//! (a dynamic rigid body) can be pushed by the particles.
//!
//! Why a log of impulses and not forces: each method changes a particle's momentum by contact
//! in its own place. The contact pass and the velocity pass after a solve change its velocity
//! by Δv (an impulse m Δv); XPBD pushes its positions inside a substep of length hₛ, and the
//! push δx becomes the velocity δx/hₛ (an impulse m δx/hₛ). Each place notes the impulse it
//! gave, at the point of the surface it touched; the obstacle takes minus their sum. Springs
//! are internal and pass momentum only between particles, so the particles and the obstacles
//! together keep theirs.
//!
//! Why sorted before summing: the passes run on several threads, which note in no fixed order.
//! The impulses are summed in an order of their own values, so that the same step gives the
//! same bits however the threads ran.
//!
//! Why a body's mass enters at the end of the step: within a step the obstacle stands where its
//! engine put it, as heavy as a wall, so each place above gives the particle the whole change
//! a wall would: a 1 kg particle hitting a 1 kg box stopped dead and sent the box off at its
//! speed. At the step's end ([`Reactions::close_step`]) each particle's impulse from a body of
//! inverse mass W (along the impulse, 1/M + (r × d)²/I) is scaled to what a free pair would
//! exchange for the same change of their relative velocity, w/(w + W) of it (w the particle's
//! inverse mass), and the particle keeps that share of its velocity change. A body touched by
//! k particles in the step is shared among them (mass splitting, Tonge et al. 2012, "Mass
//! splitting for jitter-free parallel rigid body simulation"): each sees k W, so that k
//! particles landing together on a light body do not each push it as if alone (which sent it
//! off faster than they came, with more energy than they brought).

use glam::DVec2;
use std::sync::Mutex;

/// What one obstacle took from the particles over the steps since it was last read.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Reaction {
    /// The sum of the impulses on the obstacle, N·s.
    pub impulse: DVec2,
    /// Their moment about the world's origin, Σ p × J, N·m·s: about a point c the moment is
    /// `moment - c.perp_dot(impulse)`.
    pub moment: f64,
    /// How many contacts gave them.
    pub contacts: u32,
}

impl Reaction {
    /// The angular impulse about the point `c`, N·m·s.
    pub fn moment_about(&self, c: DVec2) -> f64 {
        self.moment - c.perp_dot(self.impulse)
    }
}

/// How a body behind an obstacle answers an impulse: its inverse mass and inverse moment of
/// inertia, and its centre of mass. The default, all zero, is a body as heavy as a wall (a
/// static or kinematic one), which the particles' contacts do not move.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Inertia {
    /// 1/M, 1/kg.
    pub inverse_mass: f64,
    /// 1/I about the centre of mass, 1/(kg·m²).
    pub inverse_inertia: f64,
    /// The centre of mass, world, m.
    pub center_of_mass: DVec2,
    /// Which body: the obstacles of one body (a body of several colliders) share it, so that a
    /// solve that moves the body moves them together (VBD: `solver::contact::solved`).
    pub body: u64,
    /// How its engine moves it over a step: in `substeps` substeps (0 counts as 1), each
    /// damping its velocity by 1/(1 + c hₛ) with c [`Self::linear_damping`] and its angular
    /// velocity with c [`Self::angular_damping`].
    pub substeps: u32,
    /// The damping of its velocity, 1/s (avian's `LinearDamping`; 0: undamped).
    pub linear_damping: f64,
    /// The damping of its angular velocity, 1/s (avian's `AngularDamping`; 0: undamped).
    pub angular_damping: f64,
}

impl Inertia {
    /// The inverse mass the body shows to an impulse along the unit `d` at the point `p`:
    /// 1/M + ((p − c) × d)²/I.
    pub fn along(&self, p: DVec2, d: DVec2) -> f64 {
        let arm = (p - self.center_of_mass).perp_dot(d);
        self.inverse_mass + arm * arm * self.inverse_inertia
    }

    /// The share of a change of velocity at a step's start that the engine carries into the
    /// body's move over a step of `dt`, (linear, angular): 1 undamped ([`mean_decay`]).
    pub fn kept(&self, dt: f64) -> (f64, f64) {
        let n = self.substeps.max(1);
        (
            mean_decay(self.linear_damping, n, dt),
            mean_decay(self.angular_damping, n, dt),
        )
    }

    fn is_wall(&self) -> bool {
        self.inverse_mass == 0.0 && self.inverse_inertia == 0.0
    }
}

/// The mean over a step of `dt` in `substeps` substeps of the decay of a velocity that each
/// substep damps by r = 1/(1 + c hₛ) before moving by it: (1/n) Σₖ₌₁ⁿ rᵏ (1 for c = 0).
pub fn mean_decay(damping: f64, substeps: u32, dt: f64) -> f64 {
    let n = substeps.max(1);
    let r = 1.0 / (1.0 + damping * dt / n as f64);
    (1..=n).map(|k| r.powi(k as i32)).sum::<f64>() / n as f64
}

/// The mean velocity over a step of `dt` in `substeps` substeps that a constant acceleration of
/// 1 gives a body starting at rest, each substep damping by r = 1/(1 + c hₛ) and then adding
/// hₛ: hₛ (1/n) Σₖ₌₁ⁿ Σⱼ₌₀ᵏ⁻¹ rʲ (dt (n + 1)/(2n) for c = 0).
pub fn mean_gain(damping: f64, substeps: u32, dt: f64) -> f64 {
    let n = substeps.max(1);
    let hs = dt / n as f64;
    let r = 1.0 / (1.0 + damping * hs);
    let (mut v, mut sum) = (0.0, 0.0);
    for _ in 0..n {
        v = v * r + hs;
        sum += v;
    }
    sum / n as f64
}

/// One contact's impulse on its obstacle.
#[derive(Debug, Clone, Copy)]
struct Note {
    obstacle: u32,
    particle: u32,
    point: DVec2,
    impulse: DVec2,
    /// The particle's speed toward the surface before the contact, m/s (0: it was not coming
    /// in, as a particle resting on the body is not).
    approach: f64,
}

impl Note {
    /// A total order of the notes by their values.
    fn key(&self) -> (u32, u32, u64, u64, u64, u64) {
        (
            self.obstacle,
            self.particle,
            self.point.x.to_bits(),
            self.point.y.to_bits(),
            self.impulse.x.to_bits(),
            self.impulse.y.to_bits(),
        )
        // (The approach is the particle's, the same in each of its notes of one contact.)
    }
}

/// The log of one step's contact impulses, and the reactions summed from it.
#[derive(Debug, Default)]
pub struct Reactions {
    notes: Mutex<Vec<Note>>,
    /// Impulses a solve gave its bodies whole (obstacle, impulse, moment about the origin),
    /// which no share cuts: the solve moved the body with the particles ([`super::solved`]).
    given: Mutex<Vec<(u32, DVec2, f64)>>,
    summed: Vec<Reaction>,
    /// Each obstacle's body, by the obstacle's index (none past the end: walls).
    inertia: Vec<Inertia>,
}

impl Reactions {
    /// Notes that a contact of particle `particle` with obstacle `obstacle` at the surface
    /// point `point` changed the particle's momentum by `on_particle`: the obstacle takes
    /// minus that.
    ///
    /// `approach` is the particle's speed toward the surface before the contact (m/s, ≥ 0):
    /// the part of the impulse that stopped it is an impact's, which the body's mass shares
    /// ([`Self::close_step`]); the rest held it against its other forces. A wall's contacts (an
    /// obstacle without a body that moves) are not noted: nothing reads them.
    pub(crate) fn note(
        &self,
        obstacle: usize,
        particle: usize,
        point: DVec2,
        on_particle: DVec2,
        approach: f64,
    ) {
        if on_particle == DVec2::ZERO || !self.feels(obstacle) {
            return;
        }
        let note = Note {
            obstacle: obstacle as u32,
            particle: particle as u32,
            point,
            impulse: -on_particle,
            approach: approach.max(0.0),
        };
        // A poisoned lock only means another thread panicked mid-push; the log is still a
        // list of whole notes.
        let mut notes = self.notes.lock().unwrap_or_else(|e| e.into_inner());
        notes.push(note);
    }

    /// Gives obstacle `obstacle`'s body the impulse `impulse` (N·s, at its centre of mass
    /// `center`) and the angular impulse `angular` (N·m·s about it), whole: what a solve that
    /// moved the body among its unknowns found the particles gave it ([`super::solved`]).
    pub(crate) fn give(&self, obstacle: usize, center: DVec2, impulse: DVec2, angular: f64) {
        let mut given = self.given.lock().unwrap_or_else(|e| e.into_inner());
        given.push((obstacle as u32, impulse, center.perp_dot(impulse) + angular));
    }

    /// The body behind obstacle `obstacle`, if it is one that moves (not a wall).
    pub(crate) fn body(&self, obstacle: usize) -> Option<Inertia> {
        self.inertia.get(obstacle).copied().filter(|b| !b.is_wall())
    }

    /// Forgets the bodies: every obstacle is a wall until [`Self::set_inertia`] says otherwise.
    pub fn clear_inertia(&mut self) {
        self.inertia.clear();
    }

    /// Whether obstacle `obstacle` stands for a body that the particles' contacts move (one
    /// that is not a wall).
    pub fn feels(&self, obstacle: usize) -> bool {
        self.inertia.get(obstacle).is_some_and(|b| !b.is_wall())
    }

    /// The body behind obstacle `obstacle`.
    pub fn set_inertia(&mut self, obstacle: usize, inertia: Inertia) {
        if self.inertia.len() <= obstacle {
            self.inertia.resize(obstacle + 1, Inertia::default());
        }
        self.inertia[obstacle] = inertia;
    }

    /// Ends a step: each particle's impulse from a body that moves is cut to its share (the
    /// module's doc), with the particle's velocity in `v` (inverse masses `w`) given back the
    /// rest; then the notes are summed into the reactions of `obstacles` obstacles, in an
    /// order of their values (the same bits whatever order the threads noted in), and the log
    /// is cleared.
    pub fn close_step(&mut self, obstacles: usize, v: &mut [DVec2], w: &[f64]) {
        if self.summed.len() != obstacles {
            self.summed.resize(obstacles, Reaction::default());
        }
        let given = self.given.get_mut().unwrap_or_else(|e| e.into_inner());
        given.sort_unstable_by_key(|(o, j, m)| (*o, j.x.to_bits(), j.y.to_bits(), m.to_bits()));
        for (o, impulse, moment) in given.drain(..) {
            if let Some(r) = self.summed.get_mut(o as usize) {
                r.impulse += impulse;
                r.moment += moment;
                r.contacts += 1;
            }
        }
        let notes = self.notes.get_mut().unwrap_or_else(|e| e.into_inner());
        if notes.is_empty() {
            return;
        }
        notes.sort_unstable_by_key(Note::key);
        // Runs of one obstacle, and within them runs of one particle.
        for run in runs(notes, |n| n.obstacle) {
            let o = notes[run.start].obstacle as usize;
            let body = self.inertia.get(o).copied().unwrap_or_default();
            if !body.is_wall() {
                share(&mut notes[run], body, v, w);
            }
        }
        for n in notes.drain(..) {
            if let Some(r) = self.summed.get_mut(n.obstacle as usize) {
                r.impulse += n.impulse;
                r.moment += n.point.perp_dot(n.impulse);
                r.contacts += 1;
            }
        }
    }

    /// The reactions summed since the last [`Self::take`], one per obstacle.
    pub fn summed(&self) -> &[Reaction] {
        &self.summed
    }

    /// Returns the reactions summed so far and starts again from none.
    pub fn take(&mut self) -> Vec<Reaction> {
        let n = self.summed.len();
        std::mem::replace(&mut self.summed, vec![Reaction::default(); n])
    }
}

/// The runs of `notes` (sorted by `key` first) that share a key, in order.
fn runs<K: PartialEq>(notes: &[Note], key: impl Fn(&Note) -> K) -> Vec<std::ops::Range<usize>> {
    let mut all = vec![];
    let mut start = 0;
    while let Some(first) = notes.get(start) {
        let k = key(first);
        let end = start + notes[start..].partition_point(|n| key(n) == k);
        all.push(start..end);
        start = end;
    }
    all
}

/// One moving body's notes of a step (sorted, so each particle's are together). A particle's
/// impulse P from a wall is an impact's up to m a (a its speed toward the surface before the
/// contact) and support beyond that. The impact's part I is cut to I w/(w + k W), with k the
/// particles touching the body and W its inverse mass along P at the mean point of the
/// particle's contacts, and the particle's velocity gets back w times the part cut, but never
/// more than the body's change of velocity there under the impacts (so that no particle ends
/// the step moving into the body); the notes keep what the particle kept, so that the body
/// takes exactly what the particles gave.
///
/// For one impact, or k alike, the cut is exact and the bound idle: a particle of mass m at u
/// meeting a free body of mass M leaves with it at m u/(m + M) (inelastic), and the body with
/// it. Support is not cut: a particle held against a body by its springs or its weight comes
/// in at no speed, and the body takes the whole push. Cut too, as a net's particles under a
/// resting crate were, it gave them back velocity into the crate every step, and the crates
/// bounced in the net for good (5 cm after 10 s, against 1 cm uncut).
fn share(notes: &mut [Note], body: Inertia, v: &mut [DVec2], w: &[f64]) {
    /// One particle's run of notes and what it gives.
    struct Run {
        notes: std::ops::Range<usize>,
        particle: usize,
        on_particle: DVec2,
        point: DVec2,
        /// The part of the impulse cut, N·s (along −P).
        cut: f64,
    }
    let mut runs: Vec<Run> = runs(notes, |n| n.particle)
        .into_iter()
        .map(|range| {
            let group = &notes[range.clone()];
            Run {
                particle: group[0].particle as usize,
                on_particle: -group.iter().map(|n| n.impulse).sum::<DVec2>(),
                point: group.iter().map(|n| n.point).sum::<DVec2>() / group.len() as f64,
                notes: range,
                cut: 0.0,
            }
        })
        .collect();
    let k = runs.len() as f64;
    // The cuts, and the body's change of motion under what the particles give it.
    let (mut impulse, mut moment) = (DVec2::ZERO, 0.0);
    for run in &mut runs {
        let wi = w.get(run.particle).copied().unwrap_or(0.0);
        let mut impact = 0.0;
        if let Some(d) = run.on_particle.try_normalize()
            && wi > 0.0
        {
            let approach = notes[run.notes.clone()]
                .iter()
                .map(|n| n.approach)
                .fold(0.0, f64::max);
            impact = run.on_particle.length().min(approach / wi);
            let body_w = k * body.along(run.point, d);
            run.cut = impact * body_w / (wi + body_w);
        }
        // What the body takes of the impact: its change of motion bounds what the particles
        // get back (support is left out of it: counted in, it sent the net's particles back
        // into a landing crate faster than the crate's landing alone, and the crate bounced
        // off the net).
        let given = -run.on_particle.normalize_or_zero() * (impact - run.cut);
        impulse += given;
        moment += (run.point - body.center_of_mass).perp_dot(given);
    }
    let (dv, dw) = (impulse * body.inverse_mass, moment * body.inverse_inertia);
    for run in runs {
        let (Some(&wi), Some(vi)) = (w.get(run.particle), v.get_mut(run.particle)) else {
            continue;
        };
        let Some(d) = run.on_particle.try_normalize() else {
            continue;
        };
        if wi <= 0.0 || run.cut <= 0.0 {
            continue;
        }
        // Back toward the body, by the part cut, at most as fast as the body moves away.
        let body_moves = dv + dw * (run.point - body.center_of_mass).perp();
        let back = (run.cut * wi).min((-body_moves.dot(d)).max(0.0));
        *vi -= d * back;
        let kept = 1.0 - back / (run.on_particle.length() * wi);
        for n in &mut notes[run.notes] {
            n.impulse *= kept;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean decay and gain are a damped body's mean velocity over a step as avian's
    /// substeps move it (each damps by 1/(1 + c hₛ), adds the acceleration's hₛ, then moves by
    /// the velocity): from 1 m/s without acceleration, and from rest under 1 m/s²; undamped,
    /// 1 and dt (n + 1)/(2n).
    #[test]
    fn the_mean_decay_and_gain_are_the_substeps_mean_velocity() {
        let dt = 1.0 / 30.0;
        for (damping, n) in [(0.0, 6), (2.0, 6), (5.0, 1), (0.7, 12)] {
            let hs = dt / n as f64;
            let mean = |mut v: f64, a: f64| {
                let mut x = 0.0;
                for _ in 0..n {
                    v = v / (1.0 + damping * hs) + a * hs;
                    x += v * hs;
                }
                x / dt
            };
            assert!((mean_decay(damping, n, dt) - mean(1.0, 0.0)).abs() < 1e-15);
            assert!((mean_gain(damping, n, dt) - mean(0.0, 1.0)).abs() < 1e-15);
        }
        assert_eq!(mean_decay(0.0, 6, dt), 1.0);
        assert!((mean_gain(0.0, 6, dt) - dt * 7.0 / 12.0).abs() < 1e-15);
    }

    /// The sum is the same bits whatever order the notes came in, and the moment about a point
    /// is the moment of the impulses about it.
    #[test]
    fn the_sum_does_not_depend_on_the_order_of_the_notes() {
        let notes: Vec<(usize, DVec2, DVec2)> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.37;
                (
                    i % 2,
                    DVec2::new(t.sin(), t.cos() * 3.0),
                    DVec2::new(1e-3 * t.cos(), 0.1 + t),
                )
            })
            .collect();
        let body = Inertia {
            inverse_mass: 1.0,
            ..Inertia::default()
        };
        let mut forward = Reactions::default();
        forward.set_inertia(0, body);
        forward.set_inertia(1, body);
        for &(o, p, j) in &notes {
            forward.note(o, 0, p, j, 0.0);
        }
        forward.close_step(2, &mut [], &[]);
        let mut backward = Reactions::default();
        backward.set_inertia(0, body);
        backward.set_inertia(1, body);
        for &(o, p, j) in notes.iter().rev() {
            backward.note(o, 0, p, j, 0.0);
        }
        backward.close_step(2, &mut [], &[]);
        assert_eq!(forward.summed(), backward.summed());
        let c = DVec2::new(0.3, -0.2);
        let direct: f64 = notes
            .iter()
            .filter(|n| n.0 == 1)
            .map(|&(_, p, j)| (p - c).perp_dot(-j))
            .sum();
        let r = forward.summed()[1];
        assert!((r.moment_about(c) - direct).abs() < 1e-12 * direct.abs().max(1.0));
        assert_eq!(r.contacts, 25);
    }
}
