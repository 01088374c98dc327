//! The contact pass: after the position update, each free particle is kept out of the
//! obstacles (and, when contact is set, out of the ground by its radius), and its velocity
//! relative to the surface it touches loses its approach (keeping the restitution's share)
//! and up to μ times that in sliding (Coulomb friction).
//!
//! Why after the step, for every integrator: each method's update stays what it was, and the
//! contact sees where the step ends, so a large step cannot end inside an obstacle. A fast
//! particle cannot cross a thin obstacle within a step either: its path from where the step
//! began (x₁ − dt·u, u the velocity it moved with) to where it ends is tested against each
//! obstacle, and it stops where it first touches ([`super::obstacle::Placed::first_hit`]).
//!
//! Why the velocity rule keeps energy from rising: the normal part of the relative velocity
//! only shrinks in size (|e·vₙ| ≤ |vₙ| with e ≤ 1), the tangential part only shrinks, and the
//! position moves only back toward the surface, by at most the step's own travel into it.

use super::obstacle::{Hit, Lead, Placed, SLOP, Surface, respond};
use super::reaction::Reactions;
use crate::solver::forces::sweep::Motion;
use crate::solver::threads::Threads;
use glam::DVec2;

/// Contact settings: the particles' radius, and the surfaces' friction and restitution, at
/// every contact (the ground's, the obstacles', and between particles).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSettings {
    /// Every particle's collision radius, m (0: points).
    #[serde(default)]
    pub radius: f64,
    /// Coulomb coefficient μ.
    #[serde(default)]
    pub friction: f64,
    /// The share of the normal approach speed kept after an impact, 0..=1.
    #[serde(default)]
    pub restitution: f64,
    /// Particles collide with each other, between bodies and within one ([`super::pairs`]).
    #[serde(default)]
    pub particles: bool,
    /// Particles are kept out of other bodies' outlines (their boundary springs as capsules
    /// of the radius, [`super::outline`]): bodies whose particles sit farther apart than 2r
    /// cannot pass into each other.
    #[serde(default)]
    pub outlines: bool,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            radius: 0.0,
            friction: 0.0,
            restitution: 0.0,
            particles: false,
            outlines: false,
        }
    }
}

impl ContactSettings {
    /// What is wrong with the settings, as (field, value, rule), if anything.
    pub fn problem(&self) -> Option<(&'static str, f64, &'static str)> {
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !non_negative(self.radius) {
            return Some(("radius", self.radius, "must be finite and >= 0"));
        }
        if !non_negative(self.friction) {
            return Some(("friction", self.friction, "must be finite and >= 0"));
        }
        if !(non_negative(self.restitution) && self.restitution <= 1.0) {
            return Some(("restitution", self.restitution, "must be between 0 and 1"));
        }
        None
    }
}

/// What the contact pass works against: the obstacles, the ground, and the settings (`None`:
/// particles are points, the ground is the step's own frictionless clamp and not this pass's,
/// and obstacles are frictionless and keep nothing of an impact).
#[derive(Debug, Clone, Copy)]
pub struct Surroundings<'a> {
    /// The obstacles at their poses.
    pub obstacles: &'a [Placed],
    /// The ground's height, when the scene has one.
    pub ground: Option<f64>,
    /// The contact settings.
    pub settings: Option<ContactSettings>,
    /// Where the particles' contacts note the impulse each obstacle takes back, when some
    /// obstacle stands for a body that feels them ([`super::reaction`]); `None` otherwise.
    /// The caller ends each step with [`Reactions::close_step`], which gives the bodies'
    /// masses their part.
    pub reactions: Option<&'a Reactions>,
}

