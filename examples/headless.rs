//! A test-style headless app: build a small scene from entities, step it, print the energy.
//!
//! `cargo run --example headless`

use bevy::math::DVec2;
use hooke::sim::{JoinWithin, Particle, Pinned, Position, SimParams, Solver, advance};

fn main() {
    // MinimalPlugins + SimPlugin: no window, no GPU.
    let mut app = hooke::headless_app();
    let world = app.world_mut();
    world.resource_mut::<SimParams>().paused = false;

    // A pinned particle and a short chain under it, spawned like any Bevy entity; each new
    // particle is joined to those within 0.15 m (the app's click rule).
    world.spawn((Particle, Position(DVec2::new(0.5, 0.9)), Pinned));
    for i in 1..=5 {
        let p = world
            .spawn((Particle, Position(DVec2::new(0.5 + 0.1 * i as f64, 0.9))))
            .id();
        world.commands().queue(JoinWithin {
            particle: p,
            radius: 0.15,
            stiffness: 1e4,
        });
        world.flush();
    }

    // Pack the entities into the solver now, to read the state before the first step.
    hooke::sim::pack(world).expect("a SimPlugin world");
    let gravity = world.resource::<SimParams>().gravity;
    for second in 0..=5 {
        if second > 0 {
            // 10,000 steps of the assignment's dt = 1e-4 s, through the app's fixed ticks.
            advance(world, 10_000);
        }
        let solver = world.resource::<Solver>();
        let e = solver.energy(gravity);
        println!(
            "t = {second} s: {} particles, {} springs, energy {:.4} J (kinetic {:.4}, gravity {:.4}, springs {:.4})",
            solver.particle_count(),
            solver.spring_count(),
            e.total(),
            e.kinetic,
            e.potential_gravity,
            e.potential_springs
        );
    }
}
