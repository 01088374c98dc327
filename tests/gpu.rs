//! The step on the graphics card (the `gpu` feature), on whatever adapter this machine has:
//! Mesa's software Vulkan (lavapipe) in CI, so that the real shaders are tested there. A
//! machine with no adapter prints why and skips, unless `HOOKE_REQUIRE_GPU` is set (CI sets
//! it): then no adapter is a failure, not a silent pass.
#![cfg(feature = "gpu")]

mod common;
use common::*;
use hooke::scene::presets;
use hooke::sim::{self, Integrator, SimClock, SimParams};
use hooke::solver::gpu::{Gpu, GpuStep, Precision};

/// The card, or `None` (with the reason printed) where this machine has none and none is
/// required.
fn card() -> Option<Gpu> {
    match Gpu::open() {
        Ok(gpu) => {
            println!("adapter: {}", gpu.adapter());
            Some(gpu)
        }
        Err(e) if std::env::var_os("HOOKE_REQUIRE_GPU").is_none() => {
            println!("skipped: {e}");
            None
        }
        Err(e) => panic!("HOOKE_REQUIRE_GPU is set and {e}"),
    }
}

/// Σ(x + y) after 1000 steps, from shared/reference.md (an independent NumPy implementation).
const REFERENCE: [(Integrator, f64); 2] = [
    (Integrator::SymplecticEuler, 998.4039018283542),
    (Integrator::ExplicitEuler, 998.4254532335524),
];

fn cloth32(integrator: Integrator) -> bevy::app::App {
    let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
    scene.integrator = integrator;
    app_with(scene)
}

/// The 32×32 cloth, 1000 steps on the card in f32 (in submits of 1000 and of 7 steps), and
/// in f64 where the adapter has it: the reference sum to 1e-5 relative in f32, 1e-12 in f64.
#[test]
fn cloth32_on_the_card_matches_the_reference_sum() {
    let Some(gpu) = card() else { return };
    for (integrator, expected) in REFERENCE {
        for precision in gpu.precisions() {
            let tolerance = match precision {
                Precision::F32 => 1e-5,
                Precision::F64 => 1e-12,
            };
            for per_read in [1000, 7] {
                let mut app = cloth32(integrator);
                let world = app.world_mut();
                let mut taken = 0;
                while taken < 1000 {
                    let n = per_read.min(1000 - taken);
                    taken += sim::gpu::advance_on_gpu(world, &gpu, precision, n).unwrap();
                }
                assert_eq!(world.resource::<SimClock>().steps, 1000);
                let s = solver(&app);
                let sum: f64 = s.x().iter().map(|p| p.x + p.y).sum();
                let rel = (sum - expected).abs() / expected;
                println!("{integrator} {precision:?} in submits of {per_read}: rel {rel:e}");
                assert!(
                    rel < tolerance,
                    "{integrator} in {precision:?}: Σ(x+y) = {sum}, reference {expected}, rel {rel:e}"
                );
            }
        }
    }
}

/// Every particle of the card's cloth against the CPU's after 1000 steps, in f32: within the
/// f32 tolerance of the cloth's size, and the pinned row exactly where it was.
#[test]
fn the_card_and_the_cpu_agree_particle_by_particle() {
    let Some(gpu) = card() else { return };
    let mut cpu = cloth32(Integrator::SymplecticEuler);
    step(&mut cpu, 1000);
    let mut card_app = cloth32(Integrator::SymplecticEuler);
    sim::gpu::advance_on_gpu(card_app.world_mut(), &gpu, Precision::F32, 1000).unwrap();
    let (a, b) = (solver(&cpu), solver(&card_app));
    let mut worst: f64 = 0.0;
    for i in 0..a.particle_count() {
        worst = worst.max((a.x()[i] - b.x()[i]).length());
        if a.is_pinned(i) {
            assert_eq!(a.x()[i], b.x()[i], "pinned particle {i} moved");
        }
    }
    println!("largest difference: {worst:e} m");
    assert!(worst < 1e-4, "a particle is {worst} m from the CPU's");
}

/// What the card does not run stays on the CPU, and the reason names it.
#[test]
fn the_card_names_what_it_does_not_run() {
    let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
    scene.integrator = Integrator::Bdf2;
    let app = app_with(scene);
    let why = sim::gpu::unsupported(app.world()).expect("BDF2 is not on the card");
    assert!(why.contains("bdf2"), "{why}");
    let pile = app_with(pile_by_outlines());
    let why = sim::gpu::unsupported(pile.world()).expect("the pile collides by outlines");
    assert!(why.contains("contact by outlines"), "{why}");
    let Some(gpu) = card() else { return };
    let mut app = app;
    let before = solver(&app).x().to_vec();
    assert!(sim::gpu::advance_on_gpu(app.world_mut(), &gpu, Precision::F32, 10).is_err());
    assert_eq!(solver(&app).x(), &before[..], "a refused run stepped");
    assert_eq!(
        app.world().resource::<SimParams>().integrator,
        Integrator::Bdf2
    );
    let _ = GpuStep::unsupported;
}

/// The shipped pile with its bodies colliding by their outlines too, which the card does not
/// run.
fn pile_by_outlines() -> hooke::scene::Scene {
    let mut scene = presets::resolve("pile").unwrap().scene.clone();
    if let Some(c) = &mut scene.contact {
        c.outlines = true;
    }
    scene
}

/// Every obstacle's pose (centre, angle), as its entity holds it.
fn poses(app: &mut bevy::app::App) -> Vec<(bevy::math::DVec2, f64)> {
    let world = app.world_mut();
    let mut q = world.query::<&hooke::sim::ObstaclePose>();
    q.iter(world).map(|p| (p.center, p.angle)).collect()
}

