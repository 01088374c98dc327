//! hooke as a Bevy library: particles and springs spawned like any Bevy entity, the click rule
//! as a command, a spring at its current length.

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::sim::*;

#[test]
fn spawn_like_bevy_and_join_by_the_click_rule() {
    let mut app = hooke::headless_app();
    app.world_mut().resource_mut::<SimParams>().paused = false;
    let world = app.world_mut();
    let top = world
        .spawn((Particle, Position(DVec2::new(0.5, 0.9)), Pinned))
        .id();
    let mid = world.spawn((Particle, Position(DVec2::new(0.5, 0.8)))).id();
    let far = world.spawn((Particle, Position(DVec2::new(0.9, 0.2)))).id();
    // Creation order is assigned as they are spawned.
    let order = |w: &World, e: Entity| w.get::<CreationOrder>(e).unwrap().0;
    assert!(order(world, top) < order(world, mid) && order(world, mid) < order(world, far));
    // A spring at the current distance, and the click rule as a command.
    let spring = Spring::at_current_length(world, top, mid, 1e4).unwrap();
    assert!((spring.rest - 0.1).abs() < 1e-12);
    assert!(Spring::at_current_length(world, top, Entity::PLACEHOLDER, 1e4).is_none());
    let new = world
        .spawn((Particle, Position(DVec2::new(0.55, 0.8))))
        .id();
    world.commands().queue(JoinWithin {
        particle: new,
        radius: 0.15,
        stiffness: 1e4,
    });
    world.flush();
    let springs: Vec<Spring> = world.query::<&Spring>().iter(world).copied().collect();
    assert_eq!(
        springs.len(),
        2,
        "joined to top and mid, not far: {springs:?}"
    );
    assert!(springs.iter().all(|s| s.a == new && s.b != far));
    // It simulates: the free ones hang from the pinned one.
    advance(world, 2000);
    let solver = world.resource::<Solver>();
    assert_eq!((solver.particle_count(), solver.spring_count()), (4, 2));
    assert_eq!(solver.x()[0], DVec2::new(0.5, 0.9), "pinned");
    assert!(
        solver.x()[2].y < 0.15,
        "the lone particle fell: {}",
        solver.x()[2]
    );
}
