//! Contact inside a large-step method's solve: the iterate kept out of the obstacles, the
//! ground and the other particles while the solve runs, so that the solve and the contact
//! agree where the step ends.
//!
//! Why: run only after the step (the contact pass), contact never reaches the solve. At a
//! frame's step the solve pulls a stack's particles into each other and into the walls by
//! the weight of everything above them, and the pass can only push the end positions back:
//! the springs it leaves compressed push back on the next step, and the push itself enters the
//! velocity of the methods that move with it. At 1/60 s a pile of soft boxes was crushed into
//! one layer and gained energy (181 J to 509 J under projective dynamics).
//!
//! How: between the solve's own iterations (projective dynamics' and BDF2's global steps,
//! VBD's vertex steps, XPBD's substeps, implicit Euler's Newton steps), each free particle is
//! placed back out of every surface along its path from where the step began
//! ([`super::pass::place`]: a swept test, so a large step cannot carry it through a thin
//! obstacle), and pairs of particles closer than 2r are pushed apart (one Jacobi pass of the
//! pair lists, readied for the step's travel). Friction acts at the position level in the
//! same place, as position-based dynamics treats it (Müller et al. 2020, "Detailed Rigid Body
//! Simulation with Extended Position Based Dynamics"): the particle's slide along the surface
//! since the step began is taken back by up to μ times the depth it was pushed out by. The
//! next iteration's springs then see the particle where the contact holds it, and the solve
//! spreads the support through the body. Restitution stays in the velocity pass after the
//! step, which still runs and finds little left to do.

use super::obstacle::{Lead, Placed};
use super::outline::Outlines;
use super::pairs::Pairs;
use super::pass::{Surroundings, Touched, hold, place};
use super::reaction::Reactions;
use glam::DVec2;

/// What a solve keeps its iterate out of during one step: the obstacles and the ground by the
/// contact radius, and the other particles (through lists readied for the step).
#[derive(Clone, Copy)]
pub struct InSolve<'a> {
    obstacles: &'a [Placed],
    /// Each obstacle's reach ([`super::pass::reaches`]).
    reach: &'a [f64],
    /// How long each obstacle has been moving onto the particles when the iterate is held
    /// out of it ([`Surroundings::leads`]): the step's own motion, from its start to where
    /// the obstacle now stands at the step's end.
    lead: &'a [Lead],
    ground: Option<f64>,
    radius: f64,
    friction: f64,
    dt: f64,
    /// The pair lists and the contact distance 2r, when particles collide.
    pairs: Option<(&'a Pairs, f64)>,
    /// The outline candidates and the contact distance 2r, when bodies collide by their
    /// outlines.
    outlines: Option<(&'a Outlines, f64)>,
    /// Each particle's velocity before contact (its start velocity plus a step of its forces'
    /// acceleration): where it is heading, which tells the side of a thin segment it belongs
    /// on. The iterates cannot: one the solve already put on the surface heads away from it.
    heading: &'a [DVec2],
    /// Where the pushes that become velocity note the obstacles' share
    /// ([`Self::keep_out_noting`]).
    reactions: Option<&'a Reactions>,
    /// Where the step began, when each pair that meets within it is pushed apart along the
    /// line it met on ([`Self::holding_sides`]).
    met_from: Option<&'a [DVec2]>,
    /// Passes over the pairs in each projection ([`Self::with_pair_passes`]); 1 unless a
    /// method asks for more.
    pair_passes: usize,
}

/// Where the step's moving obstacles stand at each stage of XPBD's substeps
/// ([`InSolve::at_substep`]), kept from step to step for its buffers. Empty when nothing
/// moves onto the particles: a scene whose obstacles stand still pays nothing.
#[derive(Debug, Default, Clone)]
pub(crate) struct SubstepPoses {
    /// The obstacles at the step's start, then where each substep ends: `substeps + 1` rows.
    poses: Vec<Placed>,
    /// How long each obstacle has moved onto the particles within one substep.
    lead: Vec<Lead>,
}

impl SubstepPoses {
    /// The poses of `contact`'s obstacles at each stage of a step of `substeps`. The
    /// obstacles stand where the step ends; one that moves onto the particles
    /// ([`Surroundings::leads`]) is moved back along its velocities to each stage.
    pub(crate) fn ready(&mut self, contact: Option<&InSolve>, substeps: usize) {
        self.poses.clear();
        self.lead.clear();
        let Some(c) = contact.filter(|c| c.lead.iter().any(|l| l.time > 0.0)) else {
            return;
        };
        let substeps = substeps.max(1);
        let lead = |k: usize| c.lead.get(k).map_or(0.0, |l| l.time);
        let share = |(k, o): (usize, &Placed)| o.lead(lead(k) / substeps as f64);
        self.lead.extend(c.obstacles.iter().enumerate().map(share));
        for stage in 0..=substeps {
            // The share of the step still to come at this stage.
            let remaining = (substeps - stage) as f64 / substeps as f64;
            let placed = c.obstacles.iter().enumerate().map(|(k, o)| {
                let mut o = *o;
                if lead(k) > 0.0 && stage < substeps {
                    o.advance(-lead(k) * remaining);
                }
                o
            });
            self.poses.extend(placed);
        }
    }
}

/// The last surface that held a particle out: its outward normal, and the obstacle's index
/// (`None` for the ground).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Held {
    pub normal: DVec2,
    pub obstacle: Option<usize>,
}