impl Surroundings<'_> {
    /// Whether the pass has anything to do.
    pub fn active(&self) -> bool {
        let pairs = self.settings.is_some_and(|s| s.particles && s.radius > 0.0);
        !self.obstacles.is_empty()
            || (self.settings.is_some() && self.ground.is_some())
            || pairs
            || self.outlines().is_some()
    }

    /// The contact distance 2r when bodies collide by their outlines.
    pub(crate) fn outlines(&self) -> Option<f64> {
        self.settings
            .filter(|s| s.outlines && s.radius > 0.0)
            .map(|s| 2.0 * s.radius)
    }

    /// The ground this pass handles: only when contact is set (else the step's own clamp does).
    fn ground(&self) -> Option<f64> {
        self.settings.and(self.ground)
    }

    fn radius(&self) -> f64 {
        self.settings.map_or(0.0, |s| s.radius)
    }

    /// `p`, pushed there from `from`, put back out of the ground (when contact is set) and the
    /// obstacles by the radius (`reach`: each obstacle's [`reaches`] at it), positions only:
    /// what the pair solve holds its particles to between its iterations, so that a particle
    /// pressed against the ground by another stays on it and the other moves. Out by the
    /// nearest surface, but on `from`'s side ([`Placed::touch`]); a push across the shape
    /// itself (a segment's line, or a closed shape from side to side, [`Placed::crossing`])
    /// goes back to where it crossed first, then out on that side. A push of up to 3r (the
    /// pair solve's over-relaxation) can carry a light particle under a heavy one across a
    /// thin plank, even clear of its far side, past a shape's middle, or through a thin box:
    /// out by the nearest surface alone it went on through.
    pub(crate) fn keep_out(&self, mut p: DVec2, from: DVec2, reach: &[f64]) -> DVec2 {
        let (r, push) = (self.radius(), p - from);
        let travel = push.abs().element_sum();
        for (o, &reach) in self.obstacles.iter().zip(reach) {
            let within = reach + travel;
            if (p - o.pose.center).length_squared() > within * within {
                continue;
            }
            // A start inside a closed shape (an explicit step's update carried the particle
            // in; the obstacle pass, after this one, puts it out) has its side at its nearest
            // surface.
            let from = o.out_by_nearest(from);
            if let Some(t) = o.crossing(from, p) {
                p = from + (p - from) * t;
            }
            if let Some(touch) = o.touch(p, from, push, r) {
                p += touch.normal * touch.depth;
            }
        }
        if let Some(g) = self.ground() {
            p.y = p.y.max(g + r);
        }
        p
    }

    /// How long each obstacle has been moving onto the particles when a step of `dt` reads
    /// it ([`place`]): `dt` for one that moves by its velocity over the step, which the step
    /// moved to where it ends before its contact (an obstacle of this crate, a kinematic
    /// body); 0 for one that stands still, and for one whose body another engine moves after
    /// the step, feeling the particles' push (a dynamic rigid body, [`Reactions::feels`]):
    /// that one stands where the step began ([`moves_first`]). XPBD's substeps read a
    /// substep's share of it, each where its obstacle stands then
    /// ([`super::inside::InSolve::at_substep`]).
    ///
    /// Why not sweep a dynamic body too: the push it gave a stiff net, swept ahead of it
    /// within the step as if it were a wall, came back to it in full, and past twice its mass
    /// (k dt² > 2M, eleven times past for the `crates` scene's net at 1/60 s) that threw it
    /// back faster than it came: its crates spun up without bound under projective dynamics,
    /// XPBD and VBD (docs/performance-log.md, 2026-12-06).
    ///
    /// Empty when none has a lead: the common case, a scene whose obstacles stand still, pays
    /// nothing for it.
    pub(crate) fn leads(&self, dt: f64) -> Vec<Lead> {
        let leads = |k: usize, o: &Placed| moves_first(o, k, self.reactions);
        if !self.obstacles.iter().enumerate().any(|(k, o)| leads(k, o)) {
            return vec![];
        }
        self.obstacles
            .iter()
            .enumerate()
            .map(|(k, o)| o.lead(if leads(k, o) { dt } else { 0.0 }))
            .collect()
    }

    pub(crate) fn surface(&self, dt: f64, gravity: DVec2) -> Surface {
        let s = self.settings.unwrap_or_default();
        Surface {
            friction: s.friction,
            restitution: s.restitution,
            // A resting particle approaches at one step of gravity; twice that keeps it at rest.
            rest_speed: 2.0 * gravity.length() * dt,
        }
    }
}

/// Whether a step moves obstacle `k`, `o`, to where it ends before its contact: one that
/// moves by its velocities, unless its body feels the particles' push (`reactions`, when
/// the obstacles stand for bodies: [`Reactions::feels`]), whose engine moves it after the
/// step. The one rule for the core's contact ([`Surroundings::leads`]) and for whatever moves
/// the obstacles between steps (the ECS's `Obstacles::advance`).
pub(crate) fn moves_first(o: &Placed, k: usize, reactions: Option<&Reactions>) -> bool {
    o.moves() && !reactions.is_some_and(|r| r.feels(k))
}