/// Particle by particle, the card's state against the CPU's after the same steps: the largest
/// position difference, m.
fn difference(cpu: &bevy::app::App, card: &bevy::app::App) -> f64 {
    let (a, b) = (solver(cpu), solver(card));
    a.x()
        .iter()
        .zip(b.x())
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

/// A loose grid of 8×8 particles (springs to its neighbours) on the ground, swept by a box
/// that moves and turns through it, with friction, restitution and a radius: every part of the
/// card's contact pass at once (the swept test, a turned box, a moving surface, the ground's
/// contact).
fn swept_grid(integrator: Integrator) -> bevy::app::App {
    let mut scene = bare_scene(integrator, 1e-4);
    scene.damping = 0.5;
    scene.ground = Some(0.0);
    scene.generate = vec![hooke::scene::Generator::Grid {
        cols: 8,
        rows: 8,
        min: (0.3, 0.012),
        max: (0.6, 0.3),
        mass: 0.02,
        stiffness: 300.0,
        shear: true,
        pin: hooke::scene::Pin::None,
        vel: (0.0, 0.0),
        damping: None,
        plastic: None,
    }];
    scene.obstacles = vec![
        hooke::scene::ObstacleDef::Box {
            center: (0.15, 0.1),
            half: (0.05, 0.08),
            angle: 0.3,
        },
        hooke::scene::ObstacleDef::Circle {
            center: (0.8, 0.1),
            radius: 0.06,
        },
        hooke::scene::ObstacleDef::Segment {
            a: (0.2, 0.5),
            b: (0.7, 0.4),
            thickness: 0.0,
        },
    ];
    scene.contact = Some(hooke::sim::ContactSettings {
        radius: 0.01,
        friction: 0.4,
        restitution: 0.5,
        particles: false,
        outlines: false,
    });
    let mut app = app_with(scene);
    let world = app.world_mut();
    let mut q = world.query::<(&hooke::sim::Obstacle, &mut hooke::sim::ObstacleVelocity)>();
    for (o, mut v) in q.iter_mut(world) {
        if matches!(o.0, hooke::solver::Shape::Box { .. }) {
            v.linear = bevy::math::DVec2::new(1.5, 0.2);
            v.angular = 2.0;
        }
    }
    app
}

/// Makes one case's app.
type Make = dyn Fn() -> bevy::app::App;

/// Obstacles and the ground's contact on the card against the CPU's f64: the shipped cloth on
/// a ball (0.6 s, draped on it), the slope's sliding phase (0.5 s: later its steep box meets
/// the corner at the slope's foot, where a difference at round-off decides which way it tips),
/// the shipped paddle (0.4 s: the strip lands on the turning paddle; at 0.6 s, sliding off it at
/// friction's limit, f32's round-off has grown to 2 mm, f64 still at 6e-12 m) and a grid swept
/// by a moving, turning box (0.2 s, the box through the grid). In f64 to 1e-9 m, with the same
/// contacts in the last step; in f32 to a millimetre.
#[test]
fn obstacles_on_the_card_match_the_cpu() {
    let Some(gpu) = card() else { return };
    fn shipped(name: &str) -> bevy::app::App {
        let mut s = presets::resolve(name).unwrap().scene.clone();
        s.integrator = Integrator::SymplecticEuler;
        app_with(s)
    }
    let cases: [(&str, Box<Make>, u64, f64); 4] = [
        (
            "cloth_on_ball",
            Box::new(|| shipped("cloth_on_ball")),
            6000,
            1e-3,
        ),
        ("slope", Box::new(|| shipped("slope")), 5000, 1e-3),
        ("paddle", Box::new(|| shipped("paddle")), 4000, 1e-3),
        (
            "swept grid",
            Box::new(|| swept_grid(Integrator::SymplecticEuler)),
            2000,
            1e-3,
        ),
    ];
    for (name, make, steps, f32_tolerance) in cases {
        let mut cpu = make();
        step(&mut cpu, steps);
        let cpu_contacts = cpu.world().resource::<sim::Obstacles>().contacts.surfaces;
        assert!(cpu_contacts > 0, "{name}: nothing touched anything");
        for precision in gpu.precisions() {
            let mut on_card = make();
            let taken =
                sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, steps).unwrap();
            assert_eq!(taken, steps);
            let d = difference(&cpu, &on_card);
            let contacts = on_card
                .world()
                .resource::<sim::Obstacles>()
                .contacts
                .surfaces;
            println!(
                "{name} {precision:?}: {d:e} m, {contacts} contacts ({cpu_contacts} on the CPU)"
            );
            let tolerance = match precision {
                Precision::F32 => f32_tolerance,
                Precision::F64 => {
                    assert_eq!(contacts, cpu_contacts, "{name}: contacts in the last step");
                    1e-9
                }
            };
            assert!(
                d < tolerance,
                "{name} in {precision:?}: a particle {d} m off the CPU's"
            );
        }
    }
    // The moving box's pose comes back to its entity, as the CPU's step writes it.
    let mut a = swept_grid(Integrator::SymplecticEuler);
    step(&mut a, 100);
    let mut b = swept_grid(Integrator::SymplecticEuler);
    sim::gpu::advance_on_gpu(b.world_mut(), &gpu, Precision::F32, 100).unwrap();
    assert_eq!(poses(&mut a), poses(&mut b));
}

/// Dashpots on the card: the shipped soft box with a dashpot of 2 N·s/m on every spring, 0.5 s,
/// against the CPU's f64 (in f64 to 1e-12 m, in f32 to 0.1 mm), where the dashpots move the
/// box by a centimetre.
#[test]
fn dashpots_on_the_card_match_the_cpu() {
    let Some(gpu) = card() else { return };
    let soft_box = |c: f64| {
        let mut s = presets::resolve("soft_box").unwrap().scene.clone();
        s.integrator = Integrator::SymplecticEuler;
        s.spring_damping = c;
        app_with(s)
    };
    let mut cpu = soft_box(2.0);
    step(&mut cpu, 5000);
    let mut undamped = soft_box(0.0);
    step(&mut undamped, 5000);
    let effect = difference(&cpu, &undamped);
    assert!(
        effect > 1e-3,
        "the dashpots moved the box by only {effect} m"
    );
    for precision in gpu.precisions() {
        let mut on_card = soft_box(2.0);
        sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, 5000).unwrap();
        let d = difference(&cpu, &on_card);
        println!("{precision:?}: {d:e} m off the CPU (the dashpots' effect {effect:e} m)");
        let tolerance = match precision {
            Precision::F32 => 1e-4,
            Precision::F64 => 1e-12,
        };
        assert!(d < tolerance, "{precision:?}: {d} m off the CPU");
    }
}

/// CPU → card → CPU in the middle of a run loses nothing: the grid swept by a moving, turning
/// box, 700 steps on the CPU, 700 on the card in f64, 700 on the CPU again, ends where 2100 on
/// the CPU end (to 1e-9 m), with the same clock and the box at the same pose.
#[test]
fn switching_to_the_card_and_back_loses_nothing() {
    let Some(gpu) = card() else { return };
    if !gpu.has_f64() {
        println!("skipped: {} has no f64", gpu.adapter());
        return;
    }
    let mut straight = swept_grid(Integrator::SymplecticEuler);
    step(&mut straight, 2100);
    let mut switched = swept_grid(Integrator::SymplecticEuler);
    step(&mut switched, 700);
    sim::gpu::advance_on_gpu(switched.world_mut(), &gpu, Precision::F64, 700).unwrap();
    step(&mut switched, 700);
    let d = difference(&straight, &switched);
    println!("{d:e} m");
    assert!(
        d < 1e-9,
        "a particle is {d} m off the run that stayed on the CPU"
    );
    let clock = |app: &bevy::app::App| *app.world().resource::<SimClock>();
    assert_eq!(clock(&straight).steps, clock(&switched).steps);
    assert!((clock(&straight).time - clock(&switched).time).abs() < 1e-12);
    assert_eq!(poses(&mut straight), poses(&mut switched));
}

