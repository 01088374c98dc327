//! Contact at a frame's step: the shipped pile of six soft boxes, and a heavy stack of the
//! same boxes, at dt = 1/60 s under every large-step method, checked by state at the end of
//! every step against the same pile under symplectic Euler at 1e-4 s.

mod common;
use bevy::math::DVec2;
use bevy::prelude::App;
use common::*;
#[allow(unused_imports)]
use hooke::scene::Generator;
use hooke::scene::{LoadedScene, Scene, load_into_world};
use hooke::sim::{self, Integrator, Obstacles, SimParams, Solver};

const FRAME: f64 = 1.0 / 60.0;
const LARGE_STEP: [Integrator; 5] = [
    Integrator::ImplicitEuler,
    Integrator::ProjectiveDynamics,
    Integrator::Xpbd,
    Integrator::Vbd,
    Integrator::Bdf2,
];

/// The shipped pile, under `integrator` at `dt`, with the stiffness and mass of the boxes above
/// the first two changed by `heavy` (k, mass factor) when given.
fn pile(integrator: Integrator, dt: f64, heavy: Option<(f64, f64)>) -> App {
    let text = std::fs::read_to_string("assets/scenes/pile.ron").unwrap();
    let mut scene: Scene = ron::from_str(&text).unwrap();
    scene.integrator = integrator;
    scene.dt = dt;
    if let Some((k, factor)) = heavy {
        for (i, g) in scene.generate.iter_mut().enumerate() {
            if let hooke::scene::Generator::Grid {
                stiffness, mass, ..
            } = g
            {
                *stiffness = k;
                if i >= 2 {
                    *mass *= factor;
                }
            }
        }
    }
    let loaded = LoadedScene::from_scene(scene, None).expect("the pile is valid");
    let mut app = hooke::headless_app();
    load_into_world(app.world_mut(), &loaded);
    app.world_mut().resource_mut::<SimParams>().paused = false;
    sim::pack(app.world_mut()).unwrap();
    app
}

/// What the checks read of one state.
#[derive(Debug, Clone, Copy)]
struct Look {
    /// The closest pair no spring joins, as a share of 2r.
    closest: f64,
    /// The deepest particle inside a wall or under the ground, as a share of r.
    deepest: f64,
    energy: f64,
    kinetic: f64,
}

fn look(app: &App) -> Look {
    let solver = app.world().resource::<Solver>();
    let params = app.world().resource::<SimParams>();
    let r = params.contact.unwrap().radius;
    let x = solver.x();
    let closest = closest_unjoined(solver).0 / (2.0 * r);
    let obstacles = app.world().resource::<Obstacles>();
    let ground = params.ground.unwrap();
    let mut deepest: f64 = 0.0;
    for p in x {
        deepest = deepest.max((ground + r - p.y) / r);
        for o in obstacles.placed() {
            deepest = deepest.max((r - o.distance(*p).0) / r);
        }
    }
    let e = solver.state().energy(params.gravity);
    Look {
        closest,
        deepest,
        energy: e.total(),
        kinetic: e.kinetic,
    }
}

/// Each box's cells' signed areas (the 5×5 grids, 16 cells each, in generation order).
fn cells(app: &App) -> Vec<f64> {
    let x = app.world().resource::<Solver>().x();
    let mut out = vec![];
    for b in 0..x.len() / 25 {
        let p = |c: usize, r: usize| x[b * 25 + r * 5 + c];
        for r in 0..4 {
            for c in 0..4 {
                let q = [p(c, r), p(c + 1, r), p(c + 1, r + 1), p(c, r + 1)];
                let mut a = 0.0;
                for k in 0..4 {
                    a += q[k].perp_dot(q[(k + 1) % 4]);
                }
                out.push(a / 2.0);
            }
        }
    }
    out
}

fn box_areas(cells: &[f64]) -> Vec<f64> {
    cells.chunks(16).map(|c| c.iter().sum()).collect()
}

/// The pile under `integrator` at `dt` for `seconds`: the worst of every step's look, and the
/// cells at the end.
fn run(mut app: App, dt: f64, seconds: f64) -> (Look, Look, Vec<f64>, Vec<f64>) {
    let start_cells = cells(&app);
    let first = look(&app);
    let mut worst = first;
    let steps = (seconds / dt).round() as u64;
    for _ in 0..steps {
        step(&mut app, 1);
        let l = look(&app);
        worst.closest = worst.closest.min(l.closest);
        worst.deepest = worst.deepest.max(l.deepest);
        worst.energy = worst.energy.max(l.energy);
    }
    let end = look(&app);
    (worst, end, start_cells, cells(&app))
}

/// The shipped pile at 1/60 s, 6 s, against symplectic Euler at 1e-4 s: at the end of every
/// step no two particles that no spring joins closer than 90 % of 2r, none deeper than 10 % of
/// r in a wall or the ground, and the total energy never above its start; at 6 s the kinetic
/// energy under 1e-3 of the energy the drop gave up (the start's less symplectic Euler's at
/// 6 s), and, under XPBD and VBD, no more cells turned inside out than under symplectic Euler.
/// Projective dynamics turns 3 of the 96 and BDF2 6 where symplectic Euler turns 1, and
/// implicit Euler does not hold the pile yet (pairs at 49 % of 2r, the energy up to 248 J):
/// both are open in the guide (docs/large-steps.md).
#[test]
fn the_pile_at_a_frames_step_stays_whole_and_never_gains_energy() {
    let (_, reference, start, end) = run(pile(Integrator::SymplecticEuler, 1e-4, None), 1e-4, 6.0);
    let turned_reference = inverted(&start, &end);
    let first = look(&pile(Integrator::SymplecticEuler, 1e-4, None));
    let dropped = first.energy - reference.energy;
    assert!(
        dropped > 100.0,
        "the reference pile gave up only {dropped} J"
    );
    for m in [
        Integrator::ProjectiveDynamics,
        Integrator::Xpbd,
        Integrator::Vbd,
        Integrator::Bdf2,
    ] {
        let (worst, last, start, end) = run(pile(m, FRAME, None), FRAME, 6.0);
        assert!(
            worst.closest >= 0.9,
            "{m:?}: a pair at {} of 2r",
            worst.closest
        );
        assert!(
            worst.deepest <= 0.1,
            "{m:?}: {} of r inside a surface",
            worst.deepest
        );
        assert!(
            worst.energy <= first.energy * (1.0 + 1e-9),
            "{m:?}: the energy rose to {} J from {} J",
            worst.energy,
            first.energy
        );
        assert!(
            last.kinetic < 1e-3 * dropped,
            "{m:?}: still moving at 6 s, {} J",
            last.kinetic
        );
        if matches!(m, Integrator::Xpbd | Integrator::Vbd) {
            let turned = inverted(&start, &end);
            assert!(
                turned <= turned_reference,
                "{m:?}: {turned} cells turned inside out, {turned_reference} under symplectic Euler"
            );
        }
    }
}