/// The contact pass over the particles `x`, `v` (after the position update), with `u` the
/// velocity each moved with over the step (`v` itself for the methods that move with their end
/// velocity) and `w` their inverse masses (0: pinned or held, left alone). Returns how many
/// particle–surface contacts it resolved.
#[allow(clippy::too_many_arguments)]
pub fn collide(
    x: &mut [DVec2],
    v: &mut [DVec2],
    u: Option<&[DVec2]>,
    w: &[f64],
    dt: f64,
    gravity: DVec2,
    around: &Surroundings,
    threads: &Threads,
    springs: usize,
) -> usize {
    let (r, ground, surface) = (
        around.radius(),
        around.ground(),
        around.surface(dt, gravity),
    );
    let obstacles = around.obstacles;
    let (reach, lead) = (reaches(obstacles, r), around.leads(dt));
    // Once a contact has put the particle back on a surface (normal n, pushed out by depth,
    // the surface moving at surface_velocity): friction on the step's sliding, then the
    // velocity's response.
    let reactions = around.reactions;
    let grip = |i: usize, x: &mut DVec2, v: &mut DVec2, w: f64, from, touched: Touched| {
        let Touched {
            normal: n,
            depth,
            surface_velocity,
            obstacle,
        } = touched;
        hold(x, from, surface_velocity * dt, n, depth, surface.friction);
        let before = *v;
        *v = respond(*v, surface_velocity, n, surface);
        if let (Some(reactions), Some(o)) = (reactions, obstacle) {
            let approach = -(before - surface_velocity).dot(n);
            reactions.note(o, i, *x - n * r, (*v - before) / w, approach);
        }
    };
    let one = |i: usize, x: &mut DVec2, v: &mut DVec2, u: DVec2, w: f64| -> usize {
        if w == 0.0 {
            return 0;
        }
        // Where the step began, and where the particle was going (the velocity it moved
        // with, or its velocity, for a step that did not move it).
        let from = *x - u * dt;
        let heading = if *x != from { u } else { *v };
        place(
            x,
            from,
            heading,
            obstacles,
            (&reach, &lead),
            r,
            ground,
            |x, touched| grip(i, x, v, w, from, touched),
        )
    };
    // The path's velocity: the drift's, or the end velocity itself (read before it changes).
    // `at` holds the particles' indices in the whole state, for the notes.
    let part = |at: std::ops::Range<usize>,
                x: &mut [DVec2],
                v: &mut [DVec2],
                u: Option<&[DVec2]>,
                w: &[f64]| {
        let mut n = 0;
        for (k, i) in at.enumerate() {
            let uk = u.map_or(v[k], |u| u[k]);
            n += one(i, &mut x[k], &mut v[k], uk, w[k]);
        }
        n
    };
    let all = 0..x.len();
    match u {
        Some(u) => threads.chunked(
            springs,
            (all, &mut x[..], &mut v[..], u, w),
            |(at, x, v, u, w)| part(at, x, v, Some(u), w),
            |a, b| a + b,
        ),
        None => threads.chunked(
            springs,
            (all, &mut x[..], &mut v[..], w),
            |(at, x, v, w)| part(at, x, v, None, w),
            |a, b| a + b,
        ),
    }
}