/// Tearing on the card: the 32×32 cloth with a tearing strain of 1 %, 3000 steps (two thirds
/// of its springs break as it falls from its pinned row). In f64 the same springs break at the
/// same ticks as on the CPU and every particle ends within 1e-9 m of the CPU's; in f32 the
/// count is within 1 % (a spring at its limit to f32's round-off may break a tick apart).
#[test]
fn tearing_on_the_card_matches_the_cpu() {
    let Some(gpu) = card() else { return };
    let torn_cloth = || {
        let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
        scene.tear = Some(0.01);
        app_with(scene)
    };
    let mut cpu = torn_cloth();
    step(&mut cpu, 3000);
    let torn = |app: &bevy::app::App| app.world().resource::<sim::Tearing>().torn;
    let on_cpu = torn(&cpu);
    assert!(on_cpu > 1000, "only {on_cpu} springs tore");
    for precision in gpu.precisions() {
        let mut on_card = torn_cloth();
        sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, 3000).unwrap();
        let d = difference(&cpu, &on_card);
        let n = torn(&on_card);
        println!("{precision:?}: {n} torn ({on_cpu} on the CPU), {d:e} m");
        // The torn springs are gone from the world and from the packed state.
        let springs = on_card
            .world_mut()
            .query::<&hooke::sim::Spring>()
            .iter(on_card.world())
            .count();
        assert_eq!(springs as u64, 3906 - n);
        assert_eq!(solver(&on_card).spring_count(), springs);
        match precision {
            Precision::F64 => {
                assert_eq!(n, on_cpu);
                assert!(d < 1e-9, "a particle is {d} m off the CPU's");
            }
            Precision::F32 => {
                assert!(
                    n.abs_diff(on_cpu) * 100 <= on_cpu,
                    "{n} torn against {on_cpu}"
                );
            }
        }
    }
}

/// The card's summary (`GpuStep::summary`, what the app reads each tick in place of the state):
/// the 32×32 cloth tearing at 1 % strain, its top row pinned and a dashpot on every spring,
/// 1500 steps on the card. Its energy by kind is the sum over the state read back (the torn
/// springs left out: their links on the card carry nothing), to 1e-9 relative in f64 and 1e-4
/// in f32; it counts torn links exactly when springs tore, and none once they are taken.
#[test]
fn the_cards_summary_is_its_states_energy() {
    let Some(gpu) = card() else { return };
    for precision in gpu.precisions() {
        let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
        scene.tear = Some(0.01);
        scene.spring_damping = 1.0;
        let mut app = app_with(scene);
        let world = app.world_mut();
        let mut step = sim::gpu::card_for(world, &gpu, precision).unwrap();
        let quiet = step.summary(bevy::math::DVec2::new(0.0, -9.8)).unwrap();
        assert_eq!(quiet.torn_links, 0, "{precision:?}: torn before a step");
        step.run(1500);
        step.tear_now();
        let g = world.resource::<SimParams>().gravity;
        let summary = step.summary(g).unwrap();
        step.read_into(&mut world.resource_mut::<sim::Solver>())
            .unwrap();
        let torn = step.torn_springs().unwrap();
        let s = world.resource::<sim::Solver>();
        let (mut kinetic, mut gravity, mut springs) = (0.0, 0.0, 0.0);
        for ((x, v), m) in s.x().iter().zip(s.v()).zip(s.mass()) {
            kinetic += 0.5 * m * v.length_squared();
            gravity -= m * g.dot(*x);
        }
        for (i, sp) in s.springs().iter().enumerate() {
            if torn.binary_search(&i).is_err() {
                let stretch = (s.x()[sp.a as usize] - s.x()[sp.b as usize]).length() - sp.rest;
                springs += 0.5 * sp.k * stretch * stretch;
            }
        }
        let e = summary.energy;
        let tolerance = match precision {
            Precision::F32 => 1e-4,
            Precision::F64 => 1e-9,
        };
        let scale = kinetic.abs() + gravity.abs() + springs.abs();
        for (name, card, cpu) in [
            ("kinetic", e.kinetic, kinetic),
            ("gravity", e.potential_gravity, gravity),
            ("springs", e.potential_springs, springs),
        ] {
            let rel = (card - cpu).abs() / scale;
            println!("{precision:?} {name}: card {card} cpu {cpu} rel {rel:e}");
            assert!(
                rel < tolerance,
                "{precision:?} {name}: {card} against {cpu}"
            );
        }
        println!(
            "{precision:?}: {} torn links, {} springs",
            summary.torn_links,
            torn.len()
        );
        assert!(!torn.is_empty(), "{precision:?}: nothing tore");
        assert_eq!(summary.torn_links, 2 * torn.len() as u64);
        assert_eq!(step.summary(g).unwrap().torn_links, 0);
    }
}

/// Tearing inside the tick on the card with the state read on demand (the app's way: the card
/// tears, its summary says so, the state comes back and the springs' entities go): the cloth
/// tearing at 1 % strain, 3000 steps, against the CPU's ticks: in f64 the same springs torn and
/// the same state to 1e-9 m; and while nothing needed the state, it was not read.
#[test]
fn tearing_on_the_card_in_the_tick_matches_the_cpu() {
    let Some(gpu) = card() else { return };
    if !gpu.has_f64() {
        println!("skipped: {} has no f64", gpu.adapter());
        return;
    }
    let torn_cloth = || {
        let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
        scene.tear = Some(0.01);
        app_with(scene)
    };
    let torn = |app: &bevy::app::App| app.world().resource::<sim::Tearing>().torn;
    let mut cpu = torn_cloth();
    step(&mut cpu, 3000);
    let mut app = torn_cloth();
    {
        let mut card = app.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.use_card(gpu.clone());
        card.precision = Some(Precision::F64);
        card.wanted = true;
        Reads::OnDemand.set(&mut card);
    }
    step(&mut app, 3000);
    sim::gpu::catch_up(app.world_mut()).unwrap();
    let d = difference(&cpu, &app);
    // The last tick's tears are found by the catch-up, and go at the next tick's start.
    let pending = app.world().resource::<sim::Tearing>().pending.len() as u64;
    println!(
        "{} torn and {pending} to go ({} on the CPU), {d:e} m",
        torn(&app),
        torn(&cpu)
    );
    assert!(torn(&cpu) > 1000);
    assert_eq!(torn(&app) + pending, torn(&cpu));
    assert!(d < 1e-9, "a particle is {d} m off the CPU's");
    step(&mut app, 1);
    let springs = app
        .world_mut()
        .query::<&hooke::sim::Spring>()
        .iter(app.world())
        .count();
    assert_eq!(springs as u64, 3906 - torn(&app));
    assert!(torn(&app) >= torn(&cpu));
}

