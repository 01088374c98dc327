//! Physics against closed-form results, in headless apps.

mod common;
use bevy::math::DVec2;
use common::*;
use hooke::sim::{Force, Integrator, Particle, SimParams, SolverIndex, Spring, Velocity};

/// One free particle on a spring to a pinned one, displaced by `u0` along x. ω² = k/m.
fn oscillator(integrator: Integrator, dt: f64, k: f64, u0: f64) -> bevy::app::App {
    let mut scene = bare_scene(integrator, dt);
    let rest = 0.5;
    scene.particles = vec![particle(0.0, 0.5, true), particle(rest + u0, 0.5, false)];
    scene.springs = vec![spring(0, 1, k, rest)];
    app_with(scene)
}

#[test]
fn symplectic_euler_oscillates_like_the_exact_solution() {
    let (dt, k, u0): (f64, f64, f64) = (1e-4, 1e4, 0.1);
    let omega: f64 = k.sqrt();
    let mut app = oscillator(Integrator::SymplecticEuler, dt, k, u0);
    let mut max_err: f64 = 0.0;
    for n in 1..=10_000u64 {
        step(&mut app, 1);
        let exact = u0 * (omega * n as f64 * dt).cos();
        max_err = max_err.max((pos(&app, 1).x - 0.5 - exact).abs());
    }
    // Symplectic Euler: an O(hω) amplitude wobble plus a phase drift of t·ω·(hω)²/24.
    let h_omega = dt * omega;
    let bound = u0 * (h_omega + 1.0 * omega * h_omega * h_omega / 24.0);
    assert!(
        max_err < bound,
        "max error {max_err:e} over 1 s, bound {bound:e}"
    );
    // And it is not trivially small: it does oscillate (10000 steps = 15.9 periods).
    assert!(pos(&app, 1).y == 0.5);
}

#[test]
fn explicit_euler_energy_grows_as_predicted() {
    // Explicit Euler on x'' = -ω² x scales (ωx, v) by sqrt(1 + h²ω²) per step: the amplitude
    // grows as (1 + h²ω²)^(n/2), the energy as (1 + h²ω²)^n.
    let (dt, k, u0) = (1e-3, 1e4, 0.05);
    let mut app = oscillator(Integrator::ExplicitEuler, dt, k, u0);
    let energy = |app: &bevy::app::App| solver(app).energy(DVec2::ZERO).total();
    let e0 = energy(&app);
    let n = 200;
    step(&mut app, n);
    let growth = (1.0 + dt * dt * k).powf(n as f64 / 2.0);
    let amplitude_ratio = (energy(&app) / e0).sqrt();
    let rel = (amplitude_ratio - growth).abs() / growth;
    assert!(growth > 2.5, "the test should see real growth ({growth})");
    assert!(
        rel < 1e-9,
        "amplitude grew {amplitude_ratio}, predicted {growth}"
    );
}

#[test]
fn hanging_chain_reaches_its_static_extension() {
    // N free particles under a pinned one: total extension m g N (N + 1) / (2k).
    let (n, k, m, g, rest) = (10usize, 1e4, 1.0, 9.8, 0.05);
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.gravity = (0.0, -g);
    scene.damping = 10.0;
    scene.particles = (0..=n)
        .map(|i| particle(0.5, 0.95 - i as f64 * rest, i == 0))
        .collect();
    scene.springs = (0..n).map(|i| spring(i, i + 1, k, rest)).collect();
    let mut app = app_with(scene);
    step(&mut app, 40_000);
    let extension = pos(&app, 0).y - pos(&app, n).y - n as f64 * rest;
    let expected = m * g * (n * (n + 1)) as f64 / (2.0 * k);
    let rel = (extension - expected).abs() / expected;
    assert!(rel < 1e-6, "extension {extension}, expected {expected}");
}

