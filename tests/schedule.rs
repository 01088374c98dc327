//! The schedule: systems for unused features do not run, and the app's fixed-timestep loop
//! steps the simulation like the direct headless stepping does.

mod common;
use common::*;
use hooke::scene::presets;
use hooke::sim::{Integrator, PassCounts, SimClock, SimParams};
use std::time::Duration;

#[test]
fn systems_for_unused_features_do_not_run() {
    // No springs, no damping, no ground: only gravity, velocity and position updates run.
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.gravity = (0.0, -9.8);
    scene.particles = vec![particle(0.5, 0.5, false)];
    let mut app = app_with(scene);
    step(&mut app, 250);
    let n = *app.world().resource::<PassCounts>();
    assert_eq!(
        n,
        PassCounts {
            gravity: 250,
            springs: 0,
            integrate: 250,
            damping: 0,
            ground: 0,
            advance: 250,
            sweeps: 250,
            tear: 0,
            contact: 0,
            materials: 0,
            actuate: 0,
            yield_springs: 0,
        }
    );

    // The cloth uses every feature: every pass runs every step.
    let mut app = app_with(presets::resolve("cloth32").unwrap().scene);
    step(&mut app, 40);
    let n = *app.world().resource::<PassCounts>();
    assert_eq!(
        (n.springs, n.damping, n.ground, n.advance),
        (40, 40, 40, 40)
    );

    // Switching a feature off at run time stops its pass from the next step on.
    app.world_mut().resource_mut::<SimParams>().damping = 0.0;
    app.world_mut().resource_mut::<SimParams>().ground = None;
    step(&mut app, 10);
    let n = *app.world().resource::<PassCounts>();
    assert_eq!(
        (n.springs, n.damping, n.ground, n.advance),
        (50, 40, 40, 50)
    );
}

/// The fused particle sweep gives the separate passes' result bit for bit, for every
/// integrator, with damping and ground each on and off, on one and two threads; and it is
/// assembled from the passes in use: without damping it counts no damping work, without a
/// ground no contact test, while the separate passes' systems do not run at all.
#[test]
fn the_fused_sweep_equals_the_separate_passes_bit_for_bit() {
    use hooke::sim::{ParticleSweep, SolverThreads};
    let cloth = presets::resolve("cloth32").unwrap().scene;
    let big = hooke::bench::perf::cloth(80); // 25k springs: two threads split the work
    for (scene, threads) in [(&cloth, 1), (&big, 2)] {
        for integrator in Integrator::ALL {
            for (damping, ground) in [
                (10.0, Some(0.0)),
                (0.0, Some(0.0)),
                (10.0, None),
                (0.0, None),
            ] {
                let mut scene = scene.clone();
                scene.integrator = integrator;
                scene.damping = damping;
                scene.ground = ground;
                // Large enough steps that the cloth reaches the ground in a few steps.
                scene.dt = if integrator.unconditionally_stable() {
                    1.0 / 120.0
                } else {
                    2e-4
                };
                if integrator == Integrator::ExplicitEuler {
                    scene.dt = 5e-5;
                }
                let run = |fused: bool| {
                    let mut app = app_with(scene.clone());
                    app.insert_resource(ParticleSweep { fused });
                    app.insert_resource(SolverThreads::new(threads).unwrap());
                    step(&mut app, 30);
                    let s = solver(&app);
                    let bits: Vec<[u64; 4]> = (s.x().iter().zip(s.v()))
                        .map(|(x, v)| [x.x, x.y, v.x, v.y].map(f64::to_bits))
                        .collect();
                    (bits, *app.world().resource::<PassCounts>())
                };
                let (fused, counts) = run(true);
                let (separate, separate_counts) = run(false);
                let what =
                    format!("{integrator}, mu {damping}, ground {ground:?}, {threads} threads");
                assert!(fused == separate, "{what}: the fused sweep differs");
                assert_eq!(counts.sweeps, 30, "{what}");
                assert_eq!(separate_counts.sweeps, 0, "{what}");
                // BDF2 takes the damping inside its solve: no damping pass.
                let damped = damping != 0.0 && !integrator.drags_in_solve();
                assert_eq!(counts.damping, if damped { 30 } else { 0 }, "{what}");
                assert_eq!(
                    counts.ground,
                    if ground.is_some() { 30 } else { 0 },
                    "{what}"
                );
                assert_eq!(
                    (counts.integrate, counts.advance),
                    (separate_counts.integrate, separate_counts.advance),
                    "{what}"
                );
            }
        }
    }
}