/// With the state read on demand and nothing asking for it, the tick on the card brings back
/// only its summary: the cloth's solver and entities stay where they were while the card
/// steps, the energy the panel and the plots read (`Solver::energy_now`) is the card's, and
/// `catch_up` brings the state level, to 1e-9 m of the CPU's in f64.
#[test]
fn an_untouched_tick_on_the_card_reads_only_its_summary() {
    let Some(gpu) = card() else { return };
    if !gpu.has_f64() {
        println!("skipped: {} has no f64", gpu.adapter());
        return;
    }
    let mut cpu = cloth32(Integrator::SymplecticEuler);
    step(&mut cpu, 2000);
    let mut app = cloth32(Integrator::SymplecticEuler);
    {
        let mut card = app.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.use_card(gpu.clone());
        card.precision = Some(Precision::F64);
        card.wanted = true;
        Reads::OnDemand.set(&mut card);
    }
    step(&mut app, 1000);
    let held = solver(&app).x().to_vec();
    let entity = |app: &mut bevy::app::App| {
        let world = app.world_mut();
        let mut q = world.query::<(&hooke::sim::SolverIndex, &hooke::sim::Position)>();
        q.iter(world).find(|(i, _)| i.0 == 500).unwrap().1.0
    };
    let before = entity(&mut app);
    step(&mut app, 1000);
    assert!(app.world().resource::<sim::gpu::CardStep>().behind());
    assert_eq!(solver(&app).x(), &held[..], "the state came back unasked");
    assert_eq!(entity(&mut app), before);
    // The last tick's summary, taken as the next tick takes it.
    sim::gpu::receive_from_card(app.world_mut());
    assert!(app.world().resource::<sim::gpu::CardStep>().behind());
    assert_eq!(solver(&app).x(), &held[..], "the state came back unasked");
    let g = app.world().resource::<SimParams>().gravity;
    let serial = hooke::solver::Threads::serial();
    let shown = solver(&app).energy_now(g, &serial).total();
    let expected = solver(&cpu).energy_now(g, &serial).total();
    println!("energy: card {shown}, CPU {expected}");
    assert!((shown - expected).abs() < 1e-9 * expected.abs());
    sim::gpu::catch_up(app.world_mut()).unwrap();
    assert!(!app.world().resource::<sim::gpu::CardStep>().behind());
    let d = difference(&cpu, &app);
    println!("{d:e} m");
    assert!(d < 1e-9, "a particle is {d} m off the CPU's");
    assert_eq!(entity(&mut app), solver(&app).x()[500]);
}

/// The fixed tick on the card (`CardStep`, the panel's switch), through the app's own ticks:
/// the grid swept by a moving, turning box, 1000 steps on the card in f64, a particle's
/// `Velocity` set (an edit; with reads on demand, of a world that lags the card), 1000 more on
/// the card, 500 on the CPU with the switch off and 500 on the card again, against the same on
/// the CPU alone (to 1e-9 m, the same clock).
/// A scene the card does not run steps on the CPU with the reason named.
#[test]
fn the_tick_steps_on_the_card_when_switched_and_carries_the_state_over() {
    for reads in Reads::ALL {
        the_tick_steps_on_the_card(reads);
    }
}

/// How the tick on the card brings its state back (`CardStep`'s settings).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reads {
    /// Each tick waits for its state.
    EachTick,
    /// In the background, taken by the next tick.
    Background,
    /// On demand, the app's way: only the summary comes back each tick.
    OnDemand,
}

impl Reads {
    const ALL: [Reads; 3] = [Reads::EachTick, Reads::Background, Reads::OnDemand];

    fn set(self, card: &mut sim::gpu::CardStep) {
        card.background_reads = self != Reads::EachTick;
        card.on_demand = self == Reads::OnDemand;
    }
}

/// The test above, with the state read back as `reads` says (in the background or on demand,
/// the solver is brought level by `catch_up` before each look).
fn the_tick_steps_on_the_card(reads: Reads) {
    let Some(gpu) = card() else { return };
    if !gpu.has_f64() {
        println!("skipped: {} has no f64", gpu.adapter());
        return;
    }
    let level = |app: &mut bevy::app::App| sim::gpu::catch_up(app.world_mut()).unwrap();
    // An edit that reads nothing of the world (a velocity set), so that it means the same on
    // a world that lags the card.
    let nudge = |app: &mut bevy::app::App| {
        let world = app.world_mut();
        let mut q = world.query::<(&hooke::sim::SolverIndex, &mut hooke::sim::Velocity)>();
        for (i, mut v) in q.iter_mut(world) {
            if i.0 == 9 {
                v.0 = bevy::math::DVec2::new(0.5, 0.3);
            }
        }
    };
    let mut cpu = swept_grid(Integrator::SymplecticEuler);
    step(&mut cpu, 1000);
    nudge(&mut cpu);
    step(&mut cpu, 2000);
    let mut app = swept_grid(Integrator::SymplecticEuler);
    let switch = |app: &mut bevy::app::App, on: bool| {
        let mut card = app.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.wanted = on;
    };
    {
        let mut card = app.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.use_card(gpu.clone());
        card.precision = Some(Precision::F64);
        reads.set(&mut card);
    }
    switch(&mut app, true);
    step(&mut app, 1000);
    let card = app.world().resource::<sim::gpu::CardStep>();
    assert!(card.active(), "not on the card: {:?}", card.why_not);
    if reads == Reads::Background {
        // The solver is behind the card until it catches up. (On demand it stays behind:
        // the nudge below is an edit of a world that lags the card, which the tick brings
        // level before it takes the edit.)
        let behind = solver(&app).x().to_vec();
        level(&mut app);
        assert_ne!(
            solver(&app).x(),
            &behind[..],
            "the last tick's state came back at once"
        );
    }
    nudge(&mut app);
    step(&mut app, 1000);
    switch(&mut app, false);
    step(&mut app, 500);
    assert!(!app.world().resource::<sim::gpu::CardStep>().active());
    switch(&mut app, true);
    step(&mut app, 500);
    level(&mut app);
    let d = difference(&cpu, &app);
    println!("{reads:?}: {d:e} m");
    assert!(d < 1e-9, "{reads:?}: a particle is {d} m off the CPU's run");
    assert_eq!(app.world().resource::<SimClock>().steps, 3000);

    let mut pile = app_with(pile_by_outlines());
    {
        let mut card = pile.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.use_card(gpu.clone());
        card.wanted = true;
    }
    step(&mut pile, 100);
    let card = pile.world().resource::<sim::gpu::CardStep>();
    assert!(!card.active());
    let why = card.why_not.clone().unwrap_or_default();
    assert!(why.contains("contact by outlines"), "{why}");
    assert_eq!(pile.world().resource::<SimClock>().steps, 100);
}

/// XPBD on the card: the 32×32 cloth at 1/60 s, 60 steps of 10 substeps, with one sweep, with
/// three, and with dashpots (c = 1), against the CPU's XPBD: in f64 to 1e-12 m (the same
/// colours in the same order: the same Gauss-Seidel sweeps), in f32 to 0.1 mm.
#[test]
fn xpbd_on_the_card_matches_the_cpu() {
    let Some(gpu) = card() else { return };
    let cloth = |sweeps: u32, c: f64| {
        let mut scene = presets::resolve("cloth32").unwrap().scene.clone();
        scene.integrator = Integrator::Xpbd;
        scene.dt = 1.0 / 60.0;
        scene.spring_damping = c;
        let mut app = app_with(scene);
        app.world_mut()
            .resource_mut::<SimParams>()
            .iterations
            .xpbd_sweeps = sweeps;
        app
    };
    for (sweeps, c) in [(1, 0.0), (3, 0.0), (1, 1.0)] {
        let mut cpu = cloth(sweeps, c);
        step(&mut cpu, 60);
        let moved = solver(&cpu)
            .x()
            .iter()
            .map(|p| (1.0 - p.y).abs())
            .fold(0.0, f64::max);
        assert!(moved > 0.05, "the cloth barely moved");
        for precision in gpu.precisions() {
            let mut on_card = cloth(sweeps, c);
            assert_eq!(sim::gpu::unsupported(on_card.world()), None);
            sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, 60).unwrap();
            let d = difference(&cpu, &on_card);
            println!("{sweeps} sweeps, c = {c}, {precision:?}: {d:e} m");
            let tolerance = match precision {
                Precision::F32 => 1e-4,
                Precision::F64 => 1e-12,
            };
            assert!(
                d < tolerance,
                "{precision:?}: a particle {d} m off the CPU's"
            );
        }
    }
}

