//! Contact with obstacles and the ground: Coulomb friction on a slope, restitution on a bounce,
//! no tunnelling through a thin segment, moving obstacles, and scenes without contact left
//! exactly as they were. Each under every integrator, checked by state.

mod common;
use bevy::math::DVec2;
use common::*;
use hooke::scene::{ObstacleDef, Scene};
use hooke::sim::{
    ContactSettings, Integrator, Obstacle, ObstaclePose, ObstacleVelocity, Obstacles, PassCounts,
    SimParams,
};
use hooke::solver::Shape;

const G: f64 = 9.8;

fn contact(friction: f64, restitution: f64) -> Option<ContactSettings> {
    Some(ContactSettings {
        friction,
        restitution,
        ..ContactSettings::default()
    })
}

/// One free particle of 1 kg at `at`, at rest, no damping, no ground.
fn one_particle(integrator: Integrator, dt: f64, at: DVec2) -> Scene {
    let mut scene = bare_scene(integrator, dt);
    scene.gravity = (0.0, -G);
    scene.particles = vec![particle(at.x, at.y, false)];
    scene
}

/// A slope of angle θ (down to the right) through the origin, as a long zero-thickness
/// segment, and a point mass at rest on it at distance 0.4 up the slope.
fn on_slope(integrator: Integrator, dt: f64, theta: f64, mu: f64) -> (Scene, DVec2) {
    let down = DVec2::new(theta.cos(), -theta.sin());
    let start = -down * 0.4;
    let mut scene = one_particle(integrator, dt, start);
    let (a, b) = (-down * 2.0, down * 2.0);
    scene.obstacles = vec![ObstacleDef::Segment {
        a: (a.x, a.y),
        b: (b.x, b.y),
        thickness: 0.0,
    }];
    scene.contact = contact(mu, 0.0);
    (scene, down)
}

/// Coulomb friction: on a slope steeper than atan μ a point mass slides with acceleration
/// g (sin θ − μ cos θ); on a gentler one it stays. Every integrator, at dt = 1e-3 s (a single
/// particle has no spring to make any of them unstable).
#[test]
fn a_point_mass_slides_or_holds_on_a_slope_as_coulomb_says() {
    let (dt, seconds) = (1e-3, 1.0);
    for integrator in Integrator::ALL {
        // Slides: tan 40° = 0.84 > 0.3.
        let (theta, mu) = (40f64.to_radians(), 0.3);
        let (scene, down) = on_slope(integrator, dt, theta, mu);
        let start = DVec2::from(scene.particles[0].pos);
        let mut app = app_with(scene);
        step(&mut app, (seconds / dt) as u64);
        let moved = pos(&app, 0) - start;
        let along = moved.dot(down);
        let expected = 0.5 * G * (theta.sin() - mu * theta.cos()) * seconds * seconds;
        assert!(
            (along / expected - 1.0).abs() < 0.02,
            "{integrator:?}: slid {along} m, Coulomb says {expected} m"
        );
        // On the slope: a zero-thickness segment collides as one a micrometre thick.
        let off = moved.dot(down.perp()).abs();
        assert!(off < 1e-5, "{integrator:?}: left the slope by {off} m");

        // Holds: tan 20° = 0.36 <= 0.5.
        let (scene, down) = on_slope(integrator, dt, 20f64.to_radians(), 0.5);
        let start = DVec2::from(scene.particles[0].pos);
        let mut app = app_with(scene);
        step(&mut app, (seconds / dt) as u64);
        let crept = (pos(&app, 0) - start).dot(down).abs();
        assert!(
            crept < 1e-9,
            "{integrator:?}: crept {crept} m on a slope friction holds"
        );
    }
}

/// Restitution e: a particle dropped on the ground with no damping bounces to e² times its
/// drop height.
#[test]
fn a_bounce_reaches_e_squared_of_the_drop_height() {
    let (dt, h, e) = (1e-4, 0.5, 0.6);
    for integrator in Integrator::ALL {
        let mut scene = one_particle(integrator, dt, DVec2::new(0.5, h));
        scene.ground = Some(0.0);
        scene.contact = contact(0.0, e);
        let mut app = app_with(scene);
        // Down (0.32 s) and most of the way back up: the apex is at 0.32 + 0.6·0.32 s.
        let mut apex = 0.0f64;
        let mut bounced = false;
        for _ in 0..700 {
            step(&mut app, 10);
            let (y, vy) = (pos(&app, 0).y, vel(&app, 0).y);
            bounced |= vy > 0.0;
            if bounced {
                apex = apex.max(y);
            }
        }
        assert!(
            (apex / (e * e * h) - 1.0).abs() < 0.02,
            "{integrator:?}: bounced to {apex} m, e² h = {} m",
            e * e * h
        );
    }
}

