//! A scene's rigid bodies ([`BodyDef`]) as avian2d entities, and back: what the `avian`
//! feature loads and saves. Without the feature a scene with bodies is refused by its
//! validation ([`super::validate()`]), so nothing here runs.

use super::format::BodyDef;
use bevy::math::DVec2;
use bevy::prelude::*;

/// The rigid bodies' collider shape, as avian builds it, or why not.
#[cfg(feature = "avian")]
pub fn collider(def: &BodyDef) -> Result<avian2d::prelude::Collider, String> {
    use crate::solver::Shape;
    use avian2d::prelude::Collider;
    let placed = def.shape.placed()?;
    let v = |p: DVec2| p.as_vec2();
    Ok(match placed.shape {
        Shape::Circle { radius } => Collider::circle(radius as f32),
        Shape::Box { half } => Collider::rectangle(2.0 * half.x as f32, 2.0 * half.y as f32),
        Shape::Segment { a, b, thickness } if thickness > 0.0 => {
            Collider::capsule_endpoints(thickness as f32, v(a), v(b))
        }
        Shape::Segment { a, b, .. } => Collider::segment(v(a), v(b)),
        Shape::Polygon(p) => Collider::convex_hull(p.corners().iter().map(|&c| v(c)).collect())
            .ok_or("the corners make no convex polygon")?,
    })
}

/// Despawns every rigid body and spawns the scene's, in its order, under `gravity`.
#[cfg(feature = "avian")]
pub fn replace_bodies(world: &mut World, bodies: &[BodyDef], gravity: DVec2) {
    use avian2d::prelude::*;
    super::despawn::despawn_all::<With<RigidBody>>(world);
    // One gravity for both engines from the start (the coupling keeps them one after).
    if let Some(mut g) = world.get_resource_mut::<Gravity>() {
        g.0 = gravity.as_vec2();
    }
    for def in bodies {
        spawn_body(world, def);
    }
}

/// Spawns one rigid body; a shape that makes no collider (which validation refuses first) is
/// left out.
#[cfg(feature = "avian")]
pub fn spawn_body(world: &mut World, def: &BodyDef) -> Option<Entity> {
    use avian2d::prelude::*;
    let (Ok(collider), Ok(placed)) = (collider(def), def.shape.placed()) else {
        return None;
    };
    let kind = if def.fixed {
        RigidBody::Static
    } else {
        RigidBody::Dynamic
    };
    // The order they were made in, as particles and obstacles keep it, for a save to keep.
    let order = world
        .get_resource_mut::<crate::sim::components::Serials>()
        .map_or(0, |mut s| s.next_serial());
    let body = world.spawn((
        crate::sim::components::CreationOrder(order),
        kind,
        collider,
        Mass(def.mass as f32),
        Position(placed.pose.center.as_vec2()),
        Rotation::radians(placed.pose.angle as f32),
        LinearVelocity(DVec2::from(def.velocity).as_vec2()),
        AngularVelocity(def.spin as f32),
    ));
    Some(body.id())
}

/// Without the feature there are no bodies to replace.
#[cfg(not(feature = "avian"))]
pub fn replace_bodies(_world: &mut World, _bodies: &[BodyDef], _gravity: DVec2) {}

/// The world's rigid bodies of one shape each, as a scene writes them, in the order they were
/// made; a body of a compound or another shape is left out (a scene cannot say it).
#[cfg(feature = "avian")]
pub fn body_defs(world: &mut World) -> Vec<BodyDef> {
    use crate::sim::avian::obstacle_shapes;
    use crate::solver::Placed;
    use avian2d::prelude::*;
    let mut all: Vec<((u64, Entity), BodyDef)> = world
        .query::<(
            Entity,
            Option<&crate::sim::components::CreationOrder>,
            &RigidBody,
            &Collider,
            &Position,
            &Rotation,
            Option<&Mass>,
            Option<&LinearVelocity>,
            Option<&AngularVelocity>,
        )>()
        .iter(world)
        .filter_map(|(e, order, kind, collider, at, turn, mass, v, w)| {
            let shapes = obstacle_shapes(collider).ok()?;
            let [(shape, offset, angle)] = shapes[..] else {
                return None;
            };
            if offset != DVec2::ZERO || angle != 0.0 {
                return None;
            }
            let placed = Placed::at(shape, at.0.as_dvec2(), turn.as_radians() as f64);
            let def = BodyDef {
                shape: super::format::ObstacleDef::from_placed(&placed),
                mass: mass.map_or(1.0, |m| m.0 as f64),
                velocity: v.map_or((0.0, 0.0), |v| (v.0.x as f64, v.0.y as f64)),
                spin: w.map_or(0.0, |w| w.0 as f64),
                fixed: kind.is_static(),
            };
            // Bodies made elsewhere (without an order) after the scene's, by entity.
            Some(((order.map_or(u64::MAX, |o| o.0), e), def))
        })
        .collect();
    all.sort_by_key(|(key, _)| *key);
    all.into_iter().map(|(_, d)| d).collect()
}

/// Without the feature there are no bodies.
#[cfg(not(feature = "avian"))]
pub fn body_defs(_world: &mut World) -> Vec<BodyDef> {
    vec![]
}
