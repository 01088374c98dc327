//! A body sliding on a surface as a whole, between vertex block descent's sweeps: each group
//! of particles joined by springs that rests on one still surface takes a step of its
//! translation along that surface, with Coulomb's friction at the normal force that stops the
//! group's way into it.
//!
//! Why: block descent (`methods::vbd`) moves each vertex with its neighbours held, so a body
//! stiff on the step's scale moves as a whole by about m/(m + h²Σk) of the remaining way a
//! sweep (1/556 for a strip of 20 g particles at k = 1e4 and 1/30 s). Friction reached such a
//! body only through the particles touching the surface, each held back by μ times its own
//! push, and the body did not follow within a step's sweeps: the `slope` scene's box on its 35°
//! slope (tan 35° = 0.70 > μ = 0.5) stood still at 1/120 s and larger, and a box resting on
//! the ground and sliding at 2 m/s slid 3 cm at 1/60 s where Coulomb stops it in 0.41 m, and 4
//! cm without friction, where it slides on (`docs/performance-log.md`, 2026-12-07).
//!
//! How: the group's translation δ along the surface's tangent t is one more block of the same
//! objective, G plus friction's dissipation μ Λ |u_t| (u the sliding from the step's start, Λ
//! the normal force, lagged). Along a uniform translation the springs, dashpots and gas forces
//! within the group cancel, so the block is
//!
//! ½ (s/h²) M (δ − δ*)² + μ Λ |ū + δ|,  δ* = Σ m (y − x)·t / M,
//!
//! with ū the contacts' sliding along t relative to the surface, weighted by the normal forces
//! the sweep met there. Its minimiser holds the group still where |ū + δ*| ≤ b = μ Λ h²/(s M),
//! and takes b off its way otherwise. Λ is the larger of two: what stops the group's own way into
//! the surface (b = μ d, d the group's mean way from the step's start toward y into the surface
//! as the surface moves, past the gap its contacts started at: g h² for a body at rest on the
//! ground, Λ its weight), and the normal forces the sweep met at its contacts (they carry the
//! load of the bodies stacked on it). The vertices' own steps still hold each contact with μ times its push, so a body at
//! rest stays put to the last particle. A group with a pinned particle, or touching a body
//! another engine moves, or surfaces of more than one direction (a box in a corner, a cloth over
//! a ball) takes no such step. On a surface that moves (a kinematic obstacle's), the sliding and
//! the way in are the group's relative to the surface: left to the vertices' friction, the
//! `paddle`'s strip rode its turning paddle up to 0.67 m at 1/30 s, where it slides off onto the
//! ground by 2 s under symplectic Euler (`docs/performance-log.md`, 2026-12-08).
//!
//! The groups serve implicit Euler too, whose friction after the solve slows each of them as a
//! whole: on the ground (`methods::implicit_euler`'s `rub`) and on an obstacle ([`Slides::rub`]).

use super::groups::bodies;
use super::inside::{Held, InSolve};
use crate::solver::state::State;
use glam::DVec2;

/// A vertex's contact in the last sweep: the surface's normal and the normal force its block
/// step met there, N ([`NO_CONTACT`] for none, [`LEFT_ALONE`] for a body another engine moves),
/// and how far the surface moved there over the step. Under implicit Euler, a particle's contact
/// at the step's end, with the force along the surface (its tangent `normal.perp()`) that the
/// projections' friction gave it already, N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Contact {
    pub normal: DVec2,
    pub force: f64,
    pub along: f64,
    /// How far the surface moves over the step where the contact is (0 for a still one).
    pub shift: DVec2,
}

/// No contact in the last sweep.
pub(crate) const NO_CONTACT: Contact = Contact {
    normal: DVec2::ZERO,
    force: 0.0,
    along: 0.0,
    shift: DVec2::ZERO,
};

/// A contact whose group must take no step: with a body another engine moves, or (implicit
/// Euler) with a surface that moves, or the ground that its own friction rubs.
pub(crate) const LEFT_ALONE: Contact = Contact {
    normal: DVec2::ZERO,
    force: NO_STEP,
    along: 0.0,
    shift: DVec2::ZERO,
};

/// The force of a contact whose group takes no step ([`LEFT_ALONE`]).
const NO_STEP: f64 = -1.0;

/// How far apart two contacts' normals may point and still be one surface's: cos of 0.1°.
const ONE_DIRECTION: f64 = 0.999_998_5;