#[test]
fn paused_simulation_does_not_step() {
    let mut app = app_with(presets::resolve("cloth32").unwrap().scene);
    app.world_mut().resource_mut::<SimParams>().paused = true;
    assert_eq!(hooke::sim::advance(app.world_mut(), 100), 0);
    assert_eq!(app.world().resource::<SimClock>().steps, 0);
}

/// The app path: `app.update()` with a manual clock runs the fixed loop, which sizes its tick
/// from dt and runs that many steps per tick. The result equals direct stepping.
#[test]
fn fixed_timestep_loop_matches_direct_stepping() {
    let scene = presets::resolve("rope").unwrap().scene;
    let mut driven = app_with(scene.clone());
    driven.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        Duration::from_millis(10),
    ));
    for _ in 0..30 {
        driven.update();
    }
    let steps = driven.world().resource::<SimClock>().steps;
    // 30 frames of 10 ms at dt = 1e-4 s: about 3000 steps (the first frame has no delta).
    assert!(
        (2800..=3000).contains(&steps),
        "{steps} steps after 0.3 s of frames"
    );
    let mut direct = app_with(scene);
    step(&mut direct, steps);
    assert_eq!(solver(&driven).x(), solver(&direct).x());
}

/// When steps cost more than the frame budget, the frame stops after the tick that ran over:
/// the simulation slows down (the rest of the frame's simulated time is dropped) instead of
/// the frame running on. Once a step has been timed, the tick itself is cut to fit the budget
/// (here, with none, to one step).
#[test]
fn a_frame_over_budget_drops_simulated_time_instead_of_stalling() {
    let scene = presets::resolve("cloth32").unwrap().scene;
    let mut app = app_with(scene);
    app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        Duration::from_millis(100),
    ));
    app.world_mut()
        .resource_mut::<hooke::sim::StepBudget>()
        .per_frame = Duration::ZERO;
    app.update(); // the first frame has no time delta
    let tick = |app: &bevy::app::App| {
        let w = app.world();
        let plan = w.resource::<hooke::sim::TickPlan>();
        (w.resource::<SimClock>().steps, plan.steps_per_tick as u64)
    };
    let (mut steps, _) = tick(&app);
    for frame in 0..5 {
        app.update();
        // 100 ms of frame at dt = 1e-4 asks for 1000 steps; a zero budget allows one tick.
        let (now, per_tick) = tick(&app);
        assert_eq!(now - steps, per_tick, "frame {frame}: one tick");
        assert!(per_tick < 1000);
        steps = now;
    }
    assert_eq!(tick(&app).1, 1, "the tick cut to one step");
    let dropped = app
        .world()
        .resource::<hooke::sim::StepBudget>()
        .dropped_seconds;
    assert!(dropped > 0.3, "dropped {dropped} s of simulated time");
}

/// The step schedule is built with ambiguity detection at the error level: a user system that
/// writes the solver inside a step set without an order against the passes fails when the
/// schedule is built, instead of racing; ordered, it runs every step.
#[test]
fn an_unordered_user_system_in_the_step_fails_at_build_time() {
    use bevy::prelude::*;
    use hooke::sim::{PhysicsStep, Solver, StepSystems};
    fn meddle(_solver: ResMut<Solver>) {}
    let mut app = app_with(presets::resolve("rope").unwrap().scene);
    app.add_systems(PhysicsStep, meddle.in_set(StepSystems::Integrate));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        hooke::sim::advance(app.world_mut(), 1);
    }));
    let message = result
        .err()
        .and_then(|e| e.downcast_ref::<String>().cloned())
        .expect("the schedule refuses to build");
    assert!(message.contains("conflicting"), "{message}");

    #[derive(Resource, Default)]
    struct Seen(u64);
    fn count(_solver: Res<Solver>, mut seen: ResMut<Seen>) {
        seen.0 += 1;
    }
    let mut app = app_with(presets::resolve("rope").unwrap().scene);
    app.init_resource::<Seen>().add_systems(
        PhysicsStep,
        count
            .after(StepSystems::Forces)
            .before(StepSystems::Integrate),
    );
    step(&mut app, 50);
    assert_eq!(app.world().resource::<Seen>().0, 50);
}