/// Contact between particles on the card against the CPU's f64: the strip of cloth folding
/// onto the ground and onto itself (0.4 s, its folds pressed together) under symplectic Euler,
/// the pile of boxes and balls (0.3 s, landed on each other) under symplectic and explicit
/// Euler, and the grid swept by a moving box with pairs at a radius of 0.7 spacings (the pairs
/// the box presses together held out of the box and the ground). In f64 to 1e-9 m (explicit Euler, which gains energy, to 1e-6 m) with the CPU's count
/// of touching pairs in the last step; in f32, where the folds and the pile's landings turn
/// f32's round-off into millimetres, to 1 cm and 3 mm. Without the pairs' pass the strip
/// folds through itself, centimetres from the CPU's. In both, no pair is left overlapping by
/// more than the iterations' tolerance, 1 % of 2r.
#[test]
fn pairs_on_the_card_match_the_cpu() {
    let Some(gpu) = card() else { return };
    let make = |name: &str, integrator| {
        if name == "swept grid" {
            let mut app = swept_grid(integrator);
            let mut params = app.world_mut().resource_mut::<SimParams>();
            params.contact.as_mut().unwrap().particles = true;
            params.contact.as_mut().unwrap().radius = 0.03;
            return app;
        }
        let mut s = presets::resolve(name).unwrap().scene.clone();
        s.integrator = integrator;
        app_with(s)
    };
    let cases = [
        (
            "folding_cloth",
            Integrator::SymplecticEuler,
            4000,
            1e-2,
            1e-9,
        ),
        ("pile", Integrator::SymplecticEuler, 3000, 3e-3, 1e-9),
        ("pile", Integrator::ExplicitEuler, 3000, 3e-3, 1e-6),
        ("swept grid", Integrator::SymplecticEuler, 2000, 3e-3, 1e-9),
    ];
    for (name, integrator, steps, f32_tolerance, f64_tolerance) in cases {
        let mut cpu = make(name, integrator);
        step(&mut cpu, steps);
        let cpu_pairs = cpu.world().resource::<sim::Obstacles>().contacts.pairs;
        assert!(cpu_pairs > 0, "{name}: no pair touches");
        for precision in gpu.precisions() {
            let mut on_card = make(name, integrator);
            let taken =
                sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, steps).unwrap();
            assert_eq!(taken, steps);
            let d = difference(&cpu, &on_card);
            let pairs = on_card.world().resource::<sim::Obstacles>().contacts.pairs;
            let contact = 2.0 * cpu.world().resource::<SimParams>().contact.unwrap().radius;
            let (closest, i, j) = closest_unjoined(solver(&on_card));
            let cpu_closest = closest_unjoined(solver(&cpu)).0;
            println!(
                "{name} {integrator} {precision:?}: {d:e} m, {pairs} pairs touching ({cpu_pairs} on the CPU), closest pair at {:.4} of 2r ({:.4} on the CPU)",
                closest / contact,
                cpu_closest / contact
            );
            let tolerance = match precision {
                Precision::F32 => f32_tolerance,
                Precision::F64 => {
                    assert_eq!(pairs, cpu_pairs, "{name}: pairs touching in the last step");
                    f64_tolerance
                }
            };
            assert!(
                d < tolerance,
                "{name} {integrator} in {precision:?}: a particle {d} m off the CPU's"
            );
            // The iterations' own tolerance: no pair overlaps by more than 1 % of 2r.
            assert!(
                closest >= 0.99 * contact,
                "{name} {integrator} in {precision:?}: particles {i} and {j} overlap, {closest} m apart"
            );
        }
    }
}

/// XPBD's contact on the card, inside its substeps as on the CPU, against the CPU's f64 at a
/// frame's step (1/60 s, 10 substeps): the strip of cloth folding onto the ground and itself,
/// the pile of boxes and balls, the cloth draped on the ball and the grid swept by a moving,
/// turning box. In f64 to 1e-9 m with the CPU's contacts, as long as the two find the same
/// pairs and round-off decides nothing. Later they part at once: the CPU's lists for a
/// step bound a pair's closing by its velocity and the body forces, not by its springs, and
/// miss a pair that the strip's fold closes within its 12th step, which the card's grid,
/// rebuilt every substep, finds (its velocities then differ by 0.18 m/s at equal positions;
/// with lists of the whole skin on the CPU the two agree to 2e-13 m/s there); a pair the
/// iterations leave at exactly 2r touches or not by the last bit of a sum; a box that rams
/// the grid with friction holds or slides by it. In f32 at the same steps, to 2 mm. Over the
/// whole fold and landing, in both precisions, every step taken and no pair left overlapping
/// by more than 1 % of 2r. (The energies are printed, not compared: at 1/60 s the strip's is
/// chaotic, 2.1 J on the card in f32, 9.3 J in f64 and 9.0 J on the CPU at 1.5 s.)
#[test]
fn xpbd_contact_on_the_card_matches_the_cpu() {
    let Some(gpu) = card() else { return };
    let dt = 1.0 / 60.0;
    let make = |name: &str| -> bevy::app::App {
        let mut app = match name {
            "folding strip" => app_with(folding_strip(Integrator::Xpbd, dt).0),
            "swept grid" => swept_grid(Integrator::Xpbd),
            _ => {
                let mut s = presets::resolve(name).unwrap().scene.clone();
                s.integrator = Integrator::Xpbd;
                app_with(s)
            }
        };
        app.world_mut().resource_mut::<SimParams>().dt = dt;
        app
    };
    let energy = |app: &bevy::app::App| {
        let g = app.world().resource::<SimParams>().gravity;
        solver(app).energy(g).total()
    };
    // (scene, steps that round-off decides nothing in, steps of the whole run)
    for (name, exact, whole) in [
        ("folding strip", 11, 90),
        ("pile", 20, 60),
        ("cloth_on_ball", 60, 60),
        ("swept grid", 10, 30),
    ] {
        for steps in [exact, whole] {
            let mut cpu = make(name);
            let start = energy(&cpu);
            step(&mut cpu, steps);
            let cpu_contacts = cpu.world().resource::<sim::Obstacles>().contacts;
            for precision in gpu.precisions() {
                let mut on_card = make(name);
                let taken =
                    sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, steps).unwrap();
                assert_eq!(taken, steps);
                let d = difference(&cpu, &on_card);
                let contacts = on_card.world().resource::<sim::Obstacles>().contacts;
                let radius = on_card
                    .world()
                    .resource::<SimParams>()
                    .contact
                    .unwrap()
                    .radius;
                let closest = closest_unjoined(solver(&on_card)).0 / (2.0 * radius);
                let (e_cpu, e_card) = (energy(&cpu), energy(&on_card));
                println!(
                    "{name}, {steps} steps, {precision:?}: {d:e} m; {} surface contacts and {} pairs ({} and {} on the CPU); closest pair {closest:.4} of 2r; energy {e_card:.4} J ({e_cpu:.4} J on the CPU, {start:.4} J at the start)",
                    contacts.surfaces, contacts.pairs, cpu_contacts.surfaces, cpu_contacts.pairs
                );
                if steps == exact {
                    let tolerance = match precision {
                        Precision::F32 => 2e-3,
                        Precision::F64 => {
                            let counts = |c: hooke::solver::Contacts| (c.surfaces, c.pairs);
                            assert_eq!(counts(contacts), counts(cpu_contacts), "{name}: contacts");
                            1e-9
                        }
                    };
                    assert!(
                        d < tolerance,
                        "{name} in {precision:?}: {d} m off the CPU's"
                    );
                }
                let pairs = on_card
                    .world()
                    .resource::<SimParams>()
                    .contact
                    .unwrap()
                    .particles;
                assert!(
                    !pairs || closest >= 0.99,
                    "{name} in {precision:?}: a pair at {closest} of 2r"
                );
            }
        }
    }
}

