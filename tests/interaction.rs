//! What interaction needs of the simulation, headless: external forces in every integrator,
//! kinematic (grabbed) particles, tearing, edits through the ECS mid-run, the way back from a
//! blow-up, and saving.

mod common;
use bevy::math::DVec2;
use bevy::prelude::*;
use common::*;
use hooke::scene::{LoadedScene, load_into_world, presets, snapshot, to_ron};
use hooke::sim::watch::{EnergyWatch, restore_last_good_state};
use hooke::sim::*;

/// The shared test network (tests/common) under gravity `gravity`.
fn network_under(integrator: Integrator, dt: f64, gravity: (f64, f64)) -> hooke::scene::Scene {
    let mut scene = network(integrator, dt);
    scene.gravity = gravity;
    scene
}

fn particles_in_order(app: &mut App) -> Vec<Entity> {
    solver(app).entities().to_vec()
}

/// An external force of m·a on every particle moves each integrator exactly as gravity a
/// does: the force enters every evaluation, all of RK4's and Verlet's stages and implicit
/// Euler's right-hand side included.
#[test]
fn an_external_force_enters_every_stage_of_every_integrator() {
    let a = DVec2::new(3.0, -7.0);
    for integrator in Integrator::ALL {
        let dt = 2e-3;
        let mut by_gravity = app_with(network_under(integrator, dt, (a.x, a.y)));
        let mut by_force = app_with(network_under(integrator, dt, (0.0, 0.0)));
        let masses = solver(&by_force).mass().to_vec();
        for (e, m) in particles_in_order(&mut by_force).into_iter().zip(masses) {
            by_force
                .world_mut()
                .entity_mut(e)
                .insert(ExternalForce(a * m));
        }
        step(&mut by_gravity, 300);
        step(&mut by_force, 300);
        assert!(solver(&by_force).external_active());
        for i in 0..4 {
            let (g, f) = (pos(&by_gravity, i), pos(&by_force, i));
            assert!(
                g.distance(f) < 1e-12,
                "{integrator}: particle {i} at {f} with the force, {g} with gravity"
            );
        }
        assert!(
            pos(&by_force, 3).distance(DVec2::new(0.5, 0.5)) > 1e-3,
            "{integrator}: it moved"
        );
    }
}

/// Clearing the external forces switches the extra work off again.
#[test]
fn zero_external_forces_cost_nothing() {
    let mut app = app_with(network_under(
        Integrator::SymplecticEuler,
        1e-4,
        (0.0, -9.8),
    ));
    let e = particles_in_order(&mut app)[1];
    app.world_mut()
        .entity_mut(e)
        .insert(ExternalForce(DVec2::X));
    step(&mut app, 1);
    assert!(solver(&app).external_active());
    app.world_mut()
        .entity_mut(e)
        .insert(ExternalForce(DVec2::ZERO));
    step(&mut app, 1);
    assert!(!solver(&app).external_active());
}

/// A kinematic particle moves with the velocity it is given, whatever the forces, under every
/// integrator; released, it is free again and keeps that velocity.
#[test]
fn a_kinematic_particle_moves_with_its_velocity_and_is_released_with_it() {
    for integrator in Integrator::ALL {
        let mut app = app_with(network_under(integrator, 1e-3, (0.0, -9.8)));
        let e = particles_in_order(&mut app)[3];
        let v = DVec2::new(0.4, 0.1);
        app.world_mut()
            .entity_mut(e)
            .insert((Kinematic, Velocity(v)));
        step(&mut app, 100);
        let expected = DVec2::new(0.5, 0.5) + v * 0.1;
        assert!(
            pos(&app, 3).distance(expected) < 1e-9,
            "{integrator}: {} vs {expected}",
            pos(&app, 3)
        );
        assert!(vel(&app, 3).distance(v) < 1e-12, "{integrator}");
        assert_eq!(solver(&app).kinematic(), 1);
        app.world_mut().entity_mut(e).remove::<Kinematic>();
        step(&mut app, 1);
        assert_eq!(solver(&app).kinematic(), 0);
        // One step of forces (springs of 200 N/m on 0.5 kg, dt = 1e-3) changes it by < 1 m/s.
        assert!(
            vel(&app, 3).distance(v) < 1.0,
            "{integrator}: released with about its velocity, got {}",
            vel(&app, 3)
        );
        assert!(vel(&app, 3) != v, "{integrator}: forces act on it again");
    }
}

/// A chain pinned at the top with a heavy weight at the bottom.
fn weighted_chain(tear: Option<f64>) -> hooke::scene::Scene {
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.gravity = (0.0, -9.8);
    scene.damping = 5.0;
    scene.tear = tear;
    scene.particles = (0..5)
        .map(|i| particle(0.5, 0.9 - 0.1 * i as f64, i == 0))
        .collect();
    scene.particles[4].mass = 50.0;
    scene.springs = (0..4).map(|i| spring(i, i + 1, 2000.0, 0.1)).collect();
    scene
}

