//! Nothing a user writes through the ECS breaks the simulation: a bad value pauses it with a
//! status that names the field and the value, the solver keeps its last good state, and
//! nothing panics, neither `advance` nor the app's own frame loop (`app.update()`).

mod common;
use bevy::math::DVec2;
use bevy::prelude::*;
use common::*;
use hooke::sim::*;

fn rope() -> App {
    let loaded = hooke::scene::presets::resolve("rope").unwrap();
    let mut app = hooke::running_app(&loaded).unwrap();
    advance(app.world_mut(), 200);
    app
}

fn problem(app: &App) -> Option<inputs::InputProblem> {
    match *app.world().resource::<SimStatus>() {
        SimStatus::InvalidInput(p) => Some(p),
        _ => None,
    }
}

/// Writes a bad value, then checks that the next ticks pause on it by name and keep the state;
/// then mends it and checks that the simulation runs again.
fn rejects(what: &str, field: &str, write: impl Fn(&mut World), mend: impl Fn(&mut World)) {
    let mut app = rope();
    let before = solver(&app).x().to_vec();
    write(app.world_mut());
    // The app's own loop: RunFixedMainLoop sizes the tick from dt, then the fixed ticks run.
    for _ in 0..3 {
        app.update();
    }
    advance(app.world_mut(), 100);
    let p = problem(&app).unwrap_or_else(|| panic!("{what}: not caught"));
    assert_eq!(p.field, field, "{what}: {p}");
    assert!(app.world().resource::<SimParams>().paused, "{what}: paused");
    assert_eq!(
        solver(&app).x(),
        before,
        "{what}: the last good state stays"
    );
    assert!(solver(&app).state_is_finite(), "{what}");
    let text = p.to_string();
    assert!(
        text.contains(field),
        "{what}: the message names the field: {text}"
    );

    mend(app.world_mut());
    app.world_mut().resource_mut::<SimParams>().paused = false;
    advance(app.world_mut(), 100);
    assert_eq!(problem(&app), None, "{what}: mended");
    assert_eq!(*app.world().resource::<SimStatus>(), SimStatus::Running);
    assert!(solver(&app).x() != before, "{what}: it runs again");
}

fn params(f: impl Fn(&mut SimParams)) -> impl Fn(&mut World) {
    move |w: &mut World| f(&mut w.resource_mut::<SimParams>())
}

#[test]
fn bad_parameters_pause_with_their_name_and_never_panic() {
    let ok = SimParams::default();
    for (what, dt) in [
        ("dt 0", 0.0),
        ("dt < 0", -1e-4),
        ("dt NaN", f64::NAN),
        ("dt inf", f64::INFINITY),
        // Past what a clock of whole nanoseconds holds (avian's panicked at it).
        ("dt 1e19", 1e19),
    ] {
        rejects(
            what,
            "SimParams.dt",
            params(move |p| p.dt = dt),
            params(|p| p.dt = 1e-4),
        );
    }
    rejects(
        "NaN gravity",
        "SimParams.gravity.y",
        params(|p| p.gravity.y = f64::NAN),
        params(move |p| p.gravity = ok.gravity),
    );
    rejects(
        "negative damping",
        "SimParams.damping",
        params(|p| p.damping = -1.0),
        params(|p| p.damping = 10.0),
    );
    rejects(
        "infinite ground",
        "SimParams.ground",
        params(|p| p.ground = Some(f64::INFINITY)),
        params(|p| p.ground = Some(0.0)),
    );
    rejects(
        "NaN stiffness override",
        "SimParams.stiffness_override",
        params(|p| p.stiffness_override = Some(f64::NAN)),
        params(|p| p.stiffness_override = None),
    );
    rejects(
        "negative stiffness override",
        "SimParams.stiffness_override",
        params(|p| p.stiffness_override = Some(-5.0)),
        params(|p| p.stiffness_override = Some(5000.0)),
    );
    rejects(
        "a NaN tick",
        "TickPlan.target_tick_seconds",
        |w| w.resource_mut::<TickPlan>().target_tick_seconds = f64::NAN,
        |w| w.resource_mut::<TickPlan>().target_tick_seconds = 1.0 / 120.0,
    );
    rejects(
        "a negative CG tolerance",
        "CgSettings.tolerance",
        |w| w.resource_mut::<CgSettings>().tolerance = -1.0,
        |w| w.resource_mut::<CgSettings>().tolerance = 1e-8,
    );
    rejects(
        "zero tearing strain",
        "SimParams.tear",
        params(|p| p.tear = Some(0.0)),
        params(|p| p.tear = None),
    );
}