/// The velocity pass after a step whose solve kept contact itself (`contact/inside.rs`): the
/// particles are already out of every surface, on their own sides, with friction's hold in
/// their positions, so nothing is placed again (a path re-read after the solve can start on a
/// thin segment's line and pick the wrong side). A free particle that ends touching a surface
/// keeps no approach in its end velocity, and bounces with the restitution's share of the
/// approach it had before contact, `pre` (its start velocity plus a step of its body
/// forces' acceleration), above the rest speed. Returns the contacts.
#[allow(clippy::too_many_arguments)]
pub fn settle(
    x: &[DVec2],
    v: &mut [DVec2],
    pre: &[DVec2],
    w: &[f64],
    dt: f64,
    gravity: DVec2,
    around: &Surroundings,
    threads: &Threads,
    springs: usize,
) -> usize {
    let (r, ground, surface) = (
        around.radius(),
        around.ground(),
        around.surface(dt, gravity),
    );
    let (obstacles, reactions) = (around.obstacles, around.reactions);
    let reach = reaches(obstacles, r);
    let one = |i: usize, x: DVec2, v: &mut DVec2, pre: DVec2, w: f64| -> usize {
        if w == 0.0 {
            return 0;
        }
        let mut contacts = 0;
        let mut touching = |n: DVec2, surface_velocity: DVec2, obstacle: Option<usize>| {
            let (end, before) = (
                (*v - surface_velocity).dot(n),
                (pre - surface_velocity).dot(n),
            );
            let bounce = if -before > surface.rest_speed {
                -before * surface.restitution
            } else {
                0.0
            };
            // A particle that came in leaves with the restitution's share of its approach
            // alone, whatever velocity the solve's own formula gave it (BDF2's, from its
            // history, sent a particle that landed up at half its speed); one that was leaving
            // keeps going.
            let normal = if before < 0.0 { bounce } else { end.max(0.0) };
            *v += n * (normal - end);
            if let (Some(reactions), Some(o)) = (reactions, obstacle) {
                reactions.note(o, i, x - n * r, n * ((normal - end) / w), -before);
            }
            contacts += 1;
        };
        for (k, (o, &reach)) in obstacles.iter().zip(&reach).enumerate() {
            if (x - o.pose.center).length_squared() > reach * reach {
                continue;
            }
            let (d, n) = o.distance(x);
            if d < r + SLOP {
                touching(n, o.velocity_at(x), Some(k));
            }
        }
        if let Some(g) = ground
            && x.y < g + r + SLOP
        {
            touching(DVec2::Y, DVec2::ZERO, None);
        }
        contacts
    };
    threads.chunked(
        springs,
        (0..x.len(), x, &mut v[..], pre, w),
        |(at, x, v, pre, w)| {
            let mut n = 0;
            for (k, i) in at.enumerate() {
                n += one(i, x[k], &mut v[k], pre[k], w[k]);
            }
            n
        },
        |a, b| a + b,
    )
}

/// One surface a particle was put on by [`place`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Touched {
    /// The surface's outward normal.
    pub normal: DVec2,
    /// How far the particle was pushed out, m.
    pub depth: f64,
    /// The surface's velocity where the particle touches it.
    pub surface_velocity: DVec2,
    /// The obstacle's index, `None` for the ground.
    pub obstacle: Option<usize>,
}

/// How near each obstacle's centre a particle of radius `r` must come to touch it: the
/// obstacle's bound, the radius and two slops. Worked out once a pass, not once a particle:
/// a box's bound is a square root, a polygon's one per corner, and every particle asks, in
/// every iteration of a solve.
pub(crate) fn reaches(obstacles: &[Placed], r: f64) -> Vec<f64> {
    obstacles
        .iter()
        .map(|o| o.bound() + r + 2.0 * SLOP)
        .collect()
}

/// Puts a particle that moved from `from` to `x` (heading `heading`, a velocity: only its
/// direction counts) back out of the obstacles and the ground (`ground`: its height when this
/// pass handles it) by the radius `r`, and calls `touched(x, surface)` for each surface it
/// was put on. A path that crosses into an obstacle stops where it first touches and slides
/// on along the surface for the rest of its travel, so that no step, however large, carries a
/// particle through a thin one. Returns the contacts. The contact pass and the large-step
/// methods' solves ([`super::inside`]) both place particles with it.
///
/// `(reach, lead)`: each obstacle's [`reaches`], and how long it has been moving onto the
/// particles ([`Surroundings::leads`]; missing: 0). A moving obstacle stands where the step
/// ends, and reads the path in its own frame: from where the start was on it
/// ([`Placed::carried`]), with the heading relative to its surface. A box that moves onto a
/// particle within the step strikes it, where a test of the particle's own path, which has
/// no length for a particle at rest, let a thin one move clean past it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn place(
    x: &mut DVec2,
    from: DVec2,
    heading: DVec2,
    obstacles: &[Placed],
    (reach, lead): (&[f64], &[Lead]),
    r: f64,
    ground: Option<f64>,
    touched: impl FnMut(&mut DVec2, Touched),
) -> usize {
    let around = (obstacles, reach, r, ground);
    // The path's length bounded by |Δx| + |Δy|, for the test of which obstacles it comes near.
    if lead.is_empty() {
        // Nothing moves onto the particles (`Surroundings::leads`), the common case: the path
        // as it is, its length worked out once.
        let travel = (*x - from).abs().element_sum();
        return place_along(x, around, |_| (from, travel, heading), touched);
    }
    // Each obstacle's view of the path: from where its start was on the obstacle's frame,
    // with the heading relative to its surface (at the path's end).
    let end = *x;
    let view = |k: usize| {
        let o: &Placed = &obstacles[k];
        let lead = lead.get(k).copied().unwrap_or_default();
        let start = o.carried_by(from, lead);
        let heading = if lead.time > 0.0 {
            heading - o.velocity_at(end)
        } else {
            heading
        };
        (start, (end - start).abs().element_sum(), heading)
    };
    place_along(x, around, view, touched)
}

