//! The pull toward a point ([`Attraction`]), the app's right button: evaluated every step, on
//! top of the particles' own external forces (changed or not while it pulls), and gone without
//! a trace when released.

mod common;
use bevy::math::DVec2;
use bevy::prelude::*;
use common::*;
use hooke::sim::*;

/// Two free particles without gravity or damping, one within the pull's reach with a wind of
/// its own, one out of it.
fn two_particles(integrator: Integrator) -> App {
    let mut scene = bare_scene(integrator, 1e-4);
    scene.gravity = (0.0, 0.0);
    scene.damping = 0.0;
    scene.particles = vec![particle(0.5, 0.5, false), particle(0.9, 0.9, false)];
    let mut app = app_with(scene);
    let first = app
        .world_mut()
        .query_filtered::<(Entity, &SolverIndex), With<Particle>>()
        .iter(app.world())
        .find(|(_, i)| i.0 == 0)
        .unwrap()
        .0;
    app.world_mut()
        .entity_mut(first)
        .insert(ExternalForce(DVec2::new(0.0, 0.25)));
    app
}

#[test]
fn the_pull_draws_particles_in_reach_every_step_and_leaves_their_own_forces() {
    for integrator in Integrator::ALL {
        let mut app = two_particles(integrator);
        let target = DVec2::new(0.56, 0.5);
        app.world_mut().resource_mut::<Attraction>().active_at = Some(target);
        step(&mut app, 1);
        assert!(solver(&app).external_active(), "{integrator}: pulling");
        // f = m·strength·(c − x)/radius = 200·0.06/0.12 = 100 N toward the point, plus the
        // particle's own 0.25 N upward.
        let f = solver(&app).external_force(0);
        assert!(
            (f - DVec2::new(100.0, 0.25)).length() < 2.0,
            "{integrator}: {f}"
        );
        assert_eq!(solver(&app).external_force(1), DVec2::ZERO, "{integrator}");
        // A hundredth of a second: the particle closes in on the point (its period is
        // 2π/√(200/0.12) = 0.15 s), and the pull follows it step by step, so it does not
        // overshoot past the point in a quarter period.
        step(&mut app, 100);
        let x = pos(&app, 0);
        assert!(x.x > 0.5 + 0.002 && x.x < 0.56, "{integrator}: {x}");
        assert!(
            solver(&app).external_force(0).x < 100.0,
            "{integrator}: re-evaluated"
        );
        assert_eq!(
            pos(&app, 1),
            DVec2::new(0.9, 0.9),
            "{integrator}: out of reach"
        );
        // Released: the particle's own force, exactly, and nothing else.
        app.world_mut().resource_mut::<Attraction>().active_at = None;
        step(&mut app, 1);
        assert_eq!(
            solver(&app).external_force(0),
            DVec2::new(0.0, 0.25),
            "{integrator}"
        );
        assert_eq!(solver(&app).external_force(1), DVec2::ZERO, "{integrator}");
        // A force of its own changed while the pull is on is the one given back.
        app.world_mut().resource_mut::<Attraction>().active_at = Some(pos(&app, 0));
        step(&mut app, 1);
        let mut own = app
            .world_mut()
            .query::<(&SolverIndex, &mut ExternalForce)>();
        for (i, mut f) in own.iter_mut(app.world_mut()) {
            if i.0 == 0 {
                f.0 = DVec2::new(0.0, 0.5);
            }
        }
        step(&mut app, 1);
        app.world_mut().resource_mut::<Attraction>().active_at = None;
        step(&mut app, 1);
        assert_eq!(
            solver(&app).external_force(0),
            DVec2::new(0.0, 0.5),
            "{integrator}"
        );
    }
}
