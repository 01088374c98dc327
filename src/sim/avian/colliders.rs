//! avian's colliders as hooke's obstacles: each shape in hooke's terms, and the colliders near
//! the particles gathered for the tick.

use super::{BodyRead, Coupling, Motion};
use crate::sim::obstacles::Obstacles;
use crate::sim::params::SimParams;
use crate::sim::solver::Solver;
use crate::solver::contact::reaction::{mean_decay, mean_gain};
use crate::solver::{Inertia, Placed, Polygon, Pose, Shape};
use avian2d::parry::shape::TypedShape;
use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;

/// Why a collider's shape does not act on the particles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShapeProblem(pub String);

impl std::fmt::Display for ShapeProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// A collider's shape (scaled as avian scales it) as hooke's shapes, each with its offset and
/// turn in the collider's frame: one for a simple shape, one per part of a compound.
/// Circles, rectangles, capsules, segments, triangles and convex polygons map exactly; a
/// rounded shape, a polyline, a mesh, a height field, a half-space or voxels do not, and the
/// error names it.
pub fn obstacle_shapes(collider: &Collider) -> Result<Vec<(Shape, DVec2, f64)>, ShapeProblem> {
    let mut out = vec![];
    add_shape(
        collider.shape_scaled().as_typed_shape(),
        DVec2::ZERO,
        0.0,
        &mut out,
    )?;
    Ok(out)
}

fn add_shape(
    shape: TypedShape,
    offset: DVec2,
    turn: f64,
    out: &mut Vec<(Shape, DVec2, f64)>,
) -> Result<(), ShapeProblem> {
    let v = |p: Vec2| p.as_dvec2();
    let polygon = |corners: &[DVec2]| {
        Polygon::new(corners)
            .map(Shape::Polygon)
            .map_err(|e| ShapeProblem(format!("a convex polygon hooke cannot take: {e}")))
    };
    let shape = match shape {
        TypedShape::Ball(b) => Shape::Circle {
            radius: b.radius as f64,
        },
        TypedShape::Cuboid(c) => Shape::Box {
            half: v(c.half_extents),
        },
        TypedShape::Capsule(c) => Shape::Segment {
            a: v(c.segment.a),
            b: v(c.segment.b),
            thickness: c.radius as f64,
        },
        TypedShape::Segment(s) => Shape::Segment {
            a: v(s.a),
            b: v(s.b),
            thickness: 0.0,
        },
        TypedShape::Triangle(t) => polygon(&[v(t.a), v(t.b), v(t.c)])?,
        TypedShape::ConvexPolygon(p) => {
            let corners: Vec<DVec2> = p.points().iter().map(|&c| v(c)).collect();
            polygon(&corners)?
        }
        TypedShape::Compound(c) => {
            for (pose, part) in c.shapes() {
                let (at, angle) = (v(pose.translation), pose.rotation.angle() as f64);
                let at = offset + DVec2::from_angle(turn).rotate(at);
                add_shape(part.as_typed_shape(), at, turn + angle, out)?;
            }
            return Ok(());
        }
        other => {
            let name = format!("{other:?}");
            let name = name.split('(').next().unwrap_or("this shape").to_string();
            return Err(ShapeProblem(format!(
                "hooke's particles collide with circles, rectangles, capsules, segments, \
                 triangles, convex polygons and compounds of them, not a {name}"
            )));
        }
    };
    out.push((shape, offset, turn));
    Ok(())
}

/// The particles' bounds, grown by the contact radius and by what the fastest can travel in a
/// step, or `None` without particles.
fn particle_bounds(solver: &Solver, params: &SimParams) -> Option<(DVec2, DVec2)> {
    let (x, v) = (solver.x(), solver.v());
    let first = *x.first()?;
    let (mut lo, mut hi) = (first, first);
    let mut fastest: f64 = 0.0;
    for (p, u) in x.iter().zip(v) {
        lo = lo.min(*p);
        hi = hi.max(*p);
        fastest = fastest.max(u.length());
    }
    let r = params.contact.map_or(0.0, |c| c.radius);
    // A step's travel, and a step of gravity's, twice over for a margin.
    let reach = r + 2.0 * (fastest * params.dt + params.gravity.length() * params.dt * params.dt);
    let grow = DVec2::splat(reach.max(1e-6));
    (lo.is_finite() && hi.is_finite()).then_some((lo - grow, hi + grow))
}