/// [`place`], with each obstacle `k`'s view of the path, `view(k)`: where it starts, its
/// length bounded by |Δx| + |Δy|, and the heading.
fn place_along(
    x: &mut DVec2,
    (obstacles, reach, r, ground): (&[Placed], &[f64], f64, Option<f64>),
    view: impl Fn(usize) -> (DVec2, f64, DVec2),
    mut touched: impl FnMut(&mut DVec2, Touched),
) -> usize {
    let mut contacts = 0;
    // Only the obstacles the path comes near: a test of the distance to each one's centre,
    // squared, against its reach and the path's length. With a square root for the path and
    // one for each distance, perf put 29 % of the 256² cloth's run on a disc at 1e-4 s here.
    let near = |k: usize, x: DVec2, travel: f64| {
        let within = reach[k] + travel;
        (x - obstacles[k].pose.center).length_squared() <= within * within
    };
    // Most particles of a big cloth are near no surface: they leave after those few
    // multiplications, before the swept tests' iterators (passing over them took the contact
    // pass on that cloth from 1.35 s to 0.45 s in 2,000 steps; docs/performance-log.md,
    // 2026-12-06).
    let ground_near = ground.is_some_and(|g| x.y < g + r + SLOP);
    if !ground_near && !(0..obstacles.len()).any(|k| near(k, *x, view(k).1)) {
        return 0;
    }
    // The first obstacle the path touches (a loop: as an iterator chain over the views it
    // was not inlined, and cost the contact pass 6 % of its instructions).
    let mut first: Option<(Hit, usize, DVec2, DVec2)> = None;
    for (k, o) in obstacles.iter().enumerate() {
        let (from, travel, heading) = view(k);
        if !near(k, *x, travel) {
            continue;
        }
        if let Some(hit) = o.first_hit(from, *x, r)
            && first.is_none_or(|f| hit.t < f.0.t)
        {
            first = Some((hit, k, from, heading));
        }
    }
    if let Some((Hit { t, through }, i, start, heading)) = first {
        let o = &obstacles[i];
        let step = *x - start;
        let hit = start + step * t;
        // A segment's side is its path's start's, when the path starts off it: a solve's
        // iterate can land across a segment while its heading (its velocity plus a step of its
        // forces, far off at a frame's step) points away, and was put on the far side (implicit
        // Euler's gas ball went through a slope at 1/60 s). A start on its line has no side of
        // its own and takes the one it heads from. A closed shape keeps the heading: facing its
        // hit to the path made BDF2's settled pile creep up (docs/performance-log.md,
        // 2026-12-05, the thrown box under implicit Euler), except on a path through it from
        // a start in contact, which enters where the path says.
        let toward = if through || (t > 0.0 && o.is_segment()) {
            step
        } else {
            heading
        };
        let n = o.hit_normal(hit, toward);
        let rest = step * (1.0 - t);
        let into = (-rest.dot(n)).max(0.0);
        *x = hit + rest + n * into;
        let surface_velocity = o.velocity_at(*x);
        touched(
            x,
            Touched {
                normal: n,
                depth: into,
                surface_velocity,
                obstacle: Some(i),
            },
        );
        contacts += 1;
    }
    for (k, o) in obstacles.iter().enumerate() {
        let (start, travel, heading) = view(k);
        if !near(k, *x, travel) {
            continue;
        }
        if let Some(touch) = o.touch(*x, start, heading, r) {
            *x += touch.normal * touch.depth;
            let surface_velocity = o.velocity_at(*x);
            touched(
                x,
                Touched {
                    normal: touch.normal,
                    depth: touch.depth,
                    surface_velocity,
                    obstacle: Some(k),
                },
            );
            contacts += 1;
        }
    }
    if let Some(g) = ground
        && x.y < g + r + SLOP
    {
        let depth = (g + r - x.y).max(0.0);
        x.y = x.y.max(g + r);
        touched(
            x,
            Touched {
                normal: DVec2::Y,
                depth,
                surface_velocity: DVec2::ZERO,
                obstacle: None,
            },
        );
        contacts += 1;
    }
    contacts
}

