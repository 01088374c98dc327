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

/// What the sync makes of each kind of spring edit between ticks, with no particle added or
/// removed: a spring spawned alone is packed, a changed rest length is patched in place, and a
/// spring given another end is packed under its new ends. (The sync finds all three in one
/// scan of the springs' change ticks.) A paused tick writes nothing back, yet a position set
/// while paused is what the solver holds, and the steps after it are written back.
#[test]
fn spring_edits_alone_reach_the_solver() {
    let mut app = hooke::headless_app();
    app.world_mut().resource_mut::<SimParams>().paused = false;
    let world = app.world_mut();
    let at = |x: f64, y: f64| (Particle, Position(DVec2::new(x, y)));
    let a = world.spawn((at(0.5, 0.9), Pinned)).id();
    let b = world.spawn(at(0.5, 0.8)).id();
    let c = world.spawn(at(0.6, 0.8)).id();
    let first = world.spawn(Spring::new(a, b, 0.1, 1e3)).id();
    advance(world, 10);
    let ends = |world: &World| {
        let solver = world.resource::<Solver>();
        let index = |e: Entity| solver.entities().iter().position(|&p| p == e).unwrap() as u32;
        let mut ends: Vec<(u32, u32, f64)> = solver
            .springs()
            .iter()
            .map(|s| (s.a, s.b, s.rest))
            .collect();
        ends.sort_by(|p, q| p.partial_cmp(q).unwrap());
        (ends, [index(a), index(b), index(c)])
    };
    assert_eq!(ends(world).0.len(), 1);
    // A spring spawned alone.
    world.spawn(Spring::new(b, c, 0.1, 1e3));
    advance(world, 1);
    let (got, [ia, ib, ic]) = ends(world);
    assert_eq!(
        got,
        vec![(ia, ib, 0.1), (ib, ic, 0.1)],
        "the new spring is packed"
    );
    // A rest length changed.
    world.get_mut::<Spring>(first).unwrap().rest = 0.05;
    advance(world, 1);
    assert_eq!(
        ends(world).0,
        vec![(ia, ib, 0.05), (ib, ic, 0.1)],
        "patched"
    );
    // An end changed.
    world.get_mut::<Spring>(first).unwrap().b = c;
    advance(world, 1);
    let (got, [ia, ib, ic]) = ends(world);
    assert_eq!(
        got,
        vec![(ia, ic, 0.05), (ib, ic, 0.1)],
        "packed under its new ends"
    );
    // Paused: a position set between ticks reaches the solver and stays in the component.
    world.resource_mut::<SimParams>().paused = true;
    world.get_mut::<Position>(c).unwrap().0 = DVec2::new(0.7, 0.7);
    world.run_schedule(bevy::app::FixedMain);
    world.run_schedule(bevy::app::FixedMain);
    let solver = world.resource::<Solver>();
    assert_eq!(solver.x()[ic as usize], DVec2::new(0.7, 0.7));
    assert_eq!(world.get::<Position>(c).unwrap().0, DVec2::new(0.7, 0.7));
    // Running again, the steps are written back.
    world.resource_mut::<SimParams>().paused = false;
    advance(world, 5);
    let moved = world.resource::<Solver>().x()[ic as usize];
    assert_ne!(moved, DVec2::new(0.7, 0.7));
    assert_eq!(world.get::<Position>(c).unwrap().0, moved);
}

/// The solver core's public paths from before its rooms were made still resolve: the root's
/// re-exports unchanged, the moved modules through deprecated re-exports (a user's build warns
/// and names the new path, and does not break).
#[test]
#[allow(deprecated)]
fn the_core_paths_from_before_its_rooms_still_resolve() {
    use hooke::solver::contact::{ContactSettings, Surroundings};
    use hooke::solver::{material, obstacle, pairs, state, step};
    let _ = (
        std::any::type_name::<ContactSettings>(),
        std::any::type_name::<Surroundings>(),
        std::any::type_name::<state::PackedSpring>(),
        std::any::type_name::<step::Workspace>(),
    );
    assert_eq!(
        std::any::type_name::<material::Materials>(),
        std::any::type_name::<hooke::solver::forces::material::Materials>()
    );
    assert_eq!(
        std::any::type_name::<obstacle::Shape>(),
        std::any::type_name::<hooke::solver::Shape>()
    );
    assert_eq!(
        std::any::type_name::<pairs::Pairs>(),
        std::any::type_name::<hooke::solver::contact::pairs::Pairs>()
    );
}