/// No tunnelling: a particle thrown at 10 m/s at a zero-thickness segment at dt = 1/60 s
/// (17 cm a step) stops on it under every integrator (all are stable here: no springs), and
/// slides along it (no friction) without going under it.
#[test]
fn a_fast_particle_does_not_pass_through_a_thin_segment() {
    // The line y = 0.4 − x/3 from x = 0 to 0.6, and its upper normal.
    let normal = DVec2::new(1.0 / 3.0, 1.0).normalize();
    for integrator in Integrator::ALL {
        let mut scene = one_particle(integrator, 1.0 / 60.0, DVec2::new(0.1, 0.5));
        scene.gravity = (0.0, 0.0);
        scene.particles[0].vel = (0.0, -10.0);
        scene.obstacles = vec![ObstacleDef::Segment {
            a: (0.0, 0.4),
            b: (0.6, 0.2),
            thickness: 0.0,
        }];
        let mut app = app_with(scene);
        // Three steps: the first crosses the line's height, the next two slide along it
        // (3.2 m/s along it, 5 cm a step), still over the segment.
        for i in 1..=3 {
            step(&mut app, 1);
            let p = pos(&app, 0);
            let above = p.y - (0.4 - p.x / 3.0);
            assert!(
                above > -1e-12 && p.x < 0.6,
                "{integrator:?}, step {i}: {above} m over the segment's line at {p}"
            );
            let into = vel(&app, 0).dot(normal);
            assert!(
                into > -1e-9,
                "{integrator:?}, step {i}: moving into it at {into} m/s"
            );
        }
    }
}

/// A moving obstacle carries what rests on it through friction, and its pose is written back:
/// a platform under a particle of r = 1 cm moves right at 0.5 m/s, up and right at 0.5 m/s
/// each way, or up at 2 m/s (a lift), as a box 10 cm thick and as a segment of no thickness.
/// Under every integrator at 1e-3 s, and under the large-step methods at 1/60 s too, friction
/// μ = 1 brings the particle to the platform's velocity within v²/(2μg) of slip, and it rests
/// on its top. XPBD read the platform's slide over a step against the particle's over each
/// substep: it dragged the particle off the platform at 3.4 m/s.
#[test]
fn a_moving_platform_carries_a_particle_by_friction() {
    let r = 0.01;
    let (center, half) = (DVec2::new(0.5, 0.25), 0.5);
    let platforms = [
        (
            Shape::Box {
                half: DVec2::new(half, 0.05),
            },
            0.05,
        ),
        (
            Shape::Segment {
                a: DVec2::new(-half, 0.0),
                b: DVec2::new(half, 0.0),
                thickness: 0.0,
            },
            0.0,
        ),
    ];
    let motions = [
        DVec2::new(0.5, 0.0),
        DVec2::new(0.5, 0.5),
        DVec2::new(0.0, 2.0),
    ];
    let mut runs = 0;
    for (shape, top) in platforms {
        for velocity in motions {
            for integrator in Integrator::ALL {
                let steps: &[f64] = if integrator.unconditionally_stable() {
                    &[1e-3, 1.0 / 60.0]
                } else {
                    &[1e-3]
                };
                for &dt in steps {
                    let on_top = center + DVec2::new(0.0, top + r);
                    let mut scene = one_particle(integrator, dt, on_top);
                    scene.contact = Some(ContactSettings {
                        radius: r,
                        ..contact(1.0, 0.0).unwrap()
                    });
                    let mut app = app_with(scene);
                    let platform = app
                        .world_mut()
                        .spawn((
                            Obstacle(shape),
                            ObstaclePose { center, angle: 0.0 },
                            ObstacleVelocity {
                                linear: velocity,
                                angular: 0.0,
                            },
                        ))
                        .id();
                    let n = (0.5 / dt).round() as u64;
                    step(&mut app, n);
                    runs += 1;
                    let now = center + velocity * (n as f64 * dt);
                    let case = format!("{shape:?} at {velocity} m/s, {integrator:?}, dt {dt:.4}");
                    let v = vel(&app, 0);
                    assert!((v - velocity).length() < 1e-6, "{case}: carried at {v}");
                    let pose = app.world().get::<ObstaclePose>(platform).unwrap();
                    assert!(
                        (pose.center - now).length() < 1e-9,
                        "{case}: at {}",
                        pose.center
                    );
                    let on = pos(&app, 0) - now;
                    let slip = velocity.x * velocity.x / (2.0 * G);
                    assert!(
                        (on.y - top - r).abs() < 1e-3 && on.x.abs() < slip + 1e-3,
                        "{case}: at {on} from the platform's centre"
                    );
                    assert!(app.world().resource::<Obstacles>().contacts.surfaces >= 1);
                }
            }
        }
    }
    assert_eq!(runs, 84);
}

/// A scene without obstacles or contact runs no contact pass, and its steps are the same bits
/// as before contact existed: the contact pass is the only new code on their path, and it
/// does not run. (The reference checksums, `tests/reference.rs`, check the values.)
#[test]
fn no_contact_no_contact_pass() {
    let mut app = app_with(hooke::scene::presets::resolve("cloth32").unwrap().scene);
    step(&mut app, 40);
    assert_eq!(app.world().resource::<PassCounts>().contact, 0);
    // Contact settings with a ground: the ground moves into the contact pass.
    let mut scene = hooke::scene::presets::resolve("cloth32").unwrap().scene;
    scene.contact = contact(0.5, 0.0);
    let mut app = app_with(scene);
    step(&mut app, 40);
    let n = *app.world().resource::<PassCounts>();
    assert_eq!((n.contact, n.ground), (40, 0));
}