#[test]
fn ground_stops_a_falling_particle() {
    let dt = 1e-4;
    let mut scene = bare_scene(Integrator::SymplecticEuler, dt);
    scene.gravity = (0.0, -9.8);
    scene.ground = Some(0.0);
    scene.particles = vec![particle(0.5, 0.5, false)];
    scene.particles[0].vel = (0.3, 0.0);
    let mut app = app_with(scene);
    let mut min_y = f64::MAX;
    for _ in 0..6000 {
        step(&mut app, 1);
        min_y = min_y.min(pos(&app, 0).y);
    }
    // Impact speed sqrt(2 g h) ≈ 3.13 m/s: it may end one step below the ground, no deeper.
    assert!(min_y >= -dt * 3.2, "went {min_y} below the ground");
    // At rest the contact tests the start-of-step position, so a resting particle alternates
    // between y = 0 and one gravity step below it, y = -g dt².
    let (y, vy) = (pos(&app, 0).y, vel(&app, 0).y);
    let sag = 9.8 * dt * dt;
    assert!(
        y == 0.0 || (y + sag).abs() < 1e-15,
        "rests on the ground: y = {y:e}"
    );
    assert!(
        vy == 0.0 || (vy + 9.8 * dt).abs() < 1e-12,
        "at rest: vy = {vy:e}"
    );
    step(&mut app, 1);
    assert!(
        pos(&app, 0).y == 0.0 || y == 0.0,
        "it is back on the ground every other step"
    );
    assert!(
        vel(&app, 0).x > 0.29,
        "slides on: the ground has no friction"
    );
}

#[test]
fn pinned_particles_never_move() {
    let loaded = hooke::scene::presets::resolve("cloth32").unwrap();
    let mut app = app_with(loaded.scene.clone());
    let before: Vec<DVec2> = solver(&app).x()[..32].to_vec();
    // Even a velocity written into a pinned particle's component is ignored.
    let pinned_entity = solver(&app).entities()[3];
    app.world_mut()
        .get_mut::<Velocity>(pinned_entity)
        .unwrap()
        .0 = DVec2::new(5.0, 5.0);
    step(&mut app, 500);
    let s = solver(&app);
    for (i, &start) in before.iter().enumerate() {
        assert_eq!(s.x()[i], start, "pinned particle {i} moved");
        assert_eq!(s.v()[i], DVec2::ZERO, "pinned particle {i} has a velocity");
    }
    assert!(s.x()[40].y < 1.0 - 1.0 / 31.0, "free particles fall");
}

#[test]
fn zero_length_springs_exert_no_force() {
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.gravity = (0.0, -9.8);
    // Two coincident particles, joined by a zero-rest spring and by a spring that wants 0.1.
    scene.particles = vec![particle(0.5, 0.5, true), particle(0.5, 0.5, false)];
    scene.springs = vec![spring(0, 1, 1e4, 0.0), spring(0, 1, 1e4, 0.1)];
    let mut app = app_with(scene);
    step(&mut app, 1);
    assert_eq!(
        solver(&app).f()[1],
        DVec2::new(0.0, -9.8),
        "only gravity at zero length"
    );
    step(&mut app, 1000);
    assert!(solver(&app).state_is_finite());
}

#[test]
fn a_stiffness_change_through_the_resource_takes_effect_on_the_next_step() {
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.particles = vec![particle(0.0, 0.5, true), particle(0.6, 0.5, false)];
    scene.springs = vec![spring(0, 1, 1e4, 0.5)];
    let mut app = app_with(scene);
    // Force is written back only to the particles that have it.
    let free = solver(&app).entities()[1];
    app.world_mut().entity_mut(free).insert(Force::default());
    let force_on_free = |app: &mut bevy::app::App| {
        step(app, 1);
        let world = app.world_mut();
        let mut q = world.query::<(&SolverIndex, &Force)>();
        q.iter(world).find(|(i, _)| i.0 == 1).unwrap().1.0.x
    };
    let stretch = 0.1;
    let f = force_on_free(&mut app);
    assert!((f + 1e4 * stretch).abs() < 1e-6, "k = 1e4: f = {f}");

    app.world_mut()
        .resource_mut::<SimParams>()
        .stiffness_override = Some(3e4);
    let x = pos(&app, 1).x - 0.5;
    let f = force_on_free(&mut app);
    assert_eq!(f, -3e4 * x, "override 3e4 applies on the next step");

    // Clearing the override restores the spring's own stiffness...
    app.world_mut()
        .resource_mut::<SimParams>()
        .stiffness_override = None;
    let x = pos(&app, 1).x - 0.5;
    assert_eq!(force_on_free(&mut app), -1e4 * x);

    // ...and editing the spring component also takes effect on the next step.
    let world = app.world_mut();
    let mut springs = world.query::<&mut Spring>();
    springs.single_mut(world).unwrap().stiffness = 2e3;
    let x = pos(&app, 1).x - 0.5;
    assert_eq!(force_on_free(&mut app), -2e3 * x);
}