fn nth<T: Component>(w: &mut World, n: usize) -> Entity {
    let mut all: Vec<Entity> = w.query_filtered::<Entity, With<T>>().iter(w).collect();
    all.sort();
    all[n]
}

#[test]
fn bad_components_pause_with_their_name() {
    for (what, m) in [
        ("zero mass", 0.0),
        ("negative mass", -1.0),
        ("NaN mass", f64::NAN),
    ] {
        rejects(
            what,
            "Mass",
            move |w| {
                let e = nth::<Particle>(w, 3);
                w.entity_mut(e).insert(Mass(m));
            },
            |w| {
                let e = nth::<Particle>(w, 3);
                w.entity_mut(e).insert(Mass(1.0));
            },
        );
    }
    let spring_edit = |f: fn(&mut Spring, &mut World)| {
        move |w: &mut World| {
            let e = nth::<Spring>(w, 2);
            let mut s = *w.get::<Spring>(e).unwrap();
            f(&mut s, w);
            w.entity_mut(e).insert(s);
        }
    };
    let mend = |w: &mut World| {
        let e = nth::<Spring>(w, 2);
        w.despawn(e);
    };
    rejects(
        "NaN spring stiffness",
        "Spring.stiffness",
        spring_edit(|s, _| s.stiffness = f64::NAN),
        mend,
    );
    rejects(
        "negative rest length",
        "Spring.rest",
        spring_edit(|s, _| s.rest = -0.1),
        mend,
    );
    rejects(
        "a spring to itself",
        "Spring.b",
        spring_edit(|s, _| s.b = s.a),
        mend,
    );
    rejects(
        "a spring to a non-particle",
        "Spring.b",
        spring_edit(|s, w| s.b = w.spawn_empty().id()),
        mend,
    );
}

/// A NaN position written by user code still ends in the blow-up status, not in a panic.
#[test]
fn a_nan_position_is_a_blow_up_not_a_panic() {
    let mut app = rope();
    let e = nth::<Particle>(app.world_mut(), 4);
    app.world_mut()
        .entity_mut(e)
        .insert(Position(DVec2::new(f64::NAN, 0.5)));
    advance(app.world_mut(), 100);
    assert!(matches!(
        *app.world().resource::<SimStatus>(),
        SimStatus::BlewUp { .. }
    ));
}

/// A spring left dangling by a despawned particle is no input problem (the solver leaves it
/// out), and does not keep a mended problem standing.
#[test]
fn a_dangling_spring_does_not_keep_the_simulation_paused() {
    let mut app = rope();
    let victim = nth::<Particle>(app.world_mut(), 7);
    app.world_mut().despawn(victim);
    advance(app.world_mut(), 50);
    assert_eq!(problem(&app), None);
    app.world_mut().resource_mut::<SimParams>().dt = 0.0;
    advance(app.world_mut(), 1);
    assert_eq!(problem(&app).map(|p| p.field), Some("SimParams.dt"));
    {
        let mut p = app.world_mut().resource_mut::<SimParams>();
        p.dt = 1e-4;
        p.paused = false;
    }
    assert_eq!(advance(app.world_mut(), 50), 50);
    assert_eq!(*app.world().resource::<SimStatus>(), SimStatus::Running);
}

/// `check` runs the tick's own input check without stepping: a bad edit is caught before any
/// step, and a good scene checked this way steps as it would have.
#[test]
fn check_catches_a_bad_edit_without_stepping() {
    let mut app = rope();
    let e = nth::<Spring>(app.world_mut(), 2);
    let mut s = *app.world().get::<Spring>(e).unwrap();
    s.stiffness = f64::NAN;
    app.world_mut().entity_mut(e).insert(s);
    let steps = app.world().resource::<SimClock>().steps;
    check(app.world_mut()).unwrap();
    let p = problem(&app).expect("caught by check");
    assert_eq!(p.field, "Spring.stiffness", "{p}");
    assert_eq!(app.world().resource::<SimClock>().steps, steps);
    assert!(app.world().resource::<SimParams>().paused);

    let loaded = hooke::scene::presets::resolve("rope").unwrap();
    let (mut checked, mut plain) = (
        hooke::running_app(&loaded).unwrap(),
        hooke::running_app(&loaded).unwrap(),
    );
    check(checked.world_mut()).unwrap();
    assert_eq!(problem(&checked), None);
    advance(checked.world_mut(), 100);
    advance(plain.world_mut(), 100);
    assert_eq!(solver(&checked).x(), solver(&plain).x());
    assert_eq!(solver(&checked).x().len(), 16);
}
