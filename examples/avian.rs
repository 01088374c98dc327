//! Rigid bodies and soft ones in one world: the `crates` scene (a net hung by its ends, three
//! avian2d bodies falling into it, a gas-filled ball on top) run headless for three seconds,
//! with each body's height printed as it goes, and the impulses the particles gave them.
//!
//! `cargo run --release --example avian`
//!
//! The same in your own app: add avian's `PhysicsPlugins` and hooke's `HookeAvianPlugin` beside
//! `SimPlugin`, and spawn avian's bodies as avian's documentation says; hooke's particles then
//! collide with their colliders, and the dynamic ones feel the particles.

use avian2d::prelude::*;
use bevy::prelude::{Entity, With};
use hooke::scene::LoadedScene;
use hooke::sim::avian::Coupling;

fn main() -> Result<(), String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/crates.ron");
    let loaded = LoadedScene::read(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    // The scene has bodies, so the app comes with avian's plugins, coupled.
    let mut app = hooke::running_app(&loaded)?;
    let dt = app.world().resource::<hooke::sim::SimParams>().dt;
    let steps_per_print = (0.25 / dt).round() as u64;
    println!("  t (s)   body heights (m)                      impulses from the particles (N·s)");
    for k in 1..=12 {
        hooke::sim::advance(app.world_mut(), steps_per_print);
        let world = app.world_mut();
        let mut heights: Vec<(Entity, f32)> = world
            .query_filtered::<(Entity, &Position), With<Collider>>()
            .iter(world)
            .map(|(e, p)| (e, p.0.y))
            .collect();
        heights.sort_by_key(|(e, _)| *e);
        let heights: Vec<String> = heights.iter().map(|(_, y)| format!("{y:6.3}")).collect();
        let pushed: f32 = world
            .resource::<Coupling>()
            .impulses
            .iter()
            .map(|(_, j)| j.length())
            .sum();
        println!(
            "{:7.2}   {:<38}{pushed:.4}",
            k as f64 * steps_per_print as f64 * dt,
            heights.join(" ")
        );
    }
    Ok(())
}