impl Contact {
    /// The contact a vertex's block step met: `held` by `c`'s surfaces after its unconstrained
    /// step to `free`, put at `end`, its block's Hessian `h` (h00, h01, h11).
    #[inline]
    pub(crate) fn met(
        c: &InSolve,
        held: Option<Held>,
        free: DVec2,
        end: DVec2,
        h: [f64; 3],
    ) -> Self {
        let Some(held) = held else {
            return NO_CONTACT;
        };
        if held
            .obstacle
            .is_some_and(|o| c.reactions().is_some_and(|r| r.feels(o)))
        {
            return LEFT_ALONE;
        }
        let moving = held
            .obstacle
            .map(|o| &c.obstacles()[o])
            .filter(|o| o.moves());
        let shift = moving.map_or(DVec2::ZERO, |o| o.velocity_at(end) * c.dt());
        let push = end - free;
        let force = DVec2::new(h[0] * push.x + h[1] * push.y, h[1] * push.x + h[2] * push.y);
        Contact {
            normal: held.normal,
            force: held.normal.dot(force).max(0.0),
            along: 0.0,
            shift,
        }
    }
}

/// The groups, and each vertex's contact from the last sweep, kept from step to step.
#[derive(Debug, Default, Clone)]
pub(crate) struct Slides {
    /// The state revision the groups are for.
    revision: Option<u64>,
    /// The groups' members, by group, and each group's start in it (and the end).
    members: Vec<u32>,
    starts: Vec<usize>,
    /// Each group's mass, kg.
    mass: Vec<f64>,
    /// Each vertex's contact in the last sweep (the vertices' block steps write it).
    pub(crate) contacts: Vec<Contact>,
    /// Each particle's group ([`NO_GROUP`] for one in a group with a pinned particle).
    group_of: Vec<u32>,
}

/// The group of a particle whose group has a pinned particle: it has none here.
pub(crate) const NO_GROUP: u32 = u32::MAX;

impl Slides {
    /// Readies the groups for `s`'s springs and pins (again only after an edit of them).
    pub(crate) fn ready(&mut self, s: &State) {
        let n = s.x.len();
        if self.revision == Some(s.revision) && self.contacts.len() == n {
            return;
        }
        self.revision = Some(s.revision);
        self.contacts.clear();
        self.contacts.resize(n, NO_CONTACT);
        let body = bodies(&s.springs, n);
        // A group with a pinned particle is held by it: it takes no step.
        let mut pinned = vec![false; n];
        for i in 0..n {
            if s.inv_mass[i] == 0.0 {
                pinned[body[i] as usize] = true;
            }
        }
        let mut count = vec![0usize; n];
        for &b in &body {
            if !pinned[b as usize] {
                count[b as usize] += 1;
            }
        }
        // Each body's group, by the body's name (its smallest index).
        let mut group_of_body = vec![NO_GROUP; n];
        self.starts.clear();
        self.starts.push(0);
        for (b, &c) in count.iter().enumerate() {
            if c > 0 {
                group_of_body[b] = (self.starts.len() - 1) as u32;
                self.starts.push(self.starts.last().unwrap() + c);
            }
        }
        self.group_of.clear();
        self.group_of
            .extend(body.iter().map(|&b| group_of_body[b as usize]));
        let mut at = self.starts.clone();
        self.members.clear();
        self.members.resize(*self.starts.last().unwrap(), 0);
        self.mass.clear();
        self.mass.resize(self.starts.len() - 1, 0.0);
        for (i, &g) in self.group_of.iter().enumerate() {
            if g != NO_GROUP {
                let g = g as usize;
                self.members[at[g]] = i as u32;
                at[g] += 1;
                self.mass[g] += s.mass[i];
            }
        }
    }

