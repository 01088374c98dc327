//! Observed order of accuracy and long-run energy behaviour of every integrator, without
//! damping and ground.

mod common;
use bevy::math::DVec2;
use common::*;
use hooke::scene::Scene;
use hooke::sim::{Integrator, SimParams};

const T: f64 = 1.0;
const CHECKPOINTS: u64 = 50;

/// One free particle on a spring (k = 100, m = 1: ω = 10) to a pinned one, displaced 0.1.
fn oscillator(integrator: Integrator, dt: f64) -> Scene {
    let mut scene = bare_scene(integrator, dt);
    scene.particles = vec![particle(0.0, 0.5, true), particle(0.6, 0.5, false)];
    scene.springs = vec![spring(0, 1, 100.0, 0.5)];
    scene
}

/// Positions and velocities at the checkpoints t = j T / CHECKPOINTS.
fn trajectory(scene: Scene) -> Vec<(Vec<DVec2>, Vec<DVec2>)> {
    let steps = (T / scene.dt).round() as u64;
    assert_eq!(steps % CHECKPOINTS, 0);
    let mut app = app_with(scene);
    (0..CHECKPOINTS)
        .map(|_| {
            step(&mut app, steps / CHECKPOINTS);
            let s = solver(&app);
            (s.x().to_vec(), s.v().to_vec())
        })
        .collect()
}

/// The largest phase-space distance between two trajectories (velocities scaled by 1/ω).
fn max_error(a: &[(Vec<DVec2>, Vec<DVec2>)], b: &[(Vec<DVec2>, Vec<DVec2>)], omega: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for ((xa, va), (xb, vb)) in a.iter().zip(b) {
        for i in 0..xa.len() {
            let e = (xa[i] - xb[i]).length_squared() + ((va[i] - vb[i]) / omega).length_squared();
            worst = worst.max(e.sqrt());
        }
    }
    worst
}

fn exact_oscillator() -> Vec<(Vec<DVec2>, Vec<DVec2>)> {
    let omega: f64 = 10.0;
    (1..=CHECKPOINTS)
        .map(|j| {
            let t = j as f64 * T / CHECKPOINTS as f64;
            let x = DVec2::new(0.5 + 0.1 * (omega * t).cos(), 0.5);
            let v = DVec2::new(-0.1 * omega * (omega * t).sin(), 0.0);
            (vec![DVec2::new(0.0, 0.5), x], vec![DVec2::ZERO, v])
        })
        .collect()
}

/// The orders observed between successive halvings of dt.
fn observed_orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// dt, dt/2, dt/4, dt/8, from a start in each method's asymptotic range on problems with
/// ω up to `omega`.
fn dts(integrator: Integrator, omega: f64) -> Vec<f64> {
    let stiff = omega > 20.0;
    let start = match integrator {
        // Explicit Euler grows the amplitude by e^(h ω² T / 2) and implicit Euler shrinks it by
        // as much: on the network (ω ≈ 50) they need a small step to be in their asymptotic range.
        Integrator::ExplicitEuler => 1e-4,
        Integrator::ImplicitEuler if stiff => 1e-4,
        Integrator::SymplecticEuler | Integrator::ImplicitEuler => 1e-3,
        Integrator::VelocityVerlet if stiff => 5e-3,
        Integrator::VelocityVerlet => 1e-2,
        Integrator::Rk4 if stiff => 2e-3,
        Integrator::Rk4 => 2e-2,
        // Backward Euler's objective, minimised by 10 iterations: implicit Euler's range.
        Integrator::ProjectiveDynamics if stiff => 1e-4,
        Integrator::ProjectiveDynamics => 1e-3,
        // Ten substeps: the range of a ten times smaller step.
        Integrator::Xpbd if stiff => 1e-3,
        Integrator::Xpbd => 1e-2,
        // Backward Euler's objective by vertex block descent: implicit Euler's range.
        Integrator::Vbd if stiff => 1e-4,
        Integrator::Vbd => 1e-3,
        // Second order and dissipative: velocity Verlet's range.
        Integrator::Bdf2 if stiff => 5e-3,
        Integrator::Bdf2 => 1e-2,
    };
    (0..4).map(|i| start / f64::powi(2.0, i)).collect()
}

