//! What hooke gives back to avian each tick: the contacts' impulses and the attachments'
//! pulls, onto the dynamic bodies through avian's [`Forces`]; and the attached particles put at
//! their bodies' points before the step.

use super::{BodyMotion, Coupling, Motion, centre_of_mass};
use crate::sim::components::{Kinematic, Position as ParticlePosition, SolverIndex, Velocity};
use crate::sim::obstacles::Obstacles;
use crate::sim::params::SimParams;
use crate::sim::solver::Solver;
use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Ties a particle (the entity this is on) to a point of a rigid body, two ways: each step the
/// particle starts at the point with the point's velocity, held kinematic (its mass is then the
/// body's to carry), and the body feels the pull of the particle's springs, at the point.
///
/// ```
/// # use bevy::math::{DVec2, Vec2};
/// # use bevy::prelude::*;
/// # use hooke::sim::{Particle, Position};
/// # use hooke::sim::avian::Attachment;
/// # let mut world = World::new();
/// # let crate_body = world.spawn_empty().id();
/// // The rope's last particle holds the crate by the middle of its top side.
/// world.spawn((
///     Particle,
///     Position(DVec2::new(0.5, 0.4)),
///     Attachment { body: crate_body, anchor: Vec2::new(0.0, 0.1) },
/// ));
/// ```
#[derive(Component, Debug, Clone, Copy, PartialEq)]
#[require(Kinematic)]
pub struct Attachment {
    /// The rigid body's entity.
    pub body: Entity,
    /// The point, in the body's own frame (about its [`Position`], unrotated), m.
    pub anchor: Vec2,
}

/// Puts each attached particle at its body's point, moving with it.
pub(super) fn follow(
    mut particles: Query<(&Attachment, &mut ParticlePosition, &mut Velocity)>,
    bodies: Query<BodyMotion>,
) {
    for (a, mut x, mut u) in &mut particles {
        let Ok(body) = bodies.get(a.body) else {
            continue;
        };
        let (at, turn, ..) = body;
        let p = (at.0 + *turn * a.anchor).as_dvec2();
        let pv = Motion::of(body).velocity_at(p);
        if x.0 != p {
            x.0 = p;
        }
        if u.0 != pv {
            u.0 = pv;
        }
    }
}

/// The pull of the springs on each of the particles `ends` (solver indices, sorted), at the
/// state's positions, N: each stretched spring pulls toward its other end. One pass over the
/// springs for all the attachments, each end found by a binary search.
fn pulls_on(solver: &Solver, ends: &[u32]) -> Vec<DVec2> {
    let x = solver.x();
    let mut f = vec![DVec2::ZERO; ends.len()];
    for s in solver.springs() {
        let (a, b) = (ends.binary_search(&s.a), ends.binary_search(&s.b));
        if a.is_err() && b.is_err() {
            continue;
        }
        let d = x[s.b as usize] - x[s.a as usize];
        let l = d.length();
        if l == 0.0 {
            continue;
        }
        // On a, toward b when stretched; on b, the opposite.
        let on_a = d * (s.k * (l - s.rest) / l);
        if let Ok(k) = a {
            f[k] += on_a;
        }
        if let Ok(k) = b {
            f[k] -= on_a;
        }
    }
    f
}

/// Gives each dynamic body minus the impulses its colliders gave the particles this tick, and
/// its attachments' pulls over the tick.
#[allow(clippy::too_many_arguments)]
pub(super) fn push(
    mut obstacles: ResMut<Obstacles>,
    mut coupling: ResMut<Coupling>,
    solver: Res<Solver>,
    params: Res<SimParams>,
    attached: Query<(Entity, &Attachment, &SolverIndex)>,
    owners: Query<&ColliderOf>,
    kinds: Query<&RigidBody>,
    mut forces: Query<(Forces, &ComputedCenterOfMass)>,
) {
    coupling.impulses.clear();
    let reactions = obstacles.bypass_change_detection().take_reactions();
    let mut totals: Vec<(Entity, DVec2, f64)> = vec![];
    let mut add =
        |body: Entity, impulse: DVec2, moment: f64| match totals.iter_mut().find(|t| t.0 == body) {
            Some(t) => {
                t.1 += impulse;
                t.2 += moment;
            }
            None => totals.push((body, impulse, moment)),
        };
    for (owner, r) in obstacles.entities().iter().zip(&reactions) {
        if r.contacts == 0 {
            continue;
        }
        let body = owners.get(*owner).map_or(*owner, |o| o.body);
        add(body, r.impulse, r.moment);
    }
    if !attached.is_empty() {
        // Each attached particle's solver index (not yet packed: not pulling yet).
        let mut ends: Vec<(u32, Entity)> = attached
            .iter()
            .filter(|(_, _, i)| (i.0 as usize) < solver.x().len())
            .map(|(_, a, i)| (i.0, a.body))
            .collect();
        ends.sort_unstable_by_key(|(i, _)| *i);
        let indices: Vec<u32> = ends.iter().map(|(i, _)| *i).collect();
        let pulls = pulls_on(&solver, &indices);
        for ((i, body), pull) in ends.into_iter().zip(pulls) {
            let at = solver.x()[i as usize];
            let j = pull * params.dt;
            add(body, j, at.perp_dot(j));
        }
    }
    for (body, impulse, moment) in totals {
        if !kinds.get(body).is_ok_and(|k| k.is_dynamic()) {
            continue;
        }
        let Ok((mut f, com)) = forces.get_mut(body) else {
            continue;
        };
        let c = centre_of_mass(f.position(), f.rotation(), Some(com));
        f.apply_linear_impulse(impulse.as_vec2());
        f.apply_angular_impulse((moment - c.perp_dot(impulse)) as f32);
        coupling.impulses.push((body, impulse.as_vec2()));
    }
}