/// With contact set, the ground holds particles at their radius above it, and friction stops
/// a soft box pushed along it within v²/(2 μ g), where the assignment's frictionless ground
/// lets it slide on until the air's damping stops it.
#[test]
fn friction_stops_a_sliding_box() {
    // An 8 × 8 box resting on the ground, moving right at 0.5 m/s: friction 0.5 stops it
    // within 2.6 cm; damping μ = 1/s alone lets it slide 0.32 m in 1 s.
    let slide = |contact: Option<ContactSettings>| {
        let radius = contact.map_or(0.0, |c| c.radius);
        let mut scene = bare_scene(Integrator::SymplecticEuler, 1e-4);
        (scene.gravity, scene.damping, scene.ground) = ((0.0, -G), 1.0, Some(0.0));
        scene.generate = vec![hooke::scene::Generator::Grid {
            cols: 8,
            rows: 8,
            min: (0.1, radius),
            max: (0.4, 0.3 + radius),
            mass: 0.1,
            stiffness: 1e4,
            shear: true,
            pin: hooke::scene::Pin::None,
            vel: (0.5, 0.0),
            damping: None,
            plastic: None,
        }];
        scene.contact = contact;
        let mut app = app_with(scene);
        let centre = |app: &bevy::app::App| {
            let x = solver(app).x();
            x.iter().map(|p| p.x).sum::<f64>() / x.len() as f64
        };
        let before = centre(&app);
        step(&mut app, 10_000);
        let s = solver(&app);
        let lowest = s.x().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        // (The assignment's ground tests the start of the step: a particle may end one up to
        // dt·|v| under it. Contact's ground holds every particle at its radius.)
        if let Some(c) = contact {
            assert!(
                lowest >= c.radius - 1e-12,
                "a particle at {lowest}, under its radius"
            );
        }
        centre(&app) - before
    };
    let gripped = slide(Some(ContactSettings {
        radius: 0.005,
        friction: 0.5,
        ..ContactSettings::default()
    }));
    let sliding = slide(None);
    let stop = 0.5f64.powi(2) / (2.0 * 0.5 * G);
    assert!(
        gripped > 0.0 && gripped < 1.2 * stop,
        "slid {gripped} m; Coulomb stops it in {stop} m"
    );
    assert!(
        sliding > 0.3,
        "the frictionless ground let it slide only {sliding} m"
    );
}

/// Obstacles and contact settings come from scene files, are saved back, and bad ones are
/// named.
#[test]
fn obstacles_load_save_and_are_checked() {
    let loaded = hooke::scene::presets::resolve("slope").unwrap();
    let mut app = hooke::running_app(&loaded).unwrap();
    step(&mut app, 10);
    assert_eq!(app.world().resource::<Obstacles>().placed().len(), 2);
    let saved = hooke::scene::snapshot(app.world_mut());
    assert_eq!(saved.obstacles.len(), 2);
    for (a, b) in saved.obstacles.iter().zip(&loaded.scene.obstacles) {
        let (ObstacleDef::Segment { a: a0, b: b0, .. }, ObstacleDef::Segment { a: a1, b: b1, .. }) =
            (a, b)
        else {
            panic!("{a:?} {b:?}");
        };
        for (p, q) in [(a0, a1), (b0, b1)] {
            assert!(
                (p.0 - q.0).abs() < 1e-12 && (p.1 - q.1).abs() < 1e-12,
                "{p:?} {q:?}"
            );
        }
    }
    assert_eq!(saved.contact, loaded.scene.contact);

    let mut bad = loaded.scene.clone();
    bad.obstacles.push(ObstacleDef::Circle {
        center: (0.5, f64::NAN),
        radius: -1.0,
    });
    bad.contact = Some(ContactSettings {
        restitution: 1.5,
        ..ContactSettings::default()
    });
    let e = hooke::scene::LoadedScene::from_scene(bad, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("contact.restitution: must be between 0 and 1"),
        "{e}"
    );
    assert!(e.contains("obstacles[2]: center.y: must be finite"), "{e}");

    // The same through the ECS: a circle of radius 0 written by code pauses, named.
    let mut app = app_with(one_particle(Integrator::SymplecticEuler, 1e-3, DVec2::ZERO));
    app.world_mut()
        .spawn(Obstacle(Shape::Circle { radius: 0.0 }));
    hooke::sim::advance(app.world_mut(), 10);
    let status = *app.world().resource::<hooke::sim::SimStatus>();
    let hooke::sim::SimStatus::InvalidInput(problem) = status else {
        panic!("{status:?}");
    };
    assert!(
        problem.to_string().contains("the circle's radius"),
        "{problem}"
    );
    assert!(app.world().resource::<SimParams>().paused);
}