#[test]
fn particles_added_at_run_time_join_the_simulation() {
    let mut app = app_with(bare_scene(Integrator::SymplecticEuler, 1e-4));
    app.world_mut().resource_mut::<SimParams>().gravity = DVec2::new(0.0, -9.8);
    // Spawned like any Bevy entity: its creation order is assigned for it.
    app.world_mut()
        .spawn((Particle, hooke::sim::Position(DVec2::new(0.2, 0.7))));
    step(&mut app, 100);
    assert_eq!(solver(&app).particle_count(), 1);
    assert!(pos(&app, 0).y < 0.7);
}

/// Switching the integrator of a running simulation needs no reset and makes no jump: the step
/// after the switch moves every particle about as far as the step before it.
#[test]
fn switching_the_integrator_mid_run_is_seamless() {
    let scene = hooke::scene::presets::resolve("cloth32").unwrap().scene;
    for to in Integrator::ALL {
        let mut app = app_with(scene.clone());
        step(&mut app, 300);
        let before = solver(&app).x().to_vec();
        step(&mut app, 1);
        let last = solver(&app).x().to_vec();
        app.world_mut().resource_mut::<SimParams>().integrator = to;
        step(&mut app, 1);
        let after = solver(&app).x().to_vec();
        let largest = |a: &[DVec2], b: &[DVec2]| {
            a.iter()
                .zip(b)
                .map(|(p, q)| p.distance(*q))
                .fold(0.0, f64::max)
        };
        let (d_before, d_after) = (largest(&before, &last), largest(&last, &after));
        assert!(d_before > 0.0);
        assert!(
            d_after < 1.5 * d_before,
            "switching to {to}: the step moved particles {d_after:e} m, the one before {d_before:e} m"
        );
    }
}

/// The multi-threaded step gives the single-threaded result, to round-off, for every
/// integrator (the 80×80 cloth has 25k springs: above the threshold for threads).
#[test]
fn two_threads_give_the_one_thread_result() {
    for integrator in Integrator::ALL {
        let run = |threads: usize| {
            let mut app = cloth80(integrator, threads);
            step(&mut app, 40);
            solver(&app).x().to_vec()
        };
        assert_same_positions(&run(1), &run(2), &integrator.to_string());
    }
}

/// The 80×80 cloth with `integrator`, on `threads` solver threads.
fn cloth80(integrator: Integrator, threads: usize) -> bevy::app::App {
    let mut scene = hooke::bench::perf::cloth(80);
    scene.integrator = integrator;
    let mut app = app_with(scene);
    app.insert_resource(hooke::sim::SolverThreads::new(threads).unwrap());
    app
}

/// Positions within 1e-12 m of each other.
fn assert_same_positions(one: &[DVec2], two: &[DVec2], what: &str) {
    let worst = one
        .iter()
        .zip(two)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-12,
        "{what}: threads change positions by {worst:e} m"
    );
}

/// Springs removed and added between ticks of a threaded run (the thread split is redone when
/// the springs are repacked) give the one-thread result too.
#[test]
fn edits_between_ticks_keep_two_threads_equal_to_one() {
    for integrator in [Integrator::SymplecticEuler, Integrator::ImplicitEuler] {
        let run = |threads: usize| {
            let mut app = cloth80(integrator, threads);
            step(&mut app, 20);
            let (gone, ends): (Vec<_>, Vec<_>) = {
                let sv = solver(&app);
                let world = app.world();
                let gone = (0..sv.spring_count()).step_by(97);
                let gone = gone
                    .map(|i| sv.spring_entity_in(world, i).unwrap())
                    .collect();
                let ends = (0..40).map(|i| (sv.entities()[i * 150], sv.entities()[i * 150 + 81]));
                (gone, ends.collect())
            };
            let expected = solver(&app).spring_count() - gone.len() + ends.len();
            let world = app.world_mut();
            for e in gone {
                world.despawn(e);
            }
            for (a, b) in ends {
                world.spawn(Spring::new(a, b, 0.01, 5e3));
            }
            step(&mut app, 20);
            let sv = solver(&app);
            assert_eq!(sv.spring_count(), expected, "the edits reached the solver");
            (sv.spring_count(), sv.x().to_vec())
        };
        let ((n1, one), (n2, two)) = (run(1), run(2));
        assert_eq!(n1, n2);
        assert!(n1 > hooke::sim::PARALLEL_MIN_SPRINGS);
        assert_same_positions(&one, &two, &format!("{integrator}, after edits"));
    }
}