/// A soft box thrown at 10 m/s at a wall, at 1/60 s (17 cm a step against a wall 4 cm thick):
/// under every large-step method every particle stays on its side of the wall. Under implicit
/// Euler a particle ended past the wall at step 3 while an end past a closed shape's middle
/// went out by its nearest surface, the far one (`Placed::touch`).
#[test]
fn a_box_thrown_at_a_wall_stays_on_its_side() {
    for m in [
        Integrator::ImplicitEuler,
        Integrator::ProjectiveDynamics,
        Integrator::Xpbd,
        Integrator::Vbd,
        Integrator::Bdf2,
    ] {
        let mut scene = Scene {
            gravity: (0.0, -9.8),
            damping: 1.0,
            ground: Some(0.0),
            integrator: m,
            dt: FRAME,
            ..Default::default()
        };
        scene.generate = vec![hooke::scene::Generator::Grid {
            cols: 5,
            rows: 5,
            min: (0.2, 0.05),
            max: (0.28, 0.13),
            mass: 0.02,
            stiffness: 1e4,
            shear: true,
            pin: hooke::scene::Pin::None,
            vel: (10.0, 0.0),
            damping: None,
            plastic: None,
        }];
        scene.obstacles = vec![hooke::scene::ObstacleDef::Box {
            center: (0.7, 0.2),
            half: (0.02, 0.2),
            angle: 0.0,
        }];
        scene.contact = Some(hooke::sim::ContactSettings {
            radius: 0.008,
            friction: 0.3,
            restitution: 0.0,
            particles: true,
            outlines: false,
        });
        let mut app = app_with(scene);
        let face = 0.68 - 0.008;
        for s in 0..120 {
            step(&mut app, 1);
            let right = app
                .world()
                .resource::<Solver>()
                .x()
                .iter()
                .fold(f64::MIN, |m, p| m.max(p.x));
            assert!(
                right <= face + 1e-9,
                "{m:?}: a particle at x = {right} after step {s}, the wall's face at {face}"
            );
        }
    }
}

/// The figures the guide quotes, for every large-step method: `cargo test --test
/// frame_step_contact -- --ignored --nocapture` (with `HEAVY=1`, the heavy stack).
#[test]
#[ignore = "prints figures, asserts nothing"]
fn pile_figures() {
    let heavy = std::env::var("HEAVY").is_ok().then_some((1e5, 10.0));
    // The reference, and the same at half its step: how far the reference itself is from
    // converged (the pile tumbles, and a cell buckles or not by the path).
    for dt in [1e-4, 5e-5] {
        let (_, se_end, se_start, se_cells) =
            run(pile(Integrator::SymplecticEuler, dt, heavy), dt, 6.0);
        println!(
            "SE at {dt}: end {:?} areas {:?} inverted {}",
            se_end,
            box_areas(&se_cells),
            inverted(&se_start, &se_cells)
        );
    }
    let newton: Option<u32> = std::env::var("NEWTON").ok().and_then(|n| n.parse().ok());
    for m in LARGE_STEP {
        let mut app = pile(m, FRAME, heavy);
        if let Some(n) = newton {
            app.world_mut()
                .resource_mut::<SimParams>()
                .iterations
                .newton = n;
        }
        let (worst, end, s, c) = run(app, FRAME, 6.0);
        println!(
            "{m:?}: worst {worst:?} end E {:.2} KE {:.3e} areas {:?} inverted {}",
            end.energy,
            end.kinetic,
            box_areas(&c)
                .iter()
                .map(|a| format!("{a:.5}"))
                .collect::<Vec<_>>(),
            inverted(&s, &c)
        );
    }
}

/// A flat strip of cloth (48 × 2 particles, shear springs, 1 cm wide) dropped 0.2 m onto the
/// ground, under `integrator` at `dt`, its drag in the solve or not.
fn dropped_strip(integrator: Integrator, dt: f64, drag_in_solve: bool) -> App {
    let text = "(gravity: (0.0, -9.8), damping: 2.0, ground: Some(0.0), generate: [
        Grid(cols: 48, rows: 2, min: (0.25, 0.2), max: (0.75, 0.2104), mass: 0.02,
             stiffness: 10000.0, shear: true, pin: None)],
        contact: Some((radius: 0.004, friction: 0.6, restitution: 0.0)))";
    let mut scene: Scene = ron::from_str(text).unwrap();
    scene.integrator = integrator;
    scene.dt = dt;
    scene.drag_in_solve = drag_in_solve;
    app_with(scene)
}

/// The signed areas of [`dropped_strip`]'s 47 cells.
fn strip_cells(app: &App) -> Vec<f64> {
    let x = app.world().resource::<Solver>().x();
    (0..47)
        .map(|c| {
            let q = [x[c], x[c + 1], x[48 + c + 1], x[48 + c]];
            (0..4).map(|k| q[k].perp_dot(q[(k + 1) % 4])).sum::<f64>() / 2.0
        })
        .collect()
}

/// The dropped strip under each large-step method at 1/60 and 1/30 s for 1 s: the highest
/// energy at the end of a step, the highest point once it has landed, and the cells turned
/// inside out at the end. A figure of the guide (docs/large-steps.md): until 2026-12-07 BDF2,
/// VBD and projective dynamics landed the strip turned over and gained energy
/// ([`a_layer_landing_flat_keeps_its_cells`]). `cargo test --release --test
/// frame_step_contact strip_drop_figures -- --ignored --nocapture`.
#[test]
#[ignore = "prints figures, asserts nothing"]
fn strip_drop_figures() {
    for m in LARGE_STEP {
        for dt in [FRAME, 1.0 / 30.0] {
            let mut app = dropped_strip(m, dt, false);
            let start = strip_cells(&app);
            let params = app.world().resource::<SimParams>().clone();
            let e0 = solver(&app).energy(params.gravity).total();
            let (mut highest_energy, mut highest_after) = (f64::MIN, f64::MIN);
            let steps = (1.0 / dt).round() as u64;
            for k in 1..=steps {
                step(&mut app, 1);
                let s = solver(&app);
                highest_energy = highest_energy.max(s.energy(params.gravity).total());
                // A free fall from 0.2 m lands at 0.2 s.
                if k as f64 * dt >= 0.25 {
                    let top = s.x().iter().map(|p| p.y).fold(f64::MIN, f64::max);
                    highest_after = highest_after.max(top);
                }
            }
            println!(
                "{m:?} at {dt:.4}: energy {e0:.2} J, highest {highest_energy:.2} J; highest point \
                 after 0.25 s {highest_after:.3} m; cells turned {} of 47",
                inverted(&start, &strip_cells(&app))
            );
        }
    }
}

/// A layer landing flat at a frame's step lands whole: [`dropped_strip`] (its rows a
/// centimetre apart, landing at 2 m/s: 3.3 cm a step at 1/60 s, 6.6 cm at 1/30 s, so that the
/// whole strip's guess lies under the ground) under every large-step method but XPBD, and
/// under projective dynamics with the drag in its solve, at 1/60 and 1/30 s for 1 s. No step
/// ends with a cell turned over or with more energy than the start, and the rows end at least
/// half their spacing apart. Until 2026-12-07 VBD held each particle out on its own: both rows
/// landed on the ground's line, the energy rose from 3.9 J to 34.4 J, and at 1/30 s all 47
/// cells turned over; projective dynamics, whose lower row's forces stopped the strip at twice
/// its mass, threw it up and turned its cells (25.0 J and 26 cells at 1/60 s, 43.8 J and all
/// 47 at 1/30 s); BDF2 flattened it (42 J and 43 cells, 291 J and all 47); and projective
/// dynamics with the drag in its solve, whose landing step left the upper row coming at the
/// lower, stopped one, turned it over whole at 1/60 s. XPBD keeps its cells but peaks at
/// 4.1 J at 1/60 s.
#[test]
fn a_layer_landing_flat_keeps_its_cells() {
    let methods = [
        (Integrator::ImplicitEuler, false),
        (Integrator::ProjectiveDynamics, false),
        (Integrator::ProjectiveDynamics, true),
        (Integrator::Vbd, false),
        (Integrator::Bdf2, false),
    ];
    for (m, drag_in_solve) in methods {
        for dt in [FRAME, 1.0 / 30.0] {
            let mut app = dropped_strip(m, dt, drag_in_solve);
            let m = format!(
                "{m:?}{}",
                if drag_in_solve {
                    " (drag in solve)"
                } else {
                    ""
                }
            );
            let start = strip_cells(&app);
            let gravity = app.world().resource::<SimParams>().gravity;
            let e0 = solver(&app).energy(gravity).total();
            for k in 1..=(1.0 / dt).round() as u64 {
                step(&mut app, 1);
                let turned = inverted(&start, &strip_cells(&app));
                let energy = solver(&app).energy(gravity).total();
                assert_eq!(
                    turned, 0,
                    "{m:?} at {dt:.4} s, step {k}: {turned} cells turned"
                );
                assert!(
                    energy <= e0 * (1.0 + 1e-9),
                    "{m:?} at {dt:.4} s, step {k}: {energy:.3} J from {e0:.3} J"
                );
            }
            let x = solver(&app).x();
            let row = |r: std::ops::Range<usize>| r.map(|i| x[i].y).sum::<f64>() / 48.0;
            let apart = (row(0..48) - row(48..96)).abs();
            assert!(
                apart > 0.5 * 0.0104,
                "{m:?} at {dt:.4} s: rows {apart:.4} m apart"
            );
        }
    }
}