fn expected_order(integrator: Integrator) -> f64 {
    match integrator {
        Integrator::ExplicitEuler
        | Integrator::SymplecticEuler
        | Integrator::ImplicitEuler
        | Integrator::ProjectiveDynamics
        | Integrator::Xpbd
        | Integrator::Vbd => 1.0,
        Integrator::VelocityVerlet | Integrator::Bdf2 => 2.0,
        Integrator::Rk4 => 4.0,
    }
}

fn assert_order(integrator: Integrator, what: &str, errors: &[f64]) {
    let orders = observed_orders(errors);
    let p = expected_order(integrator);
    let shown: Vec<String> = errors.iter().map(|e| format!("{e:.3e}")).collect();
    println!("{integrator} on {what}: errors {shown:?}, orders {orders:.3?}");
    for &e in errors {
        assert!(e > 1e-11, "{integrator}: error {e:e} is down at round-off");
    }
    for &o in &orders {
        assert!(
            (o - p).abs() < 0.25 * p.max(1.0),
            "{integrator} on {what}: order {o:.3}, expected {p}"
        );
    }
}

#[test]
fn order_on_a_single_spring_against_the_exact_solution() {
    let exact = exact_oscillator();
    for integrator in Integrator::ALL {
        let errors: Vec<f64> = dts(integrator, 10.0)
            .into_iter()
            .map(|dt| max_error(&trajectory(oscillator(integrator, dt)), &exact, 10.0))
            .collect();
        assert_order(integrator, "a single spring", &errors);
    }
}

#[test]
fn order_on_a_2d_network_against_converged_rk4() {
    // Reference: rk4 at half the smallest step tested, and shown converged: halving it
    // again changes the trajectory by far less than any error measured below.
    let reference = trajectory(network(Integrator::Rk4, 1.25e-5 / 2.0));
    let finer = trajectory(network(Integrator::Rk4, 1.25e-5 / 4.0));
    let omega = 40.0;
    let reference_error = max_error(&reference, &finer, omega);
    println!("reference: rk4 at dt/2 and dt/4 differ by {reference_error:.3e}");
    assert!(
        reference_error < 1e-11,
        "reference not converged: {reference_error:e}"
    );
    for integrator in Integrator::ALL {
        let errors: Vec<f64> = dts(integrator, omega)
            .into_iter()
            .map(|dt| max_error(&trajectory(network(integrator, dt)), &reference, omega))
            .collect();
        assert!(errors.iter().all(|&e| e > 10.0 * reference_error));
        assert_order(integrator, "a 2D network", &errors);
    }
}

fn energy_series(scene: Scene, steps: u64, every: u64) -> Vec<f64> {
    let g = DVec2::from(scene.gravity);
    let mut app = app_with(scene);
    let mut out = vec![solver(&app).energy(g).total()];
    for _ in 0..steps / every {
        step(&mut app, every);
        out.push(solver(&app).energy(g).total());
    }
    assert!(app.world().resource::<SimParams>().damping == 0.0);
    out
}

#[test]
fn symplectic_methods_keep_energy_bounded_without_drift() {
    for integrator in [Integrator::SymplecticEuler, Integrator::VelocityVerlet] {
        let e = energy_series(network(integrator, 1e-3), 100_000, 10);
        let e0 = e[0];
        let dev: Vec<f64> = e.iter().map(|x| (x - e0).abs() / e0.abs()).collect();
        let max_dev = dev.iter().cloned().fold(0.0, f64::max);
        // No drift: the mean deviation over the last tenth equals that over the first tenth.
        let tenth = e.len() / 10;
        let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
        let (early, late) = (mean(&e[1..tenth]), mean(&e[e.len() - tenth..]));
        let drift = (late - early).abs() / e0.abs();
        println!("{integrator}: max |ΔE/E| {max_dev:.2e}, drift {drift:.2e} over 1e5 steps");
        assert!(max_dev < 0.05, "{integrator}: energy error {max_dev}");
        assert!(
            drift < 0.1 * max_dev,
            "{integrator}: drift {drift:e} vs bound {max_dev:e}"
        );
    }
}

#[test]
fn implicit_euler_loses_energy_monotonically() {
    for scene in [
        oscillator(Integrator::ImplicitEuler, 1e-3),
        network(Integrator::ImplicitEuler, 1e-3),
    ] {
        let e = energy_series(scene, 5_000, 1);
        for (n, w) in e.windows(2).enumerate() {
            assert!(
                w[1] <= w[0] + 1e-12 * w[0].abs(),
                "energy rose at step {n}: {w:?}"
            );
        }
        assert!(e[e.len() - 1] < e[0]);
    }
}