/// Friction on the step's displacement: the particle's sliding over the step, relative to the
/// surface (which moved by `surface_shift`), is taken back by at most μ times the depth the
/// contact pushed it out by, all of it when that is enough (static friction). Without this a
/// particle held by friction would still creep down a slope by g·sinθ·dt² a step: the
/// velocity rule stops its motion, but only after the step has moved it.
pub(crate) fn hold(
    x: &mut DVec2,
    from: DVec2,
    surface_shift: DVec2,
    n: DVec2,
    depth: f64,
    friction: f64,
) {
    let moved = *x - from - surface_shift;
    let sliding = moved - n * moved.dot(n);
    let (length, limit) = (sliding.length(), friction * depth);
    if length <= limit {
        *x -= sliding;
    } else if length > 0.0 {
        *x -= sliding * (limit / length);
    }
}

/// Whether the step's path is read from the drift buffer (explicit Euler: the start-of-step
/// velocity; velocity Verlet, RK4, XPBD: the velocity the position update used), or from the
/// end velocity (symplectic and implicit Euler, projective dynamics, which move with it).
pub fn moves_with_drift(motion: Motion) -> bool {
    matches!(motion, Motion::ExplicitEuler | Motion::Drift)
}

#[cfg(test)]
mod tests {
    use super::super::obstacle::{Polygon, Shape};
    use super::*;