impl<'a> InSolve<'a> {
    /// The contact of a step of `dt` with `around`'s surfaces, and with particle pairs through
    /// `pairs` when they are readied ([`Pairs::ready_for_step`]). `None` when there is nothing
    /// to keep out of: a scene without contact runs exactly what it ran before. `reach` holds
    /// each obstacle's [`super::pass::reaches`] at the contact radius, and how long it has
    /// been moving onto the particles ([`Surroundings::leads`]).
    ///
    /// `bare_ground`: the ground is kept out of even without contact settings (the methods
    /// whose solve the step's own clamp cannot reach: [`crate::solver::step::integrate`]).
    pub(crate) fn new(
        around: &Surroundings<'a>,
        pairs: Option<&'a Pairs>,
        outlines: Option<&'a Outlines>,
        heading: &'a [DVec2],
        (reach, lead): (&'a [f64], &'a [Lead]),
        dt: f64,
        bare_ground: bool,
    ) -> Option<Self> {
        // Without settings, obstacles still hold points, frictionless, and so does the ground
        // where `bare_ground` asks (a point on a frictionless floor, as the clamp holds it);
        // otherwise the ground is then the step's own clamp's.
        let settings = around.settings.unwrap_or_default();
        let radius = settings.radius;
        let pairs = pairs
            .filter(|p| settings.particles && radius > 0.0 && p.active_count() > 0)
            .map(|p| (p, 2.0 * radius));
        let outlines = around.outlines().and_then(|contact| {
            outlines
                .filter(|o| o.candidates() > 0)
                .map(|o| (o, contact))
        });
        let ground = around
            .ground
            .filter(|_| bare_ground || around.settings.is_some());
        let obstacles = around.obstacles;
        if obstacles.is_empty() && ground.is_none() && pairs.is_none() && outlines.is_none() {
            return None;
        }
        Some(InSolve {
            obstacles,
            reach,
            lead,
            ground,
            radius,
            friction: settings.friction,
            dt,
            pairs,
            outlines,
            heading,
            reactions: around.reactions,
            met_from: None,
            pair_passes: 1,
        })
    }

    /// This contact with each pair that meets within the step, from `from` where it began,
    /// pushed apart along the line the two met on rather than their own
    /// ([`super::pairs::Pairs::push_apart`]): for projective dynamics' and BDF2's
    /// local/global iterations, whose global step moves a layer by many contact distances at
    /// once.
    ///
    /// Not for the others, measured (`docs/performance-log.md`, 2026-12-07): VBD's and XPBD's
    /// iterates move vertex by vertex or a substep at a time, the strip folding at 1/60 s kept
    /// its energy without it (9.2 J and 20.7 J from 8.8 J), and with it the pile under VBD
    /// came to rest jammed, 20 to 50 J above its resting energy and still stirring; under
    /// implicit Euler the pile at 1/30 s rose to 313 J (197 J without) and at 1/600 s turned 2
    /// to 4 of its 96 cells (none without).
    pub(crate) fn holding_sides<'b>(&'b self, from: &'b [DVec2]) -> InSolve<'b> {
        InSolve {
            met_from: Some(from),
            ..*self
        }
    }