/// A body sliding round an obstacle's corner, and the shipped contact scenes that make it, at a
/// frame's step under projective dynamics and BDF2: [`dropped_strip`] dropped instead onto a
/// box tilted 0.6 rad, whose low corner it slides round onto the ground, at 1/60 and 1/30 s,
/// and the shipped `paddle` (a strip carried round a moving paddle's corner) and
/// `cloth_on_ball` at 1/60 s, for 3 s: no step ends with more energy than the start. Until
/// 2026-12-07, when a line search began sizing the contact forces inside projective dynamics'
/// solve, the strip peaked there at 21.9 J and 31.5 J from 14.2 J, the `paddle` at 22.7 J from
/// 10.4 J and `cloth_on_ball` at 22.0 J from 13.3 J; under BDF2, until it took a backward
/// Euler step where contact acts, at 14.4 and 25.5 J, 19.2 J and 16.9 J (docs/large-steps.md).
#[test]
fn projective_dynamics_and_bdf2_slide_round_corners_at_a_frames_step() {
    let text = "(gravity: (0.0, -9.8), damping: 2.0, ground: Some(0.0),
        obstacles: [Box(center: (0.5, 0.4), half: (0.3, 0.02), angle: 0.6)],
        generate: [Grid(cols: 48, rows: 2, min: (0.25, 0.75), max: (0.75, 0.7604), mass: 0.02,
             stiffness: 10000.0, shear: true, pin: None)],
        contact: Some((radius: 0.004, friction: 0.6, restitution: 0.0)))";
    let tilted: Scene = ron::from_str(text).unwrap();
    let shipped = |name: &str| hooke::scene::presets::resolve(name).unwrap().scene;
    let cases = [
        ("tilted box", tilted.clone(), FRAME),
        ("tilted box", tilted, 1.0 / 30.0),
        ("paddle", shipped("paddle"), FRAME),
        ("cloth_on_ball", shipped("cloth_on_ball"), FRAME),
    ];
    for m in [Integrator::ProjectiveDynamics, Integrator::Bdf2] {
        for (name, scene, dt) in &cases {
            let mut scene = scene.clone();
            scene.integrator = m;
            scene.dt = *dt;
            let mut app = app_with(scene);
            let name = format!("{name} under {m:?}");
            never_gains_energy(&mut app, &name, (3.0 / dt).round() as u64);
        }
    }
}

/// Bodies that land at a frame's step under BDF2 come to rest: two soft boxes stacked (the
/// upper dropped 5 cm onto the lower, particle pairs on) at 1/60 and 1/30 s, the shipped
/// `soft_box` at 1/30 s and [`dropped_strip`] at 1/30 s, each after 6 s with a root-mean-square
/// speed under 1 cm/s. BDF2 takes a backward Euler step where contact acts, with projective
/// dynamics' line search: the search on BDF2's own steps kept the stacked boxes rocking with
/// a period of two steps (0.23 m/s at 1/60 s), and before either the `soft_box` at 1/30 s
/// still moved at 0.58 m/s and the strip at 2.9 m/s (docs/performance-log.md, 2026-12-07).
#[test]
fn bodies_landing_under_bdf2_at_a_frames_step_come_to_rest() {
    let shipped = hooke::scene::presets::resolve("soft_box").unwrap().scene;
    let cases = [
        (
            "stacked boxes",
            Some(stacked_soft_boxes(Integrator::Bdf2, FRAME)),
            FRAME,
        ),
        (
            "stacked boxes",
            Some(stacked_soft_boxes(Integrator::Bdf2, 1.0 / 30.0)),
            1.0 / 30.0,
        ),
        ("soft_box", Some(shipped), 1.0 / 30.0),
        ("dropped strip", None, 1.0 / 30.0),
    ];
    for (name, scene, dt) in cases {
        let mut app = match scene {
            Some(mut scene) => {
                scene.integrator = Integrator::Bdf2;
                scene.dt = dt;
                app_with(scene)
            }
            None => dropped_strip(Integrator::Bdf2, dt, false),
        };
        step(&mut app, (6.0 / dt).round() as u64);
        let v = solver(&app).v();
        let rms = (v.iter().map(|v| v.length_squared()).sum::<f64>() / v.len() as f64).sqrt();
        assert!(
            rms < 0.01,
            "{name} at {dt:.4} s: still moving at {rms:.4} m/s after 6 s"
        );
    }
}

