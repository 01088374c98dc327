//! Materials from code: a gas-filled ball with dashpot springs, dropped on the ground.
//!
//! A ring of particles joined neighbour to neighbour by springs, each with a `Dashpot`, and a
//! `PressureBody` entity that fills the ring with gas. The gas pushes every edge outward with
//! pressure nRT / area, so the ring inflates until the springs' pull balances it; the
//! dashpots damp its ringing and leave its fall alone. The example drops the ball under each
//! integrator and prints its area after 2 s beside the balance in closed form (the ball sags a
//! little on the ground, so a little less; XPBD at its default 10 substeps of one sweep is
//! softer than its springs' stiffness at a frame's step, so its ball is bigger), and its lowest
//! point: a few micrometres under the ground for the explicit methods, whose ground acts on
//! where a step starts (the course's step), and on it for the others.
//!
//! `cargo run --example balloon`

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::sim::{
    Dashpot, Integrator, Mass, Particle, Position, PressureBody, SimParams, Solver, Spring, advance,
};
use std::f64::consts::{PI, TAU};

const SEGMENTS: usize = 24;
const RADIUS: f64 = 0.1;
const STIFFNESS: f64 = 1e4;
const NRT: f64 = 20.0;

/// Spawns the ball and returns its particles.
fn spawn_ball(world: &mut World, center: DVec2) -> Vec<Entity> {
    let ring: Vec<Entity> = (0..SEGMENTS)
        .map(|i| {
            let at = center + DVec2::from_angle(TAU * i as f64 / SEGMENTS as f64) * RADIUS;
            world.spawn((Particle, Position(at), Mass(0.05))).id()
        })
        .collect();
    let rest = 2.0 * RADIUS * (PI / SEGMENTS as f64).sin();
    for i in 0..SEGMENTS {
        let spring = Spring::new(ring[i], ring[(i + 1) % SEGMENTS], rest, STIFFNESS);
        world.spawn((spring, Dashpot(2.0)));
    }
    world.spawn(PressureBody {
        particles: ring.clone(),
        nrt: NRT,
    });
    ring
}

/// The area a free regular N-gon of these springs and this gas settles at: its side s solves
/// nRT = N k s (s − L₀) / 2, where the pressure on each corner balances the springs' pull.
fn balance_area() -> f64 {
    let n = SEGMENTS as f64;
    let rest = 2.0 * RADIUS * (PI / n).sin();
    let side = (rest + (rest * rest + 8.0 * NRT / (n * STIFFNESS)).sqrt()) / 2.0;
    n * side * side / (4.0 * (PI / n).tan())
}

/// The area enclosed by the ring's particles, by the shoelace formula.
fn area(x: &[DVec2]) -> f64 {
    let n = x.len();
    (0..n)
        .map(|i| x[i].perp_dot(x[(i + 1) % n]))
        .sum::<f64>()
        .abs()
        / 2.0
}

fn main() {
    println!("balance in closed form: {:.5} m²", balance_area());
    println!("integrator            dt        area after 2 s   lowest point");
    for integrator in Integrator::ALL {
        let mut app = hooke::headless_app();
        let world = app.world_mut();
        spawn_ball(world, DVec2::new(0.5, 0.4));
        // The large-step methods at a frame's step, the explicit ones at the app's default.
        let dt = if integrator.unconditionally_stable() {
            1.0 / 60.0
        } else {
            1e-4
        };
        {
            let mut params = world.resource_mut::<SimParams>();
            params.paused = false;
            params.integrator = integrator;
            params.dt = dt;
            params.damping = 1.0;
        }
        advance(world, (2.0 / dt).round() as u64);
        let x = world.resource::<Solver>().x();
        let lowest = x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        println!(
            "{:<20}  {dt:<8.2e}  {:.5} m²       {:+.3} mm",
            integrator.cli_name(),
            area(x),
            lowest * 1e3
        );
    }
}
