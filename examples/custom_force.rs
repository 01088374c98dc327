//! A user's own force: wind, through the public external-force input.
//!
//! A system in `FixedUpdate`, ordered before the tick's `PhysicsSystems::Prepare`, writes each
//! particle's `ExternalForce`; the solver adds it wherever it evaluates forces, so every
//! integrator sees it at every stage. The example runs the same rope under each integrator,
//! with and without wind, and prints how far the wind blew its free end.
//!
//! `cargo run --example custom_force`

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::scene::presets;
use hooke::sim::{
    ExternalForce, Integrator, Mass, PhysicsSystems, Position, SimParams, SimPlugin, Solver,
    advance,
};

/// A wind along +x, in m/s² at a height of 1 m (so heavier particles feel more force).
#[derive(Resource)]
struct Wind {
    strength: f64,
}

/// Drag towards the wind's speed would be more physical; a push that grows with height is
/// enough to see. It is recomputed every tick from the particles' positions.
fn blow(wind: Res<Wind>, mut particles: Query<(&Position, &Mass, &mut ExternalForce)>) {
    for (pos, mass, mut force) in &mut particles {
        let f = DVec2::X * (wind.strength * mass.0 * pos.0.y.max(0.0));
        force.set_if_neq(ExternalForce(f));
    }
}

fn free_end(integrator: Integrator, wind: f64) -> DVec2 {
    let rope = presets::resolve("rope").expect("the built-in rope");
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, SimPlugin))
        .insert_resource(Wind { strength: wind })
        .add_systems(FixedUpdate, blow.before(PhysicsSystems::Prepare));
    let world = app.world_mut();
    hooke::scene::load_into_world(world, &rope);
    let mut params = world.resource_mut::<SimParams>();
    params.paused = false;
    params.integrator = integrator;
    if integrator == Integrator::ExplicitEuler {
        params.damping = 20.0; // explicit Euler is stable only through damping
    }
    advance(world, 20_000);
    *world
        .resource::<Solver>()
        .x()
        .last()
        .expect("a rope has an end")
}

fn main() {
    println!("integrator           free end, calm         free end, windy        blown by");
    for integrator in Integrator::ALL {
        let calm = free_end(integrator, 0.0);
        let windy = free_end(integrator, 15.0);
        println!(
            "{:<20} ({:.3}, {:.3})         ({:.3}, {:.3})         {:+.3} m",
            integrator.cli_name(),
            calm.x,
            calm.y,
            windy.x,
            windy.y,
            windy.x - calm.x
        );
    }
}