    /// The reach's shortcuts change nothing. Around a disc, a turned box, a sloping line and
    /// a turned hexagon above a ground, a particle at each point of a fine grid, arriving by
    /// steps of several lengths and directions: [`place`] with the reaches ends it where it
    /// ends testing every obstacle, through the same surfaces, and [`Surroundings::keep_out`]
    /// with the reaches puts each point where testing every obstacle puts it.
    #[test]
    fn the_reach_shortcuts_change_no_contact() {
        let hexagon: Vec<DVec2> = (0..6)
            .map(|k| 0.3 * DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_3))
            .collect();
        let obstacles = [
            Placed::at(Shape::Circle { radius: 0.3 }, DVec2::new(0.6, 0.5), 0.0),
            Placed::at(
                Shape::Box {
                    half: DVec2::new(0.4, 0.1),
                },
                DVec2::new(-0.6, 0.4),
                0.3,
            ),
            Placed::at(
                Shape::Segment {
                    a: DVec2::new(-0.5, 0.0),
                    b: DVec2::new(0.4, 0.2),
                    thickness: 0.0,
                },
                DVec2::new(0.0, -0.5),
                0.0,
            ),
            Placed::at(
                Shape::Polygon(Polygon::new(&hexagon).unwrap()),
                DVec2::new(0.7, -0.6),
                0.7,
            ),
        ];
        let r = 0.05;
        let around = Surroundings {
            obstacles: &obstacles,
            ground: Some(-1.0),
            settings: Some(ContactSettings {
                radius: r,
                ..Default::default()
            }),
            reactions: None,
        };
        let reach = reaches(&obstacles, r);
        let every = [f64::INFINITY; 4];
        let steps = [
            DVec2::ZERO,
            DVec2::new(0.03, -0.02),
            DVec2::new(-0.2, 0.15),
            DVec2::new(0.5, 0.6),
        ];
        let (mut untouched, mut touched) = (0, 0);
        for i in 0..=300 {
            for j in 0..=300 {
                let x = DVec2::new(-1.5 + 0.01 * i as f64, -1.2 + 0.009 * j as f64);
                for step in steps {
                    let kept = around.keep_out(x, x - step, &reach);
                    let everywhere = around.keep_out(x, x - step, &every);
                    assert_eq!(kept, everywhere, "keep_out at {x} by {step}");
                    let placed = |reach: &[f64]| {
                        let (mut end, mut surfaces) = (x, vec![]);
                        let contacts = place(
                            &mut end,
                            x - step,
                            step,
                            &obstacles,
                            (reach, &[]),
                            r,
                            Some(-1.0),
                            |_, t| surfaces.push((t.obstacle, t.normal, t.depth)),
                        );
                        (contacts, end, surfaces)
                    };
                    let shortcut = placed(&reach);
                    assert_eq!(shortcut, placed(&every), "{x} by {step}");
                    if shortcut.0 > 0 {
                        touched += 1;
                    } else {
                        untouched += 1;
                    }
                }
            }
        }
        // Both kinds are there in number: the grid holds the shapes, their edges and the space
        // between them.
        assert!(
            untouched > 100_000 && touched > 20_000,
            "{untouched} {touched}"
        );
    }

    /// The pair solve's hold puts a pushed particle back on the side it was pushed from: a
    /// particle near, on or just inside a disc of radius 2r, a turned box 4r thick, a plank of
    /// no thickness (near it only) and a thick one, a disc of radius r and a turned box r
    /// thick, pushed by up to 3r past the middle, across the line, or through the thin shapes
    /// and clear of their far sides, is put out no nearer than r to the tangent at the surface
    /// point nearest its start, on the start's side. By the nearest surface it went out the
    /// far side (a light particle under a heavy one through a plank or a thin box:
    /// tests/frame_step_contact.rs).
    #[test]
    fn the_pair_solves_hold_puts_a_pushed_particle_back_on_its_side() {
        let r = 0.01;
        let obstacles = [
            Placed::at(Shape::Circle { radius: 0.02 }, DVec2::new(0.0, 0.0), 0.0),
            Placed::at(
                Shape::Box {
                    half: DVec2::new(0.2, 0.02),
                },
                DVec2::new(1.0, 0.0),
                0.4,
            ),
            Placed::at(
                Shape::Segment {
                    a: DVec2::new(-0.3, 0.0),
                    b: DVec2::new(0.3, 0.1),
                    thickness: 0.0,
                },
                DVec2::new(2.0, 0.0),
                0.0,
            ),
            Placed::at(
                Shape::Segment {
                    a: DVec2::new(-0.3, 0.0),
                    b: DVec2::new(0.3, 0.0),
                    thickness: 0.004,
                },
                DVec2::new(3.0, 0.0),
                -0.3,
            ),
            // Thinner than the push: a disc of radius r and a turned box r thick, pushed
            // through from side to side.
            Placed::at(Shape::Circle { radius: r }, DVec2::new(4.0, 0.0), 0.0),
            Placed::at(
                Shape::Box {
                    half: DVec2::new(0.2, 0.5 * r),
                },
                DVec2::new(5.0, 0.0),
                0.4,
            ),
        ];
        let mut tried = 0;
        for o in &obstacles {
            let around = Surroundings {
                obstacles: std::slice::from_ref(o),
                ground: None,
                settings: Some(ContactSettings {
                    radius: r,
                    ..Default::default()
                }),
                reactions: None,
            };
            let reach = reaches(std::slice::from_ref(o), r);
            for k in 0..12 {
                let dir = DVec2::from_angle(k as f64 * std::f64::consts::TAU / 12.0);
                // A start inside (an explicit step's update carried the particle 1 mm in
                // before the pair pass), on the surface, and out.
                for gap in [-0.1 * r, 0.0, 0.5 * r, r, 1.5 * r] {
                    let line =
                        matches!(o.shape, Shape::Segment { thickness, .. } if thickness == 0.0);
                    if gap <= 0.0 && line {
                        // A start on a line has no side of its own.
                        continue;
                    }
                    // A start `gap` out from the surface point nearest a point near the middle.
                    let (d, n) = o.distance(o.pose.center + dir * 0.002);
                    let surface = o.pose.center + dir * 0.002 - n * d;
                    let from = surface + n * gap;
                    for push in [0.5, 0.9, 1.5, 2.5, 3.0] {
                        // Pushed toward and past the middle (not onto a disc's centre, where
                        // every way out is the nearest), by up to 3r beyond the line.
                        let p = from - n * (gap + push * r);
                        let kept = around.keep_out(p, from, &reach);
                        let out = (kept - surface).dot(n);
                        assert!(
                            out >= r - 1e-9,
                            "obstacle at {}: pushed from {from} to {p}, kept at {kept}, \
                             {out} m out on the start's side",
                            o.pose.center
                        );
                        tried += 1;
                    }
                }
            }
        }
        assert_eq!(tried, (5 * 5 + 3) * 12 * 5);
    }
}