/// Adds avian's colliders near the particles to this tick's obstacles.
#[allow(clippy::too_many_arguments)]
pub(super) fn gather(
    mut obstacles: ResMut<Obstacles>,
    mut coupling: ResMut<Coupling>,
    solver: Res<Solver>,
    params: Res<SimParams>,
    gravity: Res<Gravity>,
    substeps: Res<SubstepCount>,
    colliders: Query<(Entity, &Collider, &Position, &Rotation, Option<&ColliderOf>)>,
    bodies: Query<BodyRead>,
) {
    // A dynamic body's mean velocity over avian's coming step without the particles: in each
    // of its n substeps avian damps the velocity by 1/(1 + c hₛ), adds g hₛ and moves by it,
    // a mean of v ρ + g γ ([`mean_decay`] ρ, [`mean_gain`] γ: v + g dt (n + 1)/(2n)
    // undamped). The particles meet it where avian will take it.
    let (n, dt) = (substeps.0.max(1), params.dt);
    let g = gravity.0.as_dvec2();
    coupling.colliders = 0;
    // The steps note the contacts for the bodies while there are any.
    let feel = !bodies.is_empty();
    if obstacles.feel != feel {
        obstacles.feel = feel;
    }
    let Some((lo, hi)) = particle_bounds(&solver, &params) else {
        return;
    };
    // Every collider, each tested by its shapes' bounds against the particles' (not avian's
    // collider tree: it is built in avian's step, after hooke's, so a body spawned this tick
    // was not in it yet and the particles fell into it for a step). In the entities' order,
    // so that a run repeats bit for bit.
    let mut all: Vec<_> = colliders.iter().collect();
    all.sort_by_key(|c| c.0);
    for (e, collider, position, rotation, of) in all {
        let shapes = match obstacle_shapes(collider) {
            Ok(s) => s,
            Err(why) => {
                if !coupling.skipped.iter().any(|(s, _)| *s == e) {
                    warn!("collider {e} does not touch hooke's particles: {why}");
                    coupling.skipped.push((e, why));
                }
                continue;
            }
        };
        let (center, angle) = (position.0.as_dvec2(), rotation.as_radians() as f64);
        let placed_at = |(shape, offset, turn): &(Shape, DVec2, f64)| {
            Placed::at(
                *shape,
                center + DVec2::from_angle(angle).rotate(*offset),
                angle + turn,
            )
        };
        let near = shapes.iter().any(|s| {
            let p = placed_at(s);
            let reach = DVec2::splat(p.bound());
            let (a, b) = (p.pose.center - reach, p.pose.center + reach);
            a.x <= hi.x && a.y <= hi.y && b.x >= lo.x && b.y >= lo.y
        });
        if !near {
            continue;
        }
        let body = of.map_or(e, |o| o.body);
        // The collider's motion is its body's (a static body, or a collider without one,
        // stands still).
        let mut motion = Motion {
            com: position.0.as_dvec2(),
            linear: DVec2::ZERO,
            angular: 0.0,
        };
        // How the body answers the particles' impulses: a dynamic one by its mass, the others
        // as walls.
        let mut inertia = Inertia::default();
        if let Ok((kind, body_motion, (mass, turning, scale), (linear, angular), _)) =
            bodies.get(body)
            && !kind.is_static()
        {
            motion = Motion::of(body_motion);
            if kind.is_dynamic() {
                let linear = linear.map_or(0.0, |d| d.0 as f64);
                let angular = angular.map_or(0.0, |d| d.0 as f64);
                let fall = g * (scale.map_or(1.0, |s| s.0 as f64) * mean_gain(linear, n, dt));
                motion.linear = motion.linear * mean_decay(linear, n, dt) + fall;
                motion.angular *= mean_decay(angular, n, dt);
                inertia = Inertia {
                    inverse_mass: mass.map_or(0.0, |m| m.inverse() as f64),
                    inverse_inertia: turning.map_or(0.0, |i| i.inverse() as f64),
                    center_of_mass: motion.com,
                    body: body.to_bits(),
                    substeps: n,
                    linear_damping: linear,
                    angular_damping: angular,
                };
            }
        }
        for (shape, offset, turn) in shapes {
            let at = center + DVec2::from_angle(angle).rotate(offset);
            let pose = Pose {
                center: at,
                angle: angle + turn,
                velocity: motion.velocity_at(at),
                angular_velocity: motion.angular,
            };
            obstacles.add_for_tick(e, Placed { shape, pose }, inertia);
        }
        coupling.colliders += 1;
    }
}