/// The weight would stretch the springs by m g / k = 0.245 m, past a 50 % strain limit: a
/// spring breaks and the weight falls; with tearing off, no tear pass runs at all.
#[test]
fn overstretched_springs_tear_and_the_pass_runs_only_when_tearing_is_on() {
    let mut app = app_with(weighted_chain(None));
    step(&mut app, 5000);
    assert_eq!(app.world().resource::<PassCounts>().tear, 0);
    assert_eq!(solver(&app).spring_count(), 4);

    let mut app = app_with(weighted_chain(Some(0.5)));
    step(&mut app, 5000);
    let torn = app.world().resource::<Tearing>().torn;
    assert!(app.world().resource::<PassCounts>().tear > 0);
    assert!(torn >= 1, "nothing tore");
    assert_eq!(solver(&app).spring_count() as u64, 4 - torn);
    assert!(solver(&app).state_is_finite());
    // The weight is falling, far below where the whole chain would hang.
    assert!(pos(&app, 4).y < 0.0, "the weight fell: {}", pos(&app, 4));

    // `hooke run` tears the same way and reports it.
    let loaded = LoadedScene::from_scene(weighted_chain(Some(0.5)), None).unwrap();
    let run = hooke::runner::run(
        &loaded,
        &Default::default(),
        hooke::runner::Duration::Steps(5000),
    )
    .unwrap();
    assert_eq!(run.report.springs_torn, torn);
}

/// Two identical oscillators side by side; despawning one's spring mid-run leaves the other
/// exactly on the path it had without the edit.
#[test]
fn despawning_mid_run_leaves_the_rest_untouched() {
    let pair = || {
        let mut scene = bare_scene(Integrator::VelocityVerlet, 1e-4);
        scene.gravity = (0.0, -9.8);
        scene.particles = vec![
            particle(0.2, 0.8, true),
            particle(0.2, 0.6, false),
            particle(0.7, 0.8, true),
            particle(0.7, 0.6, false),
        ];
        scene.springs = vec![spring(0, 1, 300.0, 0.15), spring(2, 3, 300.0, 0.15)];
        app_with(scene)
    };
    let (mut edited, mut plain) = (pair(), pair());
    step(&mut edited, 777);
    step(&mut plain, 777);
    let spring = solver(&edited).spring_entity_in(edited.world(), 0).unwrap();
    let p1 = solver(&edited).entities()[1];
    edited.world_mut().despawn(spring);
    edited.world_mut().despawn(p1);
    step(&mut edited, 1234);
    step(&mut plain, 1234);
    assert_eq!(solver(&edited).particle_count(), 3);
    // Particle 3 of the plain run is particle 2 of the edited one.
    assert!(pos(&edited, 2).distance(pos(&plain, 3)) < 1e-15);
    assert!(vel(&edited, 2).distance(vel(&plain, 3)) < 1e-15);
}

/// The blow-up: cloth32 at rest, then explicit Euler with μ = 0 and k = 4e5. The watch
/// stops it, and the way back leads to a state whose energy is that of the edit, not to the
/// tangle of the tick before the stop.
#[test]
fn the_way_back_from_a_blow_up_leads_to_a_usable_state() {
    let loaded = presets::resolve("cloth32").unwrap();
    let mut app = hooke::running_app(&loaded).unwrap();
    app.insert_resource(EnergyWatch::default());
    hooke::sim::advance(app.world_mut(), 5000);
    {
        let mut p = app.world_mut().resource_mut::<SimParams>();
        p.integrator = Integrator::ExplicitEuler;
        p.damping = 0.0;
        p.stiffness_override = Some(4e5);
    }
    hooke::sim::advance(app.world_mut(), 1);
    let g = DVec2::new(0.0, -9.8);
    let at_edit = solver(&app).energy(g).total();
    hooke::sim::advance(app.world_mut(), 20_000);
    let status = *app.world().resource::<SimStatus>();
    let SimStatus::EnergyGrew { energy, .. } = status else {
        panic!("expected the watch to stop it, got {status:?}");
    };
    assert!(energy > 10.0 * at_edit.abs());
    assert!(restore_last_good_state(app.world_mut()));
    hooke::sim::pack(app.world_mut()).unwrap();
    let restored = solver(&app).energy(g).total();
    let near = EnergyWatch::near(at_edit);
    println!("edit {at_edit:.4e} J, stopped at {energy:.4e} J, restored {restored:.4e} J");
    assert!(
        restored <= near + 1e-6 * at_edit.abs(),
        "restored {restored:.4e} J, the edit had {at_edit:.4e} J (stopped at {energy:.3e} J)"
    );
}

/// Saving writes a file that loads back to the same state: every particle, spring, position,
/// velocity and pin, and the parameters (tearing included).
#[test]
fn a_saved_scene_loads_back_to_the_same_state() {
    let mut scene = presets::resolve("cloth32").unwrap().scene;
    scene.tear = Some(0.3);
    let mut app = app_with(scene);
    step(&mut app, 777);
    let text = to_ron(&snapshot(app.world_mut())).unwrap();
    let back = LoadedScene::parse(&text, std::path::Path::new("saved.ron")).unwrap();
    let mut other = hooke::headless_app();
    load_into_world(other.world_mut(), &back);
    hooke::sim::pack(other.world_mut()).unwrap();
    let (a, b) = (solver(&app), solver(&other));
    assert_eq!(a.x(), b.x());
    assert_eq!(a.v(), b.v());
    assert_eq!(a.inv_mass(), b.inv_mass());
    assert_eq!(a.springs(), b.springs());
    let (pa, pb) = (
        app.world().resource::<SimParams>(),
        other.world().resource::<SimParams>(),
    );
    assert_eq!(
        (
            pa.gravity,
            pa.damping,
            pa.ground,
            pa.dt,
            pa.integrator,
            pa.tear
        ),
        (
            pb.gravity,
            pb.damping,
            pb.ground,
            pb.dt,
            pb.integrator,
            pb.tear
        )
    );
}