/// A strip of cloth folding onto itself on the ground at a frame's step, under every
/// large-step method (a fold lands at 3 m/s: 5 cm a step at 1/60 s, eleven contact radii): no
/// pair that no spring joins ends a step closer than 90 % of 2r, and the strip does fold onto
/// itself. Implicit Euler at 1/55 and 1/50 s too, never a quarter above its start: with one
/// pass over the pairs a projection, each along the pair's own line, and unrelaxed forces, the
/// pass after the step pushed the pairs its Newton steps left at half of 2r out into the
/// springs (the shipped `folding_cloth` rose from 8.8 J to 52 J at 1/60 s). Projective dynamics and BDF2 at 1/55 and 1/50 s too: their
/// solves move a fold past the strip below it in one iteration, and pairs pushed apart along
/// their own line went on through (at 0.65 of 2r under projective dynamics at 1/60 s; on the
/// shipped `folding_cloth` the energy rose from 8.8 J to 316 J, and 196 J under BDF2).
///
/// Under projective dynamics from 1/55 s down, and under BDF2 at every step here, the strip
/// never holds more than a quarter above the energy it started with (projective dynamics at
/// 1/61, 1/60 and 1/59 s no more, at 1/55 s 13 % more; BDF2 no more, where before it took a
/// backward Euler step where contact acts it rose up to 2.3 times). Open: projective dynamics
/// at 1/50 s reaches one and a half times it (`docs/large-steps.md`).
#[test]
fn a_folding_strip_at_a_frames_step_does_not_pass_through_itself() {
    let cases = [
        (Integrator::ImplicitEuler, FRAME),
        (Integrator::ImplicitEuler, 1.0 / 55.0),
        (Integrator::ImplicitEuler, 1.0 / 50.0),
        (Integrator::Xpbd, FRAME),
        (Integrator::Vbd, FRAME),
        (Integrator::ProjectiveDynamics, FRAME),
        (Integrator::ProjectiveDynamics, 1.0 / 61.0),
        (Integrator::ProjectiveDynamics, 1.0 / 59.0),
        (Integrator::ProjectiveDynamics, 1.0 / 55.0),
        (Integrator::ProjectiveDynamics, 1.0 / 50.0),
        (Integrator::Bdf2, FRAME),
        (Integrator::Bdf2, 1.0 / 61.0),
        (Integrator::Bdf2, 1.0 / 55.0),
        (Integrator::Bdf2, 1.0 / 50.0),
    ];
    for (m, dt) in cases {
        let (scene, r) = folding_strip(m, dt);
        let mut app = app_with(scene);
        let gravity = app.world().resource::<SimParams>().gravity;
        let e0 = solver(&app).energy(gravity).total();
        let bound = match m {
            Integrator::ProjectiveDynamics if dt < 1.0 / 51.0 => e0 * 1.25,
            Integrator::Bdf2 | Integrator::ImplicitEuler => e0 * 1.25,
            _ => f64::INFINITY,
        };
        let mut touched = 0;
        for s in 0..(2.0 / dt).round() as u64 {
            step(&mut app, 1);
            let (dist, i, j) = closest_unjoined(solver(&app));
            assert!(
                dist >= 0.9 * 2.0 * r,
                "{m:?} at {dt:.4} s: particles {i} and {j} {dist} m apart after step {s} (2r = {})",
                2.0 * r
            );
            let energy = solver(&app).energy(gravity).total();
            assert!(
                energy <= bound,
                "{m:?} at {dt:.4} s, step {s}: {energy:.3} J from {e0:.3} J"
            );
            touched = touched.max(touching_unjoined(solver(&app), 1.2 * 2.0 * r));
        }
        assert!(
            touched >= 10,
            "{m:?} at {dt:.4} s: the strip never folded onto itself ({touched} pairs)"
        );
    }
}

/// Every integrator at 1e-4 s, then the large-step methods at 1/60 s.
fn every_method_then_large_steps() -> impl Iterator<Item = (Integrator, f64)> {
    let own = Integrator::ALL.into_iter().map(|m| (m, 1e-4));
    own.chain(LARGE_STEP.into_iter().map(|m| (m, FRAME)))
}

/// The particles of each ring (index ranges, in order around it) that lie inside the other.
fn inside_the_other(app: &App, rings: [std::ops::Range<usize>; 2]) -> usize {
    let x = solver(app).x();
    let [a, b] = rings.map(|r| x[r].to_vec());
    a.iter().filter(|p| inside(&b, **p)).count() + b.iter().filter(|p| inside(&a, **p)).count()
}