    /// This contact with `passes` passes over the particle pairs in each projection
    /// ([`Self::project`]), each followed by the surfaces' hold: implicit Euler's few Newton
    /// steps, each closed by one projection, otherwise ended a step with pairs at half of 2r.
    pub(crate) fn with_pair_passes(&self, passes: usize) -> InSolve<'a> {
        InSolve {
            pair_passes: passes.max(1),
            ..*self
        }
    }

    /// Free particle `i`'s iterate `x` put back out of the obstacles and the ground along
    /// their normals alone, with no friction and no reaction noted; returns whether it was
    /// inside one.
    pub(crate) fn push_out(&self, i: usize, x: &mut DVec2, from: DVec2) -> bool {
        let before = *x;
        InSolve {
            friction: 0.0,
            reactions: None,
            ..*self
        }
        .keep_out(i, x, from);
        *x != before
    }

    /// This contact as XPBD's substeps read it, `stage` of a step of `substeps`: stage 0 at
    /// the step's start (before the first prediction), stage j + 1 where substep j ends. Each
    /// moving obstacle stands where `poses` ([`SubstepPoses::ready`]) puts it then, and reads
    /// a path of one substep in its frame; the surfaces' slide that friction measures is a
    /// substep's too.
    ///
    /// Why: a stage that saw each obstacle where the step began let it jump by a step's
    /// travel after the last substep, past a particle in its way (a slab moving at 2 m/s
    /// moves 3.3 cm in a step of 1/60 s: 55 of 66 particles at rest ahead of a thin one were
    /// passed); seen where the step ends, a particle riding on it was pushed by the step's
    /// travel in every substep, and moved at twice its speed.
    pub(crate) fn at_substep<'b>(
        &'b self,
        poses: &'b SubstepPoses,
        stage: usize,
        substeps: usize,
    ) -> InSolve<'b> {
        let span = self.dt / substeps.max(1) as f64;
        let k = self.obstacles.len();
        let (obstacles, lead): (&[Placed], &[Lead]) = if poses.poses.is_empty() {
            (self.obstacles, self.lead)
        } else if stage == 0 {
            (&poses.poses[..k], &[])
        } else {
            (&poses.poses[stage * k..(stage + 1) * k], &poses.lead)
        };
        InSolve {
            obstacles,
            lead,
            dt: span,
            ..*self
        }
    }

    /// The same contact, noting no impulses for the obstacles that stand for bodies: for a
    /// solve that may be taken again (BDF2's, `methods::bdf2`), whose impulses the solve
    /// taken in its place notes.
    pub(crate) fn without_notes(&self) -> Self {
        InSolve {
            reactions: None,
            ..*self
        }
    }

    /// The same contact with the obstacles standing at `obstacles`, each read with `lead`
    /// (one per obstacle): for a solve that moves its bodies among its unknowns
    /// ([`super::solved`]).
    pub(crate) fn with_obstacles<'b>(
        &'b self,
        obstacles: &'b [Placed],
        lead: &'b [Lead],
    ) -> InSolve<'b> {
        InSolve {
            obstacles,
            lead,
            ..*self
        }
    }

    /// The obstacles, where this contact sees them.
    pub(crate) fn obstacles(&self) -> &'a [Placed] {
        self.obstacles
    }

    /// The step (or substep) this contact is for, s.
    pub(crate) fn dt(&self) -> f64 {
        self.dt
    }

    /// Where the contacts' impulses are noted, when some obstacles stand for bodies.
    pub(crate) fn reactions(&self) -> Option<&'a Reactions> {
        self.reactions
    }

    /// How long each obstacle has moved onto the particles when a path is read against it
    /// (empty: none has).
    pub(crate) fn leads(&self) -> &'a [Lead] {
        self.lead
    }

    /// The contact radius, m.
    pub(crate) fn radius(&self) -> f64 {
        self.radius
    }

    /// The friction coefficient.
    pub(crate) fn friction(&self) -> f64 {
        self.friction
    }

    /// The same contact without the outlines.
    pub(crate) fn without_outlines(&self) -> Self {
        InSolve {
            outlines: None,
            ..*self
        }
    }

    /// The ground as this contact holds particles on it: its height plus the radius, and the
    /// friction coefficient.
    pub(crate) fn ground(&self) -> Option<(f64, f64)> {
        self.ground.map(|g| (g + self.radius, self.friction))
    }

    /// Whether this contact could act on any particle of `x`: always, but for the ground
    /// alone, which acts only on a particle under its height plus the radius. A solve whose
    /// iterate nothing reaches can leave the contact's bookkeeping aside ([`Support`]), since
    /// holding that iterate would move nothing. (A pinned particle under the ground answers
    /// yes, and is then left alone as the contact leaves every pinned particle.)
    pub(crate) fn reaches(&self, x: &[DVec2]) -> bool {
        let only_ground = self.obstacles.is_empty() && !self.has_pairs();
        match self.ground {
            Some(g) if only_ground => {
                let top = g + self.radius;
                x.iter().any(|x| x.y < top)
            }
            _ => true,
        }
    }

    /// Whether particle pairs, or particles and other bodies' outlines, are kept apart too.
    pub(crate) fn has_pairs(&self) -> bool {
        self.pairs.is_some() || self.outlines.is_some()
    }

    /// The particles with listed neighbours: the length of [`Self::separate`]'s scratch.
    pub(crate) fn pair_scratch(&self) -> usize {
        self.pairs.map_or(0, |(p, _)| p.active_count())
    }

    /// Free particle `i`'s iterate `x`, which the step moves from `from`, put back out of the
    /// obstacles and the ground, with friction on its slide. Returns the last surface it
    /// touched, if any.
    #[inline]
    pub(crate) fn keep_out(&self, i: usize, x: &mut DVec2, from: DVec2) -> Option<Held> {
        self.keep_out_noting(i, x, from, 0.0)
    }

    /// [`Self::keep_out`] for a push that becomes velocity: `per_metre` (kg/s, a particle's
    /// mass over the time its push is spread over: XPBD's m/hₛ) turns each obstacle's push
    /// into the impulse that obstacle takes back. 0 notes nothing.
    #[inline]
    pub(crate) fn keep_out_noting(
        &self,
        i: usize,
        x: &mut DVec2,
        from: DVec2,
        per_metre: f64,
    ) -> Option<Held> {
        if self.obstacles.is_empty() {
            // The ground alone: one comparison for the particles far above it.
            match self.ground {
                Some(g) if x.y < g + self.radius => {}
                _ => return None,
            }
        }
        let (friction, dt) = (self.friction, self.dt);
        let heading = self.heading.get(i).copied().unwrap_or((*x - from) / dt);
        let mut held = None;
        let reactions = self.reactions.filter(|_| per_metre != 0.0);
        // Where the particle was before each obstacle's push, to note that push alone.
        let mut mark = *x;
        place(
            x,
            from,
            heading,
            self.obstacles,
            (self.reach, self.lead),
            self.radius,
            self.ground,
            |x, touched: Touched| {
                let n = touched.normal;
                let surface_shift = touched.surface_velocity * dt;
                hold(x, from, surface_shift, n, touched.depth, friction);
                held = Some(Held {
                    normal: n,
                    obstacle: touched.obstacle,
                });
                if let (Some(_), Some(o)) = (reactions, touched.obstacle) {
                    let impulse = (*x - mark) * per_metre;
                    self.note(o, i, (*x, n), impulse, Some(touched.surface_velocity));
                }
                mark = *x;
            },
        );
        held
    }

    /// Whether the contacts' impulses are noted for the obstacles (some stand for bodies).
    pub(crate) fn notes(&self) -> bool {
        self.reactions.is_some()
    }

    /// Notes that the obstacle `obstacle` gave free particle `i`, at `x` and pushing along
    /// `normal`, the impulse `on_particle` over the step (a solve's contact force times dt, or a
    /// push over its substep). `surface_velocity`, the obstacle's where the particle touches
    /// it (read from the obstacle when `None`), gives the particle's approach: its heading
    /// toward the surface before contact.
    pub(crate) fn note(
        &self,
        obstacle: usize,
        i: usize,
        (x, normal): (DVec2, DVec2),
        on_particle: DVec2,
        surface_velocity: Option<DVec2>,
    ) {
        let (Some(r), Some(o)) = (self.reactions, self.obstacles.get(obstacle)) else {
            return;
        };
        let surface_velocity = surface_velocity.unwrap_or_else(|| o.velocity_at(x));
        let heading = self.heading.get(i).copied().unwrap_or(DVec2::ZERO);
        let approach = -(heading - surface_velocity).dot(normal);
        r.note(obstacle, i, x - normal * self.radius, on_particle, approach);
    }

    /// One Jacobi pass pushing the listed pairs apart in the iterate `x` (inverse masses `w`),
    /// with `scratch` of [`Self::pair_scratch`]'s length; then one Gauss–Seidel pass pushing
    /// particles out of other bodies' outlines, back to the side each started the step on.
    pub(crate) fn separate(&self, x: &mut [DVec2], w: &[f64], scratch: &mut [DVec2]) {
        if let Some((pairs, contact)) = self.pairs {
            pairs.push_apart(x, self.met_from, w, contact, scratch);
        }
        if let Some((outlines, contact)) = self.outlines {
            outlines.push_apart(x, w, contact, None);
        }
    }

    /// The whole iterate: pairs pushed apart, then every free particle kept out of the
    /// surfaces (which wins where the two disagree: a particle pressed into the ground by
    /// another stays on it, and the other moves), as many times as [`Self::with_pair_passes`]
    /// asks. `from` is where the step began. Calls `each(i, x, held)` for every free particle
    /// where it ends, with the last surface it touched in any pass (`touched` keeps them
    /// between passes): one that an earlier pass put on a surface is still held by it, so
    /// that an engine's body under it still takes its weight (without, crates fell through
    /// the net they rested in).
    pub(crate) fn project(
        &self,
        x: &mut [DVec2],
        from: &[DVec2],
        w: &[f64],
        (scratch, touched): (&mut [DVec2], &mut Vec<Option<Held>>),
        mut each: impl FnMut(usize, DVec2, Option<Held>),
    ) {
        let passes = if self.pairs.is_some() {
            self.pair_passes
        } else {
            1
        };
        touched.clear();
        if passes > 1 {
            touched.resize(x.len(), None);
        }
        for pass in 1..=passes {
            self.separate(x, w, scratch);
            let last = pass == passes;
            for (i, ((x, &from), &w)) in x.iter_mut().zip(from).zip(w).enumerate() {
                if w != 0.0 {
                    let held = self.keep_out(i, x, from);
                    if !last {
                        if held.is_some() {
                            touched[i] = held;
                        }
                    } else {
                        each(i, *x, held.or_else(|| touched.get(i).copied().flatten()));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::obstacle::{Placed, Pose, Shape};
    use super::*;

    /// XPBD's stages see a moving obstacle from where the step began (stage 0, the entry with
    /// no lead) to where it ends (the last), a substep's motion apart, with a substep's lead;
    /// one that stands still is where it is at every stage, with none.
    #[test]
    fn each_substep_sees_a_moving_obstacle_where_it_ends() {
        let (dt, substeps) = (1.0 / 60.0, 7);
        let hs = dt / substeps as f64;
        let moving = Placed {
            shape: Shape::Box {
                half: DVec2::new(0.3, 0.02),
            },
            pose: Pose {
                center: DVec2::new(0.5, 0.4),
                angle: 0.3,
                velocity: DVec2::new(2.0, -10.0),
                angular_velocity: 20.0,
            },
        };
        let still = Placed::at(Shape::Circle { radius: 0.1 }, DVec2::new(-0.5, 0.0), 0.0);
        let obstacles = [still, moving];
        let around = Surroundings {
            obstacles: &obstacles,
            ground: None,
            settings: None,
            reactions: None,
        };
        let (reach, lead) = (
            super::super::pass::reaches(&obstacles, 0.0),
            around.leads(dt),
        );
        let contact = InSolve::new(&around, None, None, &[], (&reach, &lead), dt, false).unwrap();
        let mut poses = SubstepPoses::default();
        poses.ready(Some(&contact), substeps);
        let mut start = moving;
        start.advance(-dt);
        let close = |a: &Placed, b: &Placed| {
            (a.pose.center - b.pose.center).length() < 1e-14
                && (a.pose.angle - b.pose.angle).abs() < 1e-14
        };
        for stage in 0..=substeps {
            let seen = contact.at_substep(&poses, stage, substeps);
            assert_eq!(seen.obstacles[0], still, "stage {stage}");
            let mut expected = start;
            expected.advance(hs * stage as f64);
            assert!(close(&seen.obstacles[1], &expected), "stage {stage}");
            let want: &[f64] = if stage == 0 { &[] } else { &[0.0, hs] };
            let times: Vec<f64> = seen.lead.iter().map(|l| l.time).collect();
            assert_eq!(times, want, "stage {stage}");
            assert_eq!(seen.dt, hs);
        }
        assert_eq!(
            contact.at_substep(&poses, substeps, substeps).obstacles[1],
            moving
        );
        // Nothing moves: the contact as it is, a substep's slide for friction.
        let calm = [still];
        let around = Surroundings {
            obstacles: &calm,
            ..around
        };
        let lead = around.leads(dt);
        let contact = InSolve::new(&around, None, None, &[], (&reach, &lead), dt, false).unwrap();
        poses.ready(Some(&contact), substeps);
        assert!(poses.poses.is_empty());
        let seen = contact.at_substep(&poses, 3, substeps);
        assert!(seen.lead.is_empty());
        assert_eq!((seen.obstacles, seen.dt), (&calm[..], hs));
    }
}