    /// The groups: each one's members and mass, kg.
    pub(crate) fn groups(&self) -> impl Iterator<Item = (&[u32], f64)> + '_ {
        self.starts
            .windows(2)
            .zip(&self.mass)
            .map(|(w, &m)| (&self.members[w[0]..w[1]], m))
    }

    /// Particle `i`'s group, [`NO_GROUP`] where a pinned particle holds it.
    pub(crate) fn group_of(&self, i: usize) -> u32 {
        self.group_of[i]
    }

    /// Each group resting on one still surface takes its step along it (see the module's
    /// notes): `contacts` each vertex's in the last sweep ([`Self::contacts`]), `x` the
    /// iterate, `y` the inertial targets, `x0` the step's start, `inertia` s/h², `friction` μ.
    /// Returns how many groups moved.
    pub(crate) fn step(
        &self,
        contacts: &[Contact],
        x: &mut [DVec2],
        (y, x0, mass): (&[DVec2], &[DVec2], &[f64]),
        inertia: f64,
        friction: f64,
    ) -> usize {
        let mut moved = 0;
        for (g, members) in self.starts.windows(2).enumerate() {
            let members = &self.members[members[0]..members[1]];
            let Some(held) = contact_of(contacts, members, |i| x[i] - x0[i]) else {
                continue;
            };
            let (normal, sliding, force) = (held.normal, held.sliding, held.force);
            // (The sweep left each contact on the surface: its start stood this far off it.)
            let gap = held.gap;
            let t = normal.perp();
            // The inertia's pull along the surface, and the group's way into it over the step,
            // each the group's mean.
            let (mut pull, mut into) = (0.0, 0.0);
            for &i in members {
                let i = i as usize;
                pull += mass[i] * (y[i] - x[i]).dot(t);
                into -= mass[i] * (y[i] - x0[i] - held.shift).dot(normal);
            }
            let m = self.mass[g];
            // Friction's reach: μ times the normal force over the block's stiffness, that of the
            // way into the surface that the surface takes back, past the gap the contacts
            // started at (the weight of a body resting there, the impulse that stops one
            // landing), or of the sweep's own contact forces where those are more (the load of
            // the bodies stacked on it, whose pushes reach it through the pairs: the pile's boxes
            // on the ground, held by their own weight alone, were still stirring at 6 s). Not
            // the sweep's forces alone: those run far over the weight while a body's rows settle
            // (1,070 N against 7.4 N in a box's first sweep at 1/30 s, which held it still)
            // and under it while the body rocks (a box slid 19 % too far at 1/30 s).
            let way_in = (into / m - gap).max(0.0);
            let pressed = force / (inertia * m);
            let (free, budget) = (pull / m, friction * way_in.max(pressed));
            let way = sliding + free;
            let delta = if way.abs() <= budget {
                -sliding
            } else {
                free - budget * way.signum()
            };
            moved += usize::from(move_all(members, x, t * delta));
        }
        moved
    }

    /// Implicit Euler, after its step: each group held by one still surface has its velocity
    /// `v` along the surface changed, every member alike, toward stopping its contacts' sliding
    /// (their mean, weighted by their normal forces), as far as Coulomb's cone allows: the
    /// contacts' impulse along the surface, the projections' friction `along` and the change
    /// together, is at most μ times their normal impulse over the step `dt`. `contacts` hold
    /// each particle's contact at the step's end. Returns how many groups were slowed.
    pub(crate) fn rub(
        &self,
        contacts: &[Contact],
        (v, mass): (&mut [DVec2], &[f64]),
        friction: f64,
        dt: f64,
    ) -> usize {
        let mut slowed = 0;
        for (g, members) in self.starts.windows(2).enumerate() {
            let members = &self.members[members[0]..members[1]];
            let Some(held) = contact_of(contacts, members, |i| v[i]) else {
                continue;
            };
            let (m, t) = (self.mass[g], held.normal.perp());
            let (reach, given) = (friction * held.force * dt / m, held.along * dt / m);
            // The change c keeps |given + c| ≤ reach, and may always be none.
            let (least, most) = ((-reach - given).min(0.0), (reach - given).max(0.0));
            // Nor does it speed the group's own motion along the surface, or turn it back: where
            // the body turns, its contacts' sliding is not its own (the `slope`'s box settling on
            // its 20° slope rose from 7.960 J to 7.978 J at 1/30 s, where the group's mean was
            // stopped at most).
            let own = members
                .iter()
                .map(|&i| mass[i as usize] * v[i as usize].dot(t))
                .sum::<f64>()
                / m;
            let (least, most) = (least.max((-own).min(0.0)), most.min((-own).max(0.0)));
            let change = (-held.sliding).clamp(least, most);
            slowed += usize::from(move_all(members, v, t * change));
        }
        slowed
    }
}

/// Adds `by` to every member's entry of `out` (a position or a velocity); whether it moved
/// them.
fn move_all(members: &[u32], out: &mut [DVec2], by: DVec2) -> bool {
    if by == DVec2::ZERO {
        return false;
    }
    for &i in members {
        out[i as usize] += by;
    }
    true
}

/// A group's contacts with its one surface.
struct GroupContact {
    /// The surface's normal.
    normal: DVec2,
    /// The contacts' motion along the surface's tangent, weighted by their normal forces.
    sliding: f64,
    /// The least of the contacts' way out of the surface by their motion (0 for one that went
    /// in): where a sweep left them on it, the gap they started at.
    gap: f64,
    /// The normal forces summed, and the forces along the tangent.
    force: f64,
    along: f64,
    /// The surface's motion where the contacts are, weighted by their normal forces.
    shift: DVec2,
}

