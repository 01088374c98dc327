//! Contact between particles: soft boxes stacked under every integrator, a strip of cloth that
//! folds onto itself, and a rope across a rope. Checked by state, at the end of every step.

mod common;
use bevy::math::DVec2;
use common::*;
use hooke::scene::Scene;
use hooke::sim::{Integrator, Obstacles};

const G: f64 = 9.8;

/// The step each integrator is used with here: the force-based ones at the app's 1e-4 s
/// (explicit Euler at 2.5e-5 s: with μ = 10 1/s it needs h ω²/2 < μ, and the boxes' ω² is
/// 3.2e5), the large-step ones at 1/600 s. Contact between particles is discrete: a pair that closes by
/// more than about r in one step can pass through (the boxes meet at 1 m/s: under 2 mm a step at
/// 1/600 s, r = 9 mm; at 1/60 s it would be 17 mm).
fn usual_dt(integrator: Integrator) -> f64 {
    match integrator {
        Integrator::ExplicitEuler => 2.5e-5,
        Integrator::ImplicitEuler | Integrator::ProjectiveDynamics | Integrator::Xpbd => {
            1.0 / 600.0
        }
        _ => 1e-4,
    }
}

/// Two soft boxes dropped one onto the other onto the ground, under every integrator at its
/// usual step: no two particles of different boxes (or of one box, not joined by a spring)
/// closer than 90 % of 2r at the end of any step, and at rest within 5 s (kinetic energy under
/// 1e-6 of the potential energy of the drop).
#[test]
fn two_soft_boxes_stack_and_come_to_rest_under_every_integrator() {
    let (n, size, r) = STACKED_BOXES;
    for integrator in Integrator::ALL {
        let dt = usual_dt(integrator);
        let mut app = app_with(stacked_soft_boxes(integrator, dt));
        let steps = (5.0 / dt).round() as u64;
        let mut nearest = f64::INFINITY;
        let mut touched = 0;
        for s in 0..steps {
            step(&mut app, 1);
            let (d, i, j) = closest_unjoined(solver(&app));
            nearest = nearest.min(d);
            assert!(
                d >= 0.9 * 2.0 * r,
                "{integrator:?}: particles {i} and {j} {d} m apart after step {s}, under 90 % of 2r"
            );
            touched = touched.max(app.world().resource::<Obstacles>().contacts.pairs);
        }
        assert!(touched > 0, "{integrator:?}: the boxes never touched");
        let s = solver(&app);
        let mass: f64 = s.state().mass().iter().sum::<f64>() / 2.0;
        let drop = mass * G * 0.05;
        let kinetic = s.state().energy(DVec2::new(0.0, -G)).kinetic;
        // At rest.
        let limit = 1e-6;
        assert!(
            kinetic < limit * drop,
            "{integrator:?}: kinetic energy {kinetic} J after 5 s, over {limit} of the drop's {drop} J"
        );
        // Stacked: the upper box's lowest particle rests on the lower box's top.
        let upper_lowest = s.x()[n * n..]
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        assert!(
            upper_lowest > 0.5 * size,
            "{integrator:?}: the upper box's lowest particle is at {upper_lowest} m: it fell off"
        );
        println!(
            "{integrator:?}: nearest pair {nearest:.5} m (2r = {}), kinetic {kinetic:.2e} J",
            2.0 * r
        );
    }
}

/// A strip of cloth (two rows, 96 long) falling on its end onto the ground folds over on
/// itself (at least ten pairs not joined by a spring come within 1.2 of 2r); self-collision
/// keeps every such pair at 90 % of 2r or more at the end of every step, where without it the
/// folds pass through each other.
#[test]
fn a_folding_strip_does_not_pass_through_itself() {
    // The large-step methods at 1/600 s (a fold lands at 3 m/s: 5 mm a step, over the radius
    // of 4.3 mm). At 1/300 s two particles of a fold ended 83 % of 2r apart under implicit
    // Euler, and at 1/120 s under XPBD the strip's tip bends two particles two springs apart
    // to 45 % of 2r (2026-12-03).
    let large = 1.0 / 600.0;
    for (integrator, dt) in [
        (Integrator::SymplecticEuler, 1e-4),
        (Integrator::ImplicitEuler, large),
        (Integrator::ProjectiveDynamics, large),
        (Integrator::Xpbd, large),
    ] {
        let (scene, r) = folding_strip(integrator, dt);
        let mut app = app_with(scene);
        let steps = (2.0 / dt).round() as u64;
        let mut touched = 0;
        for s in 0..steps {
            step(&mut app, 1);
            let (dist, i, j) = closest_unjoined(solver(&app));
            assert!(
                dist >= 0.9 * 2.0 * r,
                "{integrator:?}: particles {i} and {j} {dist} m apart after step {s} (2r = {}) at {} {}, {:?}",
                2.0 * r,
                pos(&app, i),
                pos(&app, j),
                solver(&app).solve_stats()
            );
            // Pairs within 1.2 of 2r: projective dynamics' solve leaves a fold's pairs resting
            // just outside 2r, where the contact pass after the step counts none.
            touched = touched.max(touching_unjoined(solver(&app), 1.2 * 2.0 * r));
        }
        assert!(
            touched >= 10,
            "{integrator:?}: the strip never folded onto itself ({touched} pairs)"
        );
    }
}

/// The lists' skin: a body that falls as a whole keeps its neighbour lists (the common shift
/// is taken out), and one that deforms rebuilds them.
#[test]
fn a_falling_body_keeps_its_neighbour_lists() {
    let mut scene: Scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.gravity = (0.0, -G);
    scene.generate = vec![soft_box(6, 0.1, (0.3, 0.5), 1e4)];
    scene.contact = pairs_on(0.009, 0.0);
    let mut app = app_with(scene);
    step(&mut app, 3000);
    let builds = solver(&app).solve_stats().pair_list_builds;
    assert_eq!(
        builds, 1,
        "a free fall of 0.3 s rebuilt the lists {builds} times"
    );
}

/// A particle flung out of all proportion (1e300 m/s: a blow-up on its way to being caught)
/// is hashed into the pair grid without an overflow: its cell is clamped, its neighbours'
/// too. (The app's random-input hammer found `cx + 1` overflowing on 2026-12-04.)
#[test]
fn a_particle_flung_far_is_hashed_without_overflow() {
    let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
    scene.contact = pairs_on(0.005, 0.0);
    scene.particles = vec![
        particle(0.2, 0.5, false),
        particle(0.4, 0.5, false),
        particle(0.6, 0.5, false),
    ];
    scene.particles[2].vel = (1e300, -1e300);
    let mut app = app_with(scene);
    step(&mut app, 3);
    // The two at rest are where they were; the flung one is far away, finite or caught.
    assert_eq!(pos(&app, 0), DVec2::new(0.2, 0.5));
    assert_eq!(pos(&app, 1), DVec2::new(0.4, 0.5));
}