/// A push past a surface on the card goes back out on the side it came from, as on the CPU:
/// a 10 g particle resting on a plank with a 10 kg one landing on it, 3 mm off its centre (the
/// pair pass pushes the light one by up to 3r, across the plank's line:
/// tests/frame_step_contact.rs), under XPBD and symplectic Euler at 1/60 and 1/30 s, the
/// plank a segment of no thickness and a slab r thick; a particle resting on the slab, and on
/// a disc of radius r, struck into it at 10 m/s; and a particle that starts on a box's
/// face and ends its step past the box's middle, under symplectic Euler at 1e-2 s. Out by the
/// nearest surface, the light particle went through the plank and the other out through the
/// box's far side; with no swept test from a start in contact, the struck one went through
/// the slab and the disc. Under symplectic Euler against the CPU's f64 too: the box in f64 to
/// 1e-9 m, the others to 1e-5 m; in f32 to a millimetre.
#[test]
fn a_push_past_a_surface_on_the_card_stays_on_its_side() {
    let Some(gpu) = card() else { return };
    let (level, r) = PLANK;
    let plank = move |integrator, dt, speed, above, slab| {
        let mut scene = landing_on_a_plank(integrator, dt, speed, above).expect("starts apart");
        if slab {
            plank_as_slab(&mut scene);
        }
        app_with(scene)
    };
    // A particle at rest on the slab (or on a disc whose top is at the plank's level), set
    // moving into it.
    let struck = move |integrator, dt, speed: f64, disc: bool| {
        let mut scene = landing_on_a_plank(integrator, dt, 1.0, r).expect("starts apart");
        if disc {
            scene.obstacles = vec![hooke::scene::ObstacleDef::Circle {
                center: (0.5, level - r),
                radius: r,
            }];
        } else {
            plank_as_slab(&mut scene);
        }
        scene.particles.truncate(1);
        scene.particles[0].vel = (0.0, -speed);
        app_with(scene)
    };
    let through_box = move || {
        let mut scene = bare_scene(Integrator::SymplecticEuler, 0.01);
        // On the box's left face (x = 0.45), heading right at 7 m/s: 7 cm in the step, past
        // the middle of the 10 cm box.
        let mut p = particle(0.45 - r, 0.5, false);
        p.vel = (7.0, 0.0);
        let mut q = particle(0.1, 0.1, false);
        q.mass = 0.5;
        scene.particles = vec![p, q];
        scene.obstacles = vec![hooke::scene::ObstacleDef::Box {
            center: (0.5, 0.5),
            half: (0.05, 0.05),
            angle: 0.0,
        }];
        scene.contact = Some(hooke::sim::ContactSettings {
            radius: r,
            ..Default::default()
        });
        app_with(scene)
    };
    let mut cases: Vec<(String, Box<Make>, u64)> = vec![];
    for integrator in [Integrator::SymplecticEuler, Integrator::Xpbd] {
        for dt in [1.0 / 60.0, 1.0 / 30.0] {
            for slab in [false, true] {
                // On the slab, a landing that ends its free fall 0.2r above: symplectic Euler's
                // step at 1/30 s carries the light particle into the slab before the pair
                // pass pushes it (tests/frame_step_contact.rs).
                let landings: &[(f64, f64)] = if slab {
                    &[(3.0, 0.2 * r), (10.0, 1.5 * r)]
                } else {
                    &[(3.0, 0.5 * r), (3.0, r), (10.0, 1.5 * r)]
                };
                for &(speed, above) in landings {
                    let what = if slab { "slab" } else { "plank" };
                    let name = format!(
                        "{integrator} at {dt:.4} s, the {what}, {speed} m/s, {above} m above"
                    );
                    cases.push((
                        name,
                        Box::new(move || plank(integrator, dt, speed, above, slab)),
                        6,
                    ));
                }
            }
            for disc in [false, true] {
                let what = if disc { "disc" } else { "slab" };
                let name = format!("{integrator} at {dt:.4} s, the {what} struck at 10 m/s");
                cases.push((
                    name,
                    Box::new(move || struck(integrator, dt, 10.0, disc)),
                    3,
                ));
            }
        }
    }
    cases.push(("the box".into(), Box::new(through_box), 1));
    let mut passes = 0;
    for (name, make, steps) in &cases {
        let mut cpu = make();
        step(&mut cpu, *steps);
        for precision in gpu.precisions() {
            let mut on_card = make();
            let mut lowest = f64::INFINITY;
            for _ in 0..*steps {
                sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, 1).unwrap();
                let p = pos(&on_card, 0);
                if (0.0..=1.0).contains(&p.x) {
                    lowest = lowest.min(p.y);
                }
            }
            let worst = difference(&cpu, &on_card);
            let end = pos(&on_card, 0);
            println!("{name} {precision:?}: {worst:e} m off the CPU's, ends at {end}");
            if name == "the box" {
                assert!(
                    end.x <= 0.45 - r + 1e-6,
                    "{precision:?}: out of the box at {end}, not on its left"
                );
            } else {
                assert!(
                    lowest >= level,
                    "{name} in {precision:?}: the particle at y = {lowest}, under the surface"
                );
                passes += 1;
            }
            if name.starts_with("xpbd") {
                // The card's grid, rebuilt each substep, and the CPU's lists for the step find
                // the landing pair at different substeps: the light particle leaves sideways at
                // speeds microns apart in f64 (`xpbd_contact_on_the_card_matches_the_cpu`).
                continue;
            }
            let tolerance = match precision {
                Precision::F32 => 1e-3,
                // The light particle, squeezed between the plank and a body 1000 times its
                // mass, is 6e-7 m from the CPU's after the first step of one drop (under the
                // contact's slop of 1e-6 m), the others' within 3e-8 m.
                Precision::F64 if name != "the box" => 1e-5,
                Precision::F64 => 1e-9,
            };
            assert!(worst < tolerance, "{name} in {precision:?}: {worst} m off");
        }
    }
    assert!(passes >= 28, "{passes}");
}