/// A group's contacts, `moved(i)` member `i`'s motion (a displacement, or a velocity); `None`
/// when the surface pushed none of them, or one is left alone ([`LEFT_ALONE`]), or they touch
/// surfaces of more than one direction.
fn contact_of(
    contacts: &[Contact],
    members: &[u32],
    moved: impl Fn(usize) -> DVec2,
) -> Option<GroupContact> {
    let mut normal = None;
    let (mut force, mut along, mut sliding, mut gap) = (0.0, 0.0, 0.0, f64::INFINITY);
    let mut shift = DVec2::ZERO;
    for &i in members {
        let i = i as usize;
        let c = contacts[i];
        if c == NO_CONTACT {
            continue;
        }
        if c.force == NO_STEP {
            return None;
        }
        let n = *normal.get_or_insert(c.normal);
        if n.dot(c.normal) < ONE_DIRECTION {
            return None;
        }
        let moved = moved(i) - c.shift;
        force += c.force;
        along += c.along;
        shift += c.shift * c.force;
        sliding += c.force * moved.dot(n.perp());
        gap = gap.min((-moved.dot(n)).max(0.0));
    }
    let normal = normal?;
    (force > 0.0).then(|| GroupContact {
        normal,
        sliding: sliding / force,
        gap,
        force,
        along,
        shift: shift / force,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::block;

    /// s/h² at 1/60 s.
    const INERTIA: f64 = 3600.0;

    /// A 4 × 2 block of 0.16 kg resting on the ground (its bottom row touching, pushed `push`
    /// N each), its iterate moved 3 cm to the right of its start and its inertial targets 1
    /// cm under the iterate and `pull` to the side of it. Returns the block's move along the
    /// ground in the group's step, with friction `mu`.
    fn slid(pull: f64, mu: f64, pin: bool) -> f64 {
        slid_pushed(pull, mu, pin, 1.0)
    }

    fn slid_pushed(pull: f64, mu: f64, pin: bool, push: f64) -> f64 {
        let mut s = block(4, 2, 0.0);
        if pin {
            s.inv_mass[7] = 0.0;
        }
        let x0 = s.x.clone();
        let shift = DVec2::new(0.03, 0.0);
        let mut x: Vec<DVec2> = x0.iter().map(|p| *p + shift).collect();
        let y: Vec<DVec2> = x.iter().map(|p| *p + DVec2::new(pull, -0.01)).collect();
        let mut slides = Slides::default();
        slides.ready(&s);
        for i in 0..4 {
            slides.contacts[i] = Contact {
                normal: DVec2::Y,
                force: push,
                along: 0.0,
                shift: DVec2::ZERO,
            };
        }
        let before = x[5];
        slides.step(
            &slides.contacts.clone(),
            &mut x,
            (&y, &x0, &s.mass),
            INERTIA,
            mu,
        );
        // A translation along the ground: every particle moves alike, none off its height.
        for (p, q) in x.iter().zip(&x0) {
            assert!((p.y - q.y).abs() < 1e-15);
            assert!(((p.x - q.x) - (x[5].x - x0[5].x)).abs() < 1e-15);
        }
        x[5].x - before.x
    }

    /// Coulomb at the block's own weight: the inertia pulls it 5 mm further along, friction
    /// takes back μ times its 1 cm way into the ground (the contacts' 4 N over its stiffness,
    /// 4/(3600 · 0.16) = 6.9 mm, are less). Under μ = 0.3 it goes on by 5 mm − 3 mm; under
    /// μ = 4 (friction's reach 4 cm) it stops where the step began, 3 cm back; without
    /// friction it goes the whole 5 mm; pinned, it stays. Pressed by a load from above (10 N
    /// a contact: 40/(3600 · 0.16) = 6.9 cm), friction's reach under μ = 0.3 is 2.08 cm:
    /// pulled 8 cm along, it goes 8 − 2.08 cm.
    #[test]
    fn a_group_on_the_ground_slides_as_coulomb_says() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(slid(0.005, 0.3, false), 0.002));
        assert!(close(slid(0.005, 4.0, false), -0.03));
        assert!(close(slid(0.005, 0.0, false), 0.005));
        assert!(close(slid(-0.05, 0.3, false), -0.047));
        assert_eq!(slid(0.005, 0.3, true), 0.0);
        let reach = 0.3 * 40.0 / (INERTIA * 0.16);
        assert!(close(slid_pushed(-0.08, 0.3, false, 10.0), -(0.08 - reach)));
    }

    /// A group whose contacts face two ways (a box in a corner) takes no step, nor one that
    /// touches a body another engine moves.
    #[test]
    fn a_group_on_two_surfaces_or_an_engines_body_takes_no_step() {
        let s = block(3, 2, 0.0);
        let x0 = s.x.clone();
        let y: Vec<DVec2> = x0.iter().map(|p| *p + DVec2::new(0.01, -0.01)).collect();
        for other in [
            Contact {
                normal: DVec2::X,
                force: 1.0,
                along: 0.0,
                shift: DVec2::ZERO,
            },
            LEFT_ALONE,
        ] {
            let mut slides = Slides::default();
            slides.ready(&s);
            slides.contacts[0] = Contact {
                normal: DVec2::Y,
                force: 1.0,
                along: 0.0,
                shift: DVec2::ZERO,
            };
            slides.contacts[2] = other;
            let mut x = x0.clone();
            assert_eq!(
                slides.step(&slides.contacts, &mut x, (&y, &x0, &s.mass), INERTIA, 0.5),
                0
            );
            assert_eq!(x, x0);
        }
    }

    /// On a surface that moves, the step is the group's relative to it: the block of
    /// [`slid`]'s test on a floor that slides 2 cm to the right over the step, its contacts moved
    /// 3 cm (1 cm over the floor), its inertia pulling it 5 mm further. Under μ = 4 it stops on
    /// the floor (back to 2 cm, the floor's way); without friction it goes the 5 mm; under μ = 0.3
    /// its way over the floor, 1.5 cm, less μ times its 1 cm way in, 3 mm.
    #[test]
    fn a_group_on_a_moving_floor_slides_over_it() {
        let slid_on = |mu: f64| {
            let s = block(4, 2, 0.0);
            let x0 = s.x.clone();
            let mut x: Vec<DVec2> = x0.iter().map(|p| *p + DVec2::new(0.03, 0.0)).collect();
            let y: Vec<DVec2> = x.iter().map(|p| *p + DVec2::new(0.005, -0.01)).collect();
            let mut slides = Slides::default();
            slides.ready(&s);
            for i in 0..4 {
                slides.contacts[i] = Contact {
                    normal: DVec2::Y,
                    force: 1.0,
                    along: 0.0,
                    shift: DVec2::new(0.02, 0.0),
                };
            }
            let contacts = slides.contacts.clone();
            slides.step(&contacts, &mut x, (&y, &x0, &s.mass), INERTIA, mu);
            x[5].x - x0[5].x
        };
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(slid_on(4.0), 0.02));
        assert!(close(slid_on(0.0), 0.035));
        assert!(close(slid_on(0.3), 0.02 + 0.015 - 0.003));
    }

    /// Implicit Euler's rub: a 4 × 2 block of 0.16 kg on a 30° slope, its bottom row held with 1 N
    /// each (normal impulse 4/60 N·s over 1/60 s), its velocity 0.5 m/s down the slope. Under μ
    /// = 0.5 friction may take back μ J_n/M = 0.208 m/s, less what the projections' friction
    /// gave already (0.1 N up the slope a contact: 0.042 m/s); with μ = 4 it stops the block
    /// (1.67 m/s of reach); with friction given already that fills the cone, nothing more; and
    /// every particle changes alike, along the slope.
    #[test]
    fn a_group_on_a_slope_is_slowed_within_coulombs_cone() {
        let dt = 1.0 / 60.0;
        // The slope rises to the right; its tangent `normal.perp()` points down it.
        let normal = DVec2::new(-0.5, 0.75f64.sqrt());
        let down = normal.perp();
        let rubbed = |mu: f64, up: f64| {
            let s = block(4, 2, 0.0);
            let mut slides = Slides::default();
            slides.ready(&s);
            for i in 0..4 {
                slides.contacts[i] = Contact {
                    normal,
                    force: 1.0,
                    along: -up,
                    shift: DVec2::ZERO,
                };
            }
            let mut v = vec![down * 0.5; s.x.len()];
            slides.rub(&slides.contacts.clone(), (&mut v, &s.mass), mu, dt);
            for w in &v {
                assert!((*w - v[0]).length() < 1e-15);
                assert!(w.dot(normal).abs() < 1e-15);
            }
            v[0].dot(down)
        };
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        let (reach, given) = (0.5 * 4.0 * dt / 0.16, 0.1 * 4.0 * dt / 0.16);
        assert!(close(rubbed(0.5, 0.0), 0.5 - reach));
        assert!(close(rubbed(0.5, 0.1), 0.5 - (reach - given)));
        assert!(close(rubbed(4.0, 0.0), 0.0));
        assert!(close(rubbed(0.5, 0.5), 0.5));
        assert!(close(rubbed(0.0, 0.0), 0.5));
    }
}