/// The smallest distance from a particle of one ring to the other's outline (its polygon's
/// sides), m.
fn gap(app: &App, rings: [std::ops::Range<usize>; 2]) -> f64 {
    let x = solver(app).x();
    let [a, b] = rings.map(|r| x[r].to_vec());
    let to_ring = |p: bevy::math::DVec2, ring: &[bevy::math::DVec2]| {
        (0..ring.len())
            .map(|k| {
                let (s, e) = (ring[k], ring[(k + 1) % ring.len()]);
                let t = ((p - s).dot(e - s) / (e - s).length_squared()).clamp(0.0, 1.0);
                (p - (s + (e - s) * t)).length()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let one = a
        .iter()
        .map(|p| to_ring(*p, &b))
        .fold(f64::INFINITY, f64::min);
    let other = b
        .iter()
        .map(|p| to_ring(*p, &a))
        .fold(f64::INFINITY, f64::min);
    one.min(other)
}

/// The shipped balloon scene under `integrator` at `dt`.
fn balloon(integrator: Integrator, dt: f64) -> App {
    shipped("balloon", integrator, dt)
}

/// The balloons, rings of 24 and 20 particles spaced about six contact diameters apart, under
/// every integrator at the scene's own step (for the 3 s in which they roll into each other
/// against the wall) and, under the large-step methods, at 1/60 s for 6 s: no particle of one
/// ball ends a step inside the other's outline.
#[test]
fn the_balloons_never_enter_each_other() {
    let runs =
        every_method_then_large_steps().map(|(m, dt)| (m, dt, if dt == FRAME { 6.0 } else { 3.0 }));
    let mut failures = vec![];
    for (m, dt, seconds) in runs {
        let mut app = balloon(m, dt);
        let steps = (seconds / dt).round() as u64;
        let mut worst = (0, 0);
        let mut closest = f64::INFINITY;
        // At the own step, a look every 10 steps (a particle cannot cross a ring in 1 ms).
        let every = if dt < 1e-3 { 10 } else { 1 };
        for s in 0..steps / every {
            step(&mut app, every);
            let n = inside_the_other(&app, [0..24, 24..44]);
            if n > worst.0 {
                worst = (n, s * every);
            }
            closest = closest.min(gap(&app, [0..24, 24..44]));
        }
        // Touching, at the own step: within 2r (0.01 m) and a little, at least once. At 1/60 s
        // implicit Euler's damping holds the upper ball on the slope (it never comes within
        // 0.24 m); the thrown rings below meet under every method at 1/60 s.
        if worst.0 > 0 || (dt < 1e-3 && closest > 0.012) {
            failures.push(format!(
                "{m:?} at dt = {dt}: {} particles inside the other ball after step {}; closest {closest} m",
                worst.0, worst.1
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A gas ring of 12 particles of 50 g, in a scene's text: round `centre` at `radius` (where
/// its springs of k = 1e4 are at rest), the first `phase` twelfths past angle 0, all moving at
/// `vel`, filled with a gas of `nrt`; appended to the scene's lists of particles, springs and
/// pressure bodies.
fn ring_of_12(
    (particles, springs, loops): (&mut Vec<String>, &mut Vec<String>, &mut Vec<String>),
    (centre, radius, phase): ((f64, f64), f64, f64),
    (vel, nrt): ((f64, f64), f64),
) {
    let first = particles.len();
    let rest = 2.0 * radius * (std::f64::consts::PI / 12.0).sin();
    for k in 0..12 {
        let a = std::f64::consts::TAU * (k as f64 + phase) / 12.0;
        let (x, y) = (centre.0 + radius * a.cos(), centre.1 + radius * a.sin());
        particles.push(format!("(pos: ({x}, {y}), vel: {vel:?}, mass: 0.05)"));
        let (a, b) = (first + k, first + (k + 1) % 12);
        springs.push(format!(
            "(a: {a}, b: {b}, stiffness: 10000.0, rest: {rest})"
        ));
    }
    let ids: Vec<String> = (first..first + 12).map(|i| i.to_string()).collect();
    loops.push(format!("(particles: [{}], nrt: {nrt:?})", ids.join(", ")));
}

/// Two gas-filled rings of 12 particles (spaced eight contact diameters apart), thrown at
/// each other at 2 m/s with no gravity, under `integrator` at `dt`, bodies colliding by their
/// outlines when `outlines`.
fn thrown_rings(integrator: Integrator, dt: f64, outlines: bool) -> App {
    let (mut particles, mut springs, mut loops) = (vec![], vec![], vec![]);
    for (cx, vx) in [(0.35, 2.0), (0.65, -2.0)] {
        let lists = (&mut particles, &mut springs, &mut loops);
        ring_of_12(lists, ((cx, 0.5), 0.08, 0.0), ((vx, 0.0), 5.0));
    }
    let text = format!(
        "(gravity: (0.0, 0.0), damping: 0.0, spring_damping: 0.5, ground: None, dt: {dt}, integrator: {integrator:?}, \
         particles: [{}], springs: [{}], pressure: [{}], \
         contact: Some((radius: 0.005, restitution: 0.5, outlines: {outlines})))",
        particles.join(", "),
        springs.join(", "),
        loops.join(", ")
    );
    let scene: Scene = ron::from_str(&text).unwrap();
    app_with(scene)
}

/// The rings' centres' x velocities (mean of each ring's particles).
fn ring_speeds(app: &App) -> (f64, f64) {
    let v = solver(app).state().v();
    let mean = |r: std::ops::Range<usize>| v[r].iter().map(|v| v.x).sum::<f64>() / 12.0;
    (mean(0..12), mean(12..24))
}

/// Two rings of 12 particles thrown at each other at 2 m/s bounce apart under every
/// integrator (at 1e-4 s, and the large-step methods at 1/60 s too), no particle of one ever
/// inside the other; without outlines they pass through each other.
#[test]
fn two_thrown_rings_bounce_apart() {
    let runs = every_method_then_large_steps();
    let mut failures = vec![];
    for (m, dt) in runs {
        let mut app = thrown_rings(m, dt, true);
        let mut worst = 0;
        for _ in 0..(0.3 / dt).round() as u64 {
            step(&mut app, 1);
            worst = worst.max(inside_the_other(&app, [0..12, 12..24]));
        }
        let (left, right) = ring_speeds(&app);
        if worst > 0 || left >= 0.0 || right <= 0.0 {
            failures.push(format!(
                "{m:?} at dt = {dt}: {worst} inside the other at worst; speeds {left:.3}, {right:.3} m/s"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Without outlines, particle pairs alone: the rings pass through each other.
    let mut app = thrown_rings(Integrator::SymplecticEuler, 1e-4, false);
    step(&mut app, 3000);
    let (left, right) = ring_speeds(&app);
    assert!(left > 0.0 && right < 0.0, "{left} {right}");
}

/// Implicit Euler on the pile at 1/60 s: short of the pile's other checks (pairs reach 69 % of
/// 2r), but its energy never rises above the start and nothing ends inside a surface.
#[test]
fn implicit_euler_keeps_the_piles_energy_at_a_frames_step() {
    let start = look(&pile(Integrator::ImplicitEuler, FRAME, None));
    let (worst, ..) = run(pile(Integrator::ImplicitEuler, FRAME, None), FRAME, 6.0);
    assert!(
        worst.energy <= start.energy * (1.0 + 1e-9),
        "the energy rose to {} J from {} J",
        worst.energy,
        start.energy
    );
    assert!(
        worst.deepest <= 0.1,
        "{} of r inside a surface",
        worst.deepest
    );
}

/// A shipped scene under `integrator` at `dt`.
fn shipped(name: &str, integrator: Integrator, dt: f64) -> App {
    let text = std::fs::read_to_string(format!("assets/scenes/{name}.ron")).unwrap();
    let mut scene: Scene = ron::from_str(&text).unwrap();
    scene.integrator = integrator;
    scene.dt = dt;
    app_with(scene)
}

/// Implicit Euler sizes its contact forces by projective dynamics' line search: a gas body
/// landing on a slope, two of them rolling into each other by their outlines, a cloth on a ball
/// and a box sliding down a slope, each at 1/30 s, never end a step above their start energy
/// (by 1e-3 of it; the `slope` by 3e-3: in its first two steps at 1/30 s the solve pushes its
/// resting boxes 1 cm into their slopes and the push back out lifts them 0.4 mm, 7.960 J to
/// 7.978 J, which their slide down the slopes hid until the obstacles' friction held them). Learned particle by particle, the forces that stopped a landing ball's
/// lowest particles flung it: the `balloon` rose from 117 J to 29,190 J, `cloth_on_ball` from
/// 13.3 J to 70.7 J and `slope` from 7.96 J to 63.1 J. The `paddle`'s strip, sliding off its
/// turning paddle onto the ground, neither, at 1/60 and 1/30 s: the ground's friction slowed
/// its first particle down alone, after the solve, and the springs beside it stretched to 4.8
/// times their length (36.8 and 46.6 J from 10.4 J, until the friction slowed whole bodies).
#[test]
fn implicit_euler_lands_gas_bodies_and_cloths_at_a_frames_step() {
    let mut failures = vec![];
    for (name, dt, bound) in [
        ("balloon", 1.0 / 30.0, 1e-3),
        ("cloth_on_ball", 1.0 / 30.0, 1e-3),
        ("slope", 1.0 / 30.0, 3e-3),
        ("paddle", FRAME, 1e-3),
        ("paddle", 2.0 * FRAME, 1e-3),
    ] {
        let mut app = shipped(name, Integrator::ImplicitEuler, dt);
        let energy = |app: &App| {
            let gravity = app.world().resource::<SimParams>().gravity;
            let solver = app.world().resource::<Solver>();
            solver.state().energy(gravity).total()
        };
        let start = energy(&app);
        let mut most = start;
        for _ in 0..(6.0 / dt) as usize {
            step(&mut app, 1);
            most = most.max(energy(&app));
        }
        if most > start * (1.0 + bound) {
            failures.push(format!("{name} at {dt} s: {most} J from {start} J"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Implicit Euler's Newton steps after the first are searched along (`implicit_euler::search`):
/// the shipped `ropes`, three chains dropped across three pegs and onto each other at 1/30 s (hω =
/// 15), keep their energy within half its start for 3 s (it peaks at 1.23 times it). Without the
/// search, the last Newton step of a step flung rope particles lying on another rope over a peg
/// 9 cm up, their springs stretched to 6 times their length, and the energy rose from 51.2 J to
/// 254 J, 4.95 times its start.
#[test]
fn implicit_euler_never_flings_ropes_piled_on_pegs_at_two_frames_step() {
    let dt = 2.0 * FRAME;
    let mut app = shipped("ropes", Integrator::ImplicitEuler, dt);
    let gravity = app.world().resource::<SimParams>().gravity;
    let energy = |app: &App| solver(app).state().energy(gravity).total();
    let start = energy(&app);
    let mut most = start;
    for _ in 0..(3.0 / dt) as usize {
        step(&mut app, 1);
        most = most.max(energy(&app));
    }
    assert!(
        most < 1.5 * start,
        "the energy rose to {most} J from {start} J"
    );
}

/// Two gas rings of 12 particles, 52 mm apart, dropped with an edge's middle lowest: one
/// square onto the top corner of a box standing on its corner, one half over the end of a
/// ledge (a segment), so that it tips off it as the `balloon` scene's ball rolls off its
/// slope. Bodies collide by their outlines.
fn rings_on_corners(integrator: Integrator, dt: f64) -> App {
    let (mut particles, mut springs, mut loops) = (vec![], vec![], vec![]);
    for centre in [(0.3, 0.4), (0.6, 0.48)] {
        let lists = (&mut particles, &mut springs, &mut loops);
        ring_of_12(lists, (centre, 0.1, 0.5), ((0.0, 0.0), 10.0));
    }
    let text = format!(
        "(damping: 0.1, spring_damping: 1.0, dt: {dt}, integrator: {integrator:?}, \
         particles: [{}], springs: [{}], pressure: [{}], \
         obstacles: [Box(center: (0.3, 0.15), half: (0.05, 0.05), angle: {}), \
                     Segment(a: (0.6, 0.3), b: (1.0, 0.3))], \
         contact: Some((radius: 0.005, friction: 0.5, particles: true, outlines: true)))",
        particles.join(", "),
        springs.join(", "),
        loops.join(", "),
        std::f64::consts::FRAC_PI_4,
    );
    let scene: Scene = ron::from_str(&text).unwrap();
    app_with(scene)
}

/// An obstacle's corners (a box's, a segment's ends) never pass between a body's particles
/// into it: the two rings of [`rings_on_corners`], whose particles sit 52 mm apart, under every
/// integrator at 1e-4 s for 3 s and the large-step methods at 1/60 s for 6 s. Without the
/// corners' contact the box's top corner went straight through the first ring's lowest edge.
#[test]
fn no_obstacle_corner_passes_into_a_body() {
    let d = std::f64::consts::FRAC_1_SQRT_2 * 0.1;
    let corners = [
        bevy::math::DVec2::new(0.3, 0.15 + d),
        bevy::math::DVec2::new(0.3 + d, 0.15),
        bevy::math::DVec2::new(0.3 - d, 0.15),
        bevy::math::DVec2::new(0.6, 0.3),
        bevy::math::DVec2::new(1.0, 0.3),
    ];
    let runs =
        every_method_then_large_steps().map(|(m, dt)| (m, dt, if dt == FRAME { 6.0 } else { 3.0 }));
    let mut failures = vec![];
    for (m, dt, seconds) in runs {
        let mut app = rings_on_corners(m, dt);
        let every = if dt < 1e-3 { 10 } else { 1 };
        let steps = (seconds / dt).round() as u64 / every;
        let mut first = None;
        for s in 0..steps {
            step(&mut app, every);
            let x = solver(&app).x();
            let pierced = [0..12, 12..24]
                .into_iter()
                .any(|r| corners.iter().any(|c| inside(&x[r.clone()], *c)));
            if pierced {
                first = Some(s * every);
                break;
            }
        }
        if let Some(s) = first {
            failures.push(format!(
                "{m:?} at dt = {dt}: a corner inside a ring after step {s}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Whether the path `p0` → `p1` crosses the segment `a`–`b` (each on a strict side of the
/// other's line).
fn crosses(p0: DVec2, p1: DVec2, a: DVec2, b: DVec2) -> bool {
    let side = |o: DVec2, d: DVec2, p: DVec2| d.perp_dot(p - o);
    let (ab, p) = (b - a, p1 - p0);
    side(a, ab, p0) * side(a, ab, p1) < 0.0 && side(p0, p, a) * side(p0, p, b) < 0.0
}

/// No particle passes through a thin segment at a frame's step: the gas ball of
/// `examples/balloon.rs` (24 particles, nRT = 20) dropped onto a sloping plank from three
/// places, with and without friction, under the five large-step methods at 1/60 and 1/30 s;
/// no particle's path over a step crosses the plank. A solve's iterate can land across a
/// segment while its heading (its velocity plus a step of its forces) points away from it:
/// when the contact took the segment's side from the heading, implicit Euler put particles on
/// the far side in all 8 of these drops at 1/60 and 1/30 s and the ball ended cut by the plank.
///
/// The other methods' swept test runs along the step's chord, start to end, so a chord across
/// the plank is a particle through it. XPBD's runs along each substep's, and a particle that
/// slides off the plank's low end rounds it substep by substep (at 1/30 s, x = 0.32, μ = 0.6,
/// one does so at step 17, never nearer the end than the 5 mm radius) while the chord of its step
/// cuts the corner. For XPBD a crossing chord counts as a pass through only when the particle
/// starts and ends the step beside the plank, within its span: one that rounds an end starts
/// or ends past it.
#[test]
fn no_particle_passes_through_a_thin_segment_at_a_frames_step() {
    let (a, b) = (DVec2::new(0.0, 0.45), DVec2::new(0.6, 0.15));
    let mut failures = vec![];
    let runs = LARGE_STEP
        .into_iter()
        .flat_map(|m| [(m, FRAME), (m, 1.0 / 30.0)]);
    let beside = |p: DVec2| (0.0..=1.0).contains(&((p - a).dot(b - a) / (b - a).length_squared()));
    for (m, dt) in runs {
        for (x, friction) in [(0.25, 0.0), (0.32, 0.6), (0.4, 0.0), (0.4, 0.6)] {
            let text = format!(
                "(damping: 0.1, spring_damping: 2.0, ground: Some(0.0), dt: {dt}, \
                 integrator: {m:?}, generate: [Ring(center: ({x}, 0.65), radius: 0.1, \
                 segments: 24, mass: 0.05, stiffness: 10000.0, pressure: 20.0)], \
                 obstacles: [Segment(a: ({}, {}), b: ({}, {}))], \
                 contact: Some((radius: 0.005, friction: {friction})))",
                a.x, a.y, b.x, b.y
            );
            let mut app = app_with(ron::from_str(&text).unwrap());
            for s in 0..(1.5 / dt).round() as u32 {
                let before = solver(&app).x().to_vec();
                step(&mut app, 1);
                let after = solver(&app).x();
                let through = |i: usize| {
                    crosses(before[i], after[i], a, b)
                        && (m != Integrator::Xpbd || beside(before[i]) && beside(after[i]))
                };
                if let Some(i) = (0..after.len()).find(|&i| through(i)) {
                    failures.push(format!(
                        "{m:?} at dt = {dt}, ball at x = {x}, μ = {friction}: \
                         particle {i} through the plank at step {s}"
                    ));
                    break;
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A particle pressed by a heavier one stays on its side of a thin plank: a 10 g particle
/// rests on a level plank (r = 1 cm) and a 10 kg one lands beside and just above it, 3 mm off
/// its centre, falling at 1 to 10 m/s so that it ends its step 0.1r to 2r above the light
/// one's centre, under every integrator at 1/60 and 1/30 s. The pair pass pushes the light one
/// down by up to 3r (its over-relaxation), past the plank's line or clear of its far side, and
/// must put it back on the side it was pushed from. The plank is a segment of no thickness,
/// then a slab r thick (a closed shape). Put out by the nearest surface, the light particle
/// went through the segment in 283 of its 1431 drops, under every integrator (the large-step
/// methods' solves keep contact themselves, so no swept test runs after the pair pass; the
/// explicit methods' runs along the velocity, which the push did not change). With the
/// segment's crossing kept, it went through the slab in 17 under symplectic and explicit
/// Euler at 1/30 s: their step carries a resting particle 1 mm into the slab before the pair
/// pass, and a push from inside had no side. A light particle squeezed out sideways that
/// slides off an end and falls is no pass through: only a particle below the plank's top
/// within its span counts.
#[test]
fn a_particle_pressed_by_a_heavier_one_stays_on_its_side_of_a_thin_obstacle() {
    let (level, r) = PLANK;
    let mut failures = vec![];
    let mut drops = 0;
    for slab in [false, true] {
        for integrator in Integrator::ALL {
            for dt in [FRAME, 1.0 / 30.0] {
                for speed in [1.0, 3.0, 6.0, 10.0] {
                    for k in 0..20 {
                        // Where a free fall would end the step, above the light particle's
                        // centre.
                        let above = 0.1 * r * (1 + k) as f64;
                        let Some(mut scene) = landing_on_a_plank(integrator, dt, speed, above)
                        else {
                            // Starting in touch: the scene's check refuses it.
                            continue;
                        };
                        if slab {
                            plank_as_slab(&mut scene);
                        }
                        let mut app = app_with(scene);
                        drops += 1;
                        for s in 0..10 {
                            step(&mut app, 1);
                            let p = pos(&app, 0);
                            if p.y < level && (0.0..=1.0).contains(&p.x) {
                                let what = if slab { "slab" } else { "segment" };
                                failures.push(format!(
                                    "the {what}, {integrator:?} at dt = {dt:.4}, {speed} m/s, \
                                     ending {:.1}r above: the light particle at {p} after step \
                                     {s}",
                                    above / r
                                ));
                                break;
                            }
                        }
                    }
                }
            }
        }
    }
    println!("{drops} drops, {} through", failures.len());
    assert!(drops > 1400, "only {drops} drops");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A particle resting on a thin closed shape stays on it when struck: a particle of r = 1 cm
/// at rest on a slab r thick, a turned box 2r thick, a polygon 2r thick and a disc of radius r,
/// set moving into it at 0.5 to 10 m/s, under every integrator at 1/60 and 1/30 s. Its step
/// starts in contact, where the swept test used to look for no hit on a closed shape: it went
/// through in 300 of these 432 runs, under every integrator.
#[test]
fn a_particle_resting_on_a_thin_shape_stays_on_it_when_struck() {
    use hooke::scene::ObstacleDef;
    let r = 0.01;
    // Each shape about (0.5, 0.4), its top's normal, and its half-length across that.
    let shapes = [
        (
            ObstacleDef::Box {
                center: (0.5, 0.4),
                half: (0.3, 0.5 * r),
                angle: 0.0,
            },
            0.0,
            0.3,
        ),
        (
            ObstacleDef::Box {
                center: (0.5, 0.4),
                half: (0.3, r),
                angle: 0.3,
            },
            0.3,
            0.3,
        ),
        (
            ObstacleDef::Polygon {
                center: (0.5, 0.4),
                corners: vec![(-0.3, -r), (0.3, -r), (0.3, r), (-0.3, r)],
                angle: -0.2,
            },
            -0.2,
            0.3,
        ),
        (
            ObstacleDef::Circle {
                center: (0.5, 0.4),
                radius: r,
            },
            0.0,
            r,
        ),
    ];
    let center = DVec2::new(0.5, 0.4);
    let (mut failures, mut runs) = (vec![], 0);
    for (shape, angle, span) in &shapes {
        let up = DVec2::from_angle(*angle).perp();
        let placed = shape.placed().unwrap();
        let top = center - up * placed.distance(center).0;
        for integrator in Integrator::ALL {
            for dt in [FRAME, 1.0 / 30.0] {
                for speed in [0.5, 1.0, 2.0, 3.0, 6.0, 10.0] {
                    let mut scene = bare_scene(integrator, dt);
                    scene.gravity = (0.0, -9.8);
                    let start = top + up * r;
                    let mut p = particle(start.x, start.y, false);
                    p.vel = (-up * speed).into();
                    scene.particles = vec![p];
                    scene.obstacles = vec![shape.clone()];
                    scene.contact = pairs_on(r, 0.5);
                    let mut app = app_with(scene);
                    runs += 1;
                    for s in 0..5 {
                        step(&mut app, 1);
                        let q = pos(&app, 0) - center;
                        if q.dot(up) < 0.0 && q.dot(up.perp()).abs() <= *span {
                            failures.push(format!(
                                "{shape:?}, {integrator:?} at dt = {dt:.4}, {speed} m/s: at \
                                 {} after step {s}",
                                q + center
                            ));
                            break;
                        }
                    }
                }
            }
        }
    }
    println!("{runs} runs, {} through", failures.len());
    assert_eq!(runs, 432);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Sets the velocities of the scene's obstacles (a scene file gives none: an obstacle there
/// stands still; the library and the app's drag move them).
fn set_obstacle_velocity(app: &mut App, linear: DVec2, angular: f64) {
    let w = app.world_mut();
    for mut v in w.query::<&mut sim::ObstacleVelocity>().iter_mut(w) {
        *v = sim::ObstacleVelocity { linear, angular };
    }
}

/// An obstacle moving at a frame's step strikes a particle in its way, however thin it is: a
/// free particle of r = 1 cm at rest, and a segment, a slab r thick, a turned box and a polygon
/// 2r thick, and a disc of radius r coming down on it at 0.5 to 10 m/s from where they touch
/// it within the first step; and a segment turning about its middle at 5 to 40 rad/s onto a
/// particle 0.2 m out. Under every integrator at 1/60 and 1/30 s, for ten steps, the particle
/// stays ahead of the obstacle. The step read the particle's own path alone, and a particle at
/// rest has none: the obstacle moved past it after each contact, and a thin one went clean
/// past it (in 495 of the 528 runs of the eight methods other than XPBD). XPBD's substeps saw
/// each obstacle where the step began, and it jumped a step's travel after the last one: 55 of
/// XPBD's 66 runs were passed.
#[test]
fn a_particle_in_the_way_of_a_moving_obstacle_is_struck() {
    use hooke::scene::ObstacleDef;
    let r = 0.01;
    let center = DVec2::new(0.5, 0.4);
    let c = (center.x, center.y);
    // Each shape about `center`, its front's normal (the way it moves), and its half-length
    // across that.
    let shapes = [
        (
            ObstacleDef::Segment {
                a: (0.2, 0.4),
                b: (0.8, 0.4),
                thickness: 0.0,
            },
            0.0,
            0.3,
        ),
        (
            ObstacleDef::Box {
                center: c,
                half: (0.3, 0.5 * r),
                angle: 0.0,
            },
            0.0,
            0.3,
        ),
        (
            ObstacleDef::Box {
                center: c,
                half: (0.3, r),
                angle: 0.3,
            },
            0.3,
            0.3,
        ),
        (
            ObstacleDef::Polygon {
                center: c,
                corners: vec![(-0.3, -r), (0.3, -r), (0.3, r), (-0.3, r)],
                angle: -0.2,
            },
            -0.2,
            0.3,
        ),
        (
            ObstacleDef::Circle {
                center: c,
                radius: r,
            },
            0.0,
            r,
        ),
    ];
    let swept = Integrator::ALL;
    let (mut failures, mut runs) = (vec![], 0);
    for (shape, angle, span) in &shapes {
        let front = -DVec2::from_angle(*angle).perp();
        // Its half-thickness along the front's normal.
        let half = 1.0 - shape.placed().unwrap().distance(center + front).0;
        for &integrator in &swept {
            for dt in [FRAME, 1.0 / 30.0] {
                for speed in [0.5, 1.0, 2.0, 3.0, 6.0, 10.0] {
                    let mut scene = bare_scene(integrator, dt);
                    scene.gravity = (0.0, 0.0);
                    // In the way, touched halfway through the first step.
                    let start = center + front * (half + r + 0.5 * speed * dt);
                    scene.particles = vec![particle(start.x, start.y, false)];
                    scene.obstacles = vec![shape.clone()];
                    scene.contact = pairs_on(r, 0.5);
                    let mut app = app_with(scene);
                    set_obstacle_velocity(&mut app, front * speed, 0.0);
                    runs += 1;
                    for s in 1..=10 {
                        step(&mut app, 1);
                        let now = center + front * (speed * dt * s as f64);
                        let q = pos(&app, 0) - now;
                        if q.dot(front) < 0.0 && q.dot(front.perp()).abs() <= *span {
                            failures.push(format!(
                                "{shape:?}, {integrator:?} at dt = {dt:.4}, {speed} m/s: at {} \
                                 after step {s}, the obstacle's centre at {now}",
                                q + now
                            ));
                            break;
                        }
                    }
                }
            }
        }
    }
    // The paddle: a segment turning about its middle onto a particle 0.2 m out, just ahead.
    for &integrator in &swept {
        for dt in [FRAME, 1.0 / 30.0] {
            for spin in [5.0, 20.0, 40.0] {
                let mut scene = bare_scene(integrator, dt);
                scene.gravity = (0.0, 0.0);
                let start = center + DVec2::from_angle(0.5 * spin * dt) * 0.2;
                scene.particles = vec![particle(start.x, start.y, false)];
                scene.obstacles = vec![ObstacleDef::Segment {
                    a: (0.2, 0.4),
                    b: (0.8, 0.4),
                    thickness: 0.0,
                }];
                scene.contact = pairs_on(r, 0.5);
                let mut app = app_with(scene);
                set_obstacle_velocity(&mut app, DVec2::ZERO, spin);
                runs += 1;
                for s in 1..=10 {
                    step(&mut app, 1);
                    // The particle's angle ahead of the paddle's, within a half turn.
                    let turned = spin * dt * s as f64;
                    let q = pos(&app, 0) - center;
                    let ahead = DVec2::from_angle(-turned).rotate(q);
                    if ahead.y < 0.0 && ahead.x > 0.0 && q.length() <= 0.3 + r {
                        failures.push(format!(
                            "the paddle at {spin} rad/s, {integrator:?} at dt = {dt:.4}: at {} \
                             after step {s}, {ahead} in the paddle's frame",
                            q + center
                        ));
                        break;
                    }
                }
            }
        }
    }
    println!("{runs} runs, {} passed through", failures.len());
    assert_eq!(runs, 594);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A box resting on the ground and sliding at 2 m/s, under VBD at a frame's step and at two:
/// with friction μ = 0.5 it stops within 12 % of the v²/(2μg) = 0.408 m that Coulomb gives, and
/// without friction it slides on at its speed (3 m in 1.5 s, within 1 %). A stiff box (k =
/// 1e5 N/m, 10 g particles: block descent moves it as a whole by about 1/90,000 of the
/// remaining way a sweep at 1/30 s). Before its groups slid along the surface as a whole
/// (`contact::slide`), it kept none of its speed, with friction or without: its first step was
/// held back as if it were landing, and the descent never gave the body its way back.
///
/// Under implicit Euler the same, where the ground's friction after the solve slowed its held
/// particles one by one: at 1/30 s the box rose from 0.73 J to 2,556 J and slid 1.33 m, until
/// the friction slowed whole bodies.
#[test]
fn vbd_and_implicit_euler_slide_a_box_on_the_ground_as_coulomb_says_at_a_frames_step() {
    for integrator in [Integrator::Vbd, Integrator::ImplicitEuler] {
        box_on_the_ground_slides_as_coulomb_says(integrator);
    }
}

fn box_on_the_ground_slides_as_coulomb_says(integrator: Integrator) {
    let (v, mu, seconds) = (2.0, 0.5, 1.5);
    let slid = |dt: f64, friction: f64| {
        let mut scene = bare_scene(integrator, dt);
        (scene.gravity, scene.damping, scene.ground) = ((0.0, -9.8), 0.0, Some(0.0));
        scene.generate = vec![Generator::Grid {
            cols: 8,
            rows: 4,
            min: (0.1, 0.0),
            max: (0.24, 0.06),
            mass: 0.01,
            stiffness: 1e5,
            shear: true,
            pin: hooke::scene::Pin::None,
            vel: (v, 0.0),
            damping: None,
            plastic: None,
        }];
        scene.contact = Some(hooke::sim::ContactSettings {
            friction,
            ..Default::default()
        });
        let mut app = app_with(scene);
        let mean = |app: &App| {
            let x = solver(app).x();
            x.iter().map(|p| p.x).sum::<f64>() / x.len() as f64
        };
        let before = mean(&app);
        step(&mut app, (seconds / dt).round() as u64);
        mean(&app) - before
    };
    let coulomb = v * v / (2.0 * mu * 9.8);
    for dt in [FRAME, 2.0 * FRAME] {
        let gripped = slid(dt, mu);
        assert!(
            (gripped / coulomb - 1.0).abs() < 0.12,
            "{integrator:?} at {dt} s: the box slid {gripped} m; Coulomb stops it in {coulomb} m"
        );
        let free = slid(dt, 0.0);
        assert!(
            (free / (v * seconds) - 1.0).abs() < 0.01,
            "{integrator:?} at {dt} s: the box slid {free} m without friction, not {} m",
            v * seconds
        );
    }
}

/// The shipped `paddle` under VBD at a frame's step and at two: the strip the turning paddle
/// carries slides off it onto the ground, as under symplectic Euler at 1e-4 s (there by 2 s,
/// its mean height 9.2 mm): after 6 s its mean height is under 3 cm. Left to the vertices'
/// friction, on a surface that moves, the strip rode the paddle up to 0.67 m at 1/30 s and was
/// still on it at 6 s (mean height 0.116 m).
#[test]
fn vbd_slides_a_strip_off_a_turning_paddle_at_a_frames_step() {
    for dt in [FRAME, 2.0 * FRAME] {
        let mut app = shipped("paddle", Integrator::Vbd, dt);
        step(&mut app, (6.0 / dt).round() as u64);
        let x = solver(&app).x();
        let height = x.iter().map(|p| p.y).sum::<f64>() / x.len() as f64;
        assert!(
            height < 0.03,
            "at {dt} s the strip's mean height after 6 s is {height} m"
        );
    }
}

/// The shipped `slope` under VBD and implicit Euler at a frame's step and at two: the box on the
/// 35° slope (tan 35° = 0.70 over μ = 0.5) slides down onto the ground, as it does under
/// symplectic Euler at 1e-4 s, and the box on the 20° slope (0.36 under it) holds: it settles
/// in its first second (its centre moves 1.9 mm under symplectic Euler, 0.7 and 2.5 mm under
/// implicit Euler at 1/60 and 1/30 s) and then stays. Before the groups slid as a whole
/// (`contact::slide`), the steep box stood still under VBD at 1/120 s and larger; before
/// implicit Euler's surface friction held whole bodies, the gentle box crept down its slope at
/// 2.6 cm/s at 1/60 s.
#[test]
fn vbd_and_implicit_euler_slide_the_steep_slopes_box_and_hold_the_gentle_one_at_a_frames_step() {
    // Particles 0–24 are the gentle slope's box, 25–49 the steep one's.
    let centre = |app: &App, r: std::ops::Range<usize>| {
        let x = &solver(app).x()[r.clone()];
        x.iter().copied().sum::<DVec2>() / r.len() as f64
    };
    for integrator in [Integrator::Vbd, Integrator::ImplicitEuler] {
        for dt in [FRAME, 2.0 * FRAME] {
            let mut app = shipped("slope", integrator, dt);
            let (gentle, steep) = (centre(&app, 0..25), centre(&app, 25..50));
            step(&mut app, (1.0 / dt).round() as u64);
            let settled = centre(&app, 0..25);
            step(&mut app, (2.0 / dt).round() as u64);
            let (settling, crept) = (
                (settled - gentle).length(),
                (centre(&app, 0..25) - settled).length(),
            );
            assert!(
                settling < 3e-3 && crept < 1e-4,
                "{integrator:?} at {dt} s: the gentle box moved {settling} m in its first second \
                 and crept {crept} m in the next two"
            );
            let end = centre(&app, 25..50).y;
            assert!(
                end < 0.1,
                "{integrator:?} at {dt} s: the steep box's centre is at {end} m, from {} m; on \
                 the ground it rests at 0.04 m",
                steep.y
            );
        }
    }
}