/// An obstacle moving at a frame's step strikes a particle in its way on the card as on the
/// CPU (`tests/frame_step_contact.rs`): a slab r thick, a disc of radius r and a segment coming
/// down at 10 m/s onto a particle at rest, touching it halfway through the first step, under
/// symplectic and explicit Euler and XPBD at 1/60 and 1/30 s (XPBD's substeps move each
/// obstacle a substep at a time, on the card as on the CPU). The particle stays ahead of each,
/// and where the CPU puts it: in f64 to 1e-9 m, in f32 to a millimetre. (A turning obstacle's
/// carry is `obstacles_on_the_card_match_the_cpu`'s swept grid.)
#[test]
fn a_moving_obstacle_on_the_card_strikes_what_is_in_its_way() {
    use hooke::scene::ObstacleDef;
    let Some(gpu) = card() else { return };
    let r = 0.01;
    let speed = 10.0;
    let make = move |integrator, dt: f64, shape: usize| {
        let mut scene = bare_scene(integrator, dt);
        scene.gravity = (0.0, 0.0);
        // Each about (0.5, 0.4), and its half-thickness.
        let (obstacle, half) = match shape {
            0 => (
                ObstacleDef::Box {
                    center: (0.5, 0.4),
                    half: (0.3, 0.5 * r),
                    angle: 0.0,
                },
                0.5 * r,
            ),
            1 => (
                ObstacleDef::Circle {
                    center: (0.5, 0.4),
                    radius: r,
                },
                r,
            ),
            _ => (
                ObstacleDef::Segment {
                    a: (0.2, 0.4),
                    b: (0.8, 0.4),
                    thickness: 0.0,
                },
                0.0,
            ),
        };
        let below = 0.4 - half - r - 0.5 * speed * dt;
        scene.particles = vec![particle(0.5, below, false)];
        scene.obstacles = vec![obstacle];
        scene.contact = Some(hooke::sim::ContactSettings {
            radius: r,
            friction: 0.5,
            ..Default::default()
        });
        let mut app = app_with(scene);
        let world = app.world_mut();
        for mut v in world
            .query::<&mut hooke::sim::ObstacleVelocity>()
            .iter_mut(world)
        {
            v.linear = bevy::math::DVec2::new(0.0, -speed);
        }
        app
    };
    let mut runs = 0;
    let methods = [
        Integrator::SymplecticEuler,
        Integrator::ExplicitEuler,
        Integrator::Xpbd,
    ];
    for integrator in methods {
        for dt in [1.0 / 60.0, 1.0 / 30.0] {
            for (shape, what) in ["slab", "disc", "segment"].iter().enumerate() {
                let steps = 4;
                let mut cpu = make(integrator, dt, shape);
                step(&mut cpu, steps);
                for precision in gpu.precisions() {
                    let mut on_card = make(integrator, dt, shape);
                    sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, steps).unwrap();
                    let end = pos(&on_card, 0);
                    let ahead = (0.4 - speed * dt * steps as f64) - end.y;
                    let worst = difference(&cpu, &on_card);
                    let name = format!("{integrator} at {dt:.4} s, the {what}, {precision:?}");
                    println!("{name}: {worst:e} m off the CPU's, {ahead} m ahead of its centre");
                    assert!(ahead > 0.0, "{name}: behind it at {end}");
                    let tolerance = match precision {
                        Precision::F32 => 1e-3,
                        Precision::F64 => 1e-9,
                    };
                    assert!(worst < tolerance, "{name}: {worst} m off");
                    runs += 1;
                }
            }
        }
    }
    assert!(runs >= 12, "{runs}");
}

/// A moving platform carries what rests on it by friction on the card as on the CPU
/// (`tests/contact.rs`): a particle on a box moving right at 0.5 m/s, or up and right at
/// 0.5 m/s each way, friction μ = 1, under symplectic and explicit Euler and XPBD at 1/60 s.
/// After half a second the particle moves with the platform and rests on it, and sits where
/// the CPU puts it: in f64 to 1e-9 m, in f32 to 1e-4 m. XPBD's substeps move the platform a
/// substep at a time, and friction reads a substep's slide of it: read against a step's, the
/// particle was dragged off.
#[test]
fn a_moving_platform_on_the_card_carries_what_rests_on_it() {
    use hooke::sim::{Obstacle, ObstaclePose, ObstacleVelocity};
    use hooke::solver::Shape;
    let Some(gpu) = card() else { return };
    let (r, dt, steps) = (0.01, 1.0 / 60.0, 30);
    let center = bevy::math::DVec2::new(0.5, 0.25);
    let make = move |integrator, velocity| {
        let mut scene = bare_scene(integrator, dt);
        scene.gravity = (0.0, -9.8);
        scene.particles = vec![particle(0.5, 0.25 + 0.05 + r, false)];
        scene.contact = Some(hooke::sim::ContactSettings {
            radius: r,
            friction: 1.0,
            ..Default::default()
        });
        let mut app = app_with(scene);
        app.world_mut().spawn((
            Obstacle(Shape::Box {
                half: bevy::math::DVec2::new(0.5, 0.05),
            }),
            ObstaclePose { center, angle: 0.0 },
            ObstacleVelocity {
                linear: velocity,
                angular: 0.0,
            },
        ));
        app
    };
    let mut runs = 0;
    let methods = [
        Integrator::SymplecticEuler,
        Integrator::ExplicitEuler,
        Integrator::Xpbd,
    ];
    for integrator in methods {
        for velocity in [
            bevy::math::DVec2::new(0.5, 0.0),
            bevy::math::DVec2::new(0.5, 0.5),
        ] {
            let mut cpu = make(integrator, velocity);
            step(&mut cpu, steps);
            for precision in gpu.precisions() {
                let mut on_card = make(integrator, velocity);
                sim::gpu::advance_on_gpu(on_card.world_mut(), &gpu, precision, steps).unwrap();
                let worst = difference(&cpu, &on_card);
                let name = format!("{integrator} at {velocity} m/s, {precision:?}");
                let (v, at) = (vel(&on_card, 0), pos(&on_card, 0));
                let top = center.y + velocity.y * steps as f64 * dt + 0.05 + r;
                println!(
                    "{name}: {worst:e} m off the CPU's, at {v} m/s, {} m over its top",
                    at.y - top
                );
                assert!((v - velocity).length() < 1e-3, "{name}: carried at {v}");
                assert!(
                    (at.y - top).abs() < 1e-4,
                    "{name}: at {at}, its top at {top}"
                );
                let tolerance = match precision {
                    Precision::F32 => 1e-4,
                    Precision::F64 => 1e-9,
                };
                assert!(worst < tolerance, "{name}: {worst} m off");
                runs += 1;
            }
        }
    }
    assert!(runs >= 6, "{runs}");
}

/// A particle held and dragged (`Kinematic`, its `Position` moved between ticks, as the app's
/// grab does) while the card steps: the card takes each new position, so the cloth follows the
/// drag as on the CPU (in f64, to 1e-9 m); with the state read back each tick and in the
/// background.
#[test]
fn a_drag_reaches_the_card() {
    for reads in Reads::ALL {
        a_drag_on_the_card(reads);
    }
}

fn a_drag_on_the_card(reads: Reads) {
    let Some(gpu) = card() else { return };
    if !gpu.has_f64() {
        println!("skipped: {} has no f64", gpu.adapter());
        return;
    }
    let drag = |app: &mut bevy::app::App| {
        let world = app.world_mut();
        let held = {
            let mut q = world.query::<(bevy::prelude::Entity, &hooke::sim::SolverIndex)>();
            q.iter(world)
                .find(|(_, i)| i.0 == 9)
                .map(|(e, _)| e)
                .unwrap()
        };
        world.entity_mut(held).insert(hooke::sim::Kinematic);
        for _ in 0..5 {
            let mut p = world.get_mut::<hooke::sim::Position>(held).unwrap();
            p.0.x += 0.02;
            p.0.y += 0.01;
            let taken = sim::advance(world, 200);
            assert_eq!(taken, 200);
        }
    };
    let mut cpu = swept_grid(Integrator::SymplecticEuler);
    step(&mut cpu, 100);
    drag(&mut cpu);
    let mut app = swept_grid(Integrator::SymplecticEuler);
    {
        let mut card = app.world_mut().resource_mut::<sim::gpu::CardStep>();
        card.use_card(gpu.clone());
        card.precision = Some(Precision::F64);
        card.wanted = true;
        reads.set(&mut card);
    }
    step(&mut app, 100);
    assert!(app.world().resource::<sim::gpu::CardStep>().active());
    drag(&mut app);
    sim::gpu::catch_up(app.world_mut()).unwrap();
    let d = difference(&cpu, &app);
    println!("{reads:?}: {d:e} m");
    assert!(
        d < 1e-9,
        "{reads:?}: a particle is {d} m off the CPU's drag"
    );
}

/// The card draws its state (`Painter`): after 300 steps of the cloth32 on the card, each
/// particle's hexagon is centred on its position and each spring's quad spans its ends, to
/// f32's rounding, the pinned row in the pinned colour; written at an unaligned place in a
/// larger buffer, whose other bytes stay as they were.
#[test]
fn the_card_draws_its_state() {
    use hooke::solver::gpu::{
        DOT_CORNERS, DrawStyle, DrawTarget, DrawTargets, Painter, SPRING_CORNERS, VERTEX_BYTES,
    };
    let Some(gpu) = card() else { return };
    let mut app = cloth32(Integrator::SymplecticEuler);
    sim::gpu::advance_on_gpu(app.world_mut(), &gpu, Precision::F32, 300).unwrap();
    // The state after them, on the card again.
    let step = sim::gpu::card_for(app.world_mut(), &gpu, Precision::F32).unwrap();
    let state = solver(&app).state();
    let source = step.draw_source().expect("cloth32 fits");
    let (n, springs) = (source.particles(), source.springs());
    let (spring_vertices, dot_vertices) = (springs * SPRING_CORNERS, n * DOT_CORNERS);
    // The springs from vertex 3, the dots after them and 5 more: offsets no binding aligns to.
    let (spring_at, dot_at) = (3, 3 + spring_vertices + 5);
    let total = u64::from(dot_at + dot_vertices + 2) * VERTEX_BYTES;
    let device = gpu.device();
    let fill = 0x7fu8;
    let target = wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &vec![fill; total as usize],
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        },
    );
    let (free, pinned) = ([1.0, 1.0, 1.0, 1.0], [1.0, 0.5, 0.0, 1.0]);
    let style = DrawStyle {
        half_width: 0.001,
        radius: 0.004,
        full_strain: 0.05,
        palette: vec![
            [0.0, 0.0, 1.0, 1.0],
            [0.5, 0.5, 0.5, 1.0],
            [1.0, 0.0, 0.0, 1.0],
        ],
        free,
        pinned,
        held_colour: [0.0, 1.0, 1.0, 1.0],
        held: None,
    };
    let mut painter = Painter::new(device);
    let mut encoder = device.create_command_encoder(&Default::default());
    let targets = DrawTargets {
        springs: Some(DrawTarget {
            buffer: &target,
            first_vertex: spring_at,
            vertices: spring_vertices,
        }),
        dots: Some(DrawTarget {
            buffer: &target,
            first_vertex: dot_at,
            vertices: dot_vertices,
        }),
    };
    painter.record(
        (device, gpu.queue()),
        &mut encoder,
        &source,
        &style,
        targets,
    );
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: total,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(&target, 0, &staging, 0, total);
    gpu.queue().submit([encoder.finish()]);
    staging.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = staging.slice(..).get_mapped_range().to_vec();
    let floats: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let vertex = |v: u32| &floats[7 * v as usize..7 * v as usize + 7];
    let near = |p: &[f32], q: bevy::math::DVec2, tol: f64| {
        ((f64::from(p[0]) - q.x).hypot(f64::from(p[1]) - q.y)) <= tol
    };
    for i in 0..n {
        let x = state.x()[i as usize];
        let corners: Vec<&[f32]> = (0..DOT_CORNERS)
            .map(|k| vertex(dot_at + DOT_CORNERS * i + k))
            .collect();
        let centre = corners.iter().fold(bevy::math::DVec2::ZERO, |c, p| {
            c + bevy::math::DVec2::new(f64::from(p[0]), f64::from(p[1])) / f64::from(DOT_CORNERS)
        });
        assert!(
            (centre - x).length() < 1e-5,
            "particle {i}: hexagon at {centre}, state at {x}"
        );
        assert!(corners.iter().all(|p| near(p, x, 0.004 + 1e-5)));
        let colour = if state.inv_mass()[i as usize] == 0.0 {
            pinned
        } else {
            free
        };
        assert_eq!(corners[0][3..7], colour, "particle {i}'s colour");
    }
    for (s, spring) in state.springs().iter().enumerate() {
        let (a, b) = (state.x()[spring.a as usize], state.x()[spring.b as usize]);
        let quad: Vec<&[f32]> = (0..SPRING_CORNERS)
            .map(|k| vertex(spring_at + SPRING_CORNERS * s as u32 + k))
            .collect();
        assert!(
            near(quad[0], a, 0.001 + 1e-5) && near(quad[1], a, 0.001 + 1e-5),
            "spring {s}"
        );
        assert!(
            near(quad[2], b, 0.001 + 1e-5) && near(quad[3], b, 0.001 + 1e-5),
            "spring {s}"
        );
    }
    // Outside the runs, nothing was written.
    let untouched = |v: u32| {
        bytes[(v as u64 * VERTEX_BYTES) as usize..((v + 1) as u64 * VERTEX_BYTES) as usize]
            .iter()
            .all(|&b| b == fill)
    };
    for v in (0..spring_at)
        .chain(spring_at + spring_vertices..dot_at)
        .chain(dot_at + dot_vertices..dot_at + dot_vertices + 2)
    {
        assert!(untouched(v), "vertex {v} outside the runs was written");
    }
}
