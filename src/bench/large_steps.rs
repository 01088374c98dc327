//! Large steps (`hooke bench large-steps`): every method at real-time steps, dt = 1/30 to
//! 1/960 s, on four scenes, error against a fine RK4 reference and wall time per simulated
//! second; and the static sag, the distance of each method's settled shape from the true
//! equilibrium ([`super::equilibrium`]).
//!
//! * `cloth32`, `cloth64`: the 32² and 64² cloths (k = 1e4, m = 1, pinned along the top row).
//! * `stiff-cloth32`: the 32² cloth with k = 1e6.
//! * `mass-ratio`: the hanging chain whose masses alternate 1 kg and 1 g.
//!
//! All with the scenes' damping μ = 10, and no ground (contact is not smooth, and a cloth that
//! hangs to the floor has no equilibrium of its springs alone). T = 1 s, released from rest.
//! Error: the largest distance of any particle from the reference over 10 checkpoints.

use super::equilibrium::equilibrium;
use super::median;
use super::trajectory::{self, Trajectory, max_position_error};
use super::work_precision::{Row, UNSTABLE_ERROR, fmt_time, table_header};
use crate::scene::{LoadedScene, Scene, presets};
use crate::sim::{self, Integrator, Iterations, SolveStats};
use bevy::math::DVec2;
use std::fmt::Write as _;

const CHECKPOINTS: u64 = 10;
const T_END: f64 = 1.0;

/// A method of the study: an integrator with its iteration counts.
#[derive(Debug, Clone)]
pub struct Method {
    /// The label in the tables and diagrams.
    pub label: String,
    /// The integrator.
    pub integrator: Integrator,
    /// Its iteration counts.
    pub iterations: Iterations,
    /// The damping μ inside the solve (projective dynamics, VBD; BDF2 always).
    pub drag_in_solve: bool,
}

/// The methods compared: every integrator at its defaults, and the iterative ones also worked
/// harder (implicit Euler to convergence, projective dynamics at 50 iterations, XPBD at 5
/// sweeps a substep).
pub fn methods() -> Vec<Method> {
    let d = Iterations::default();
    let mut out: Vec<Method> = Integrator::ALL
        .into_iter()
        .map(|integrator| Method {
            label: integrator.cli_name().to_string(),
            integrator,
            iterations: d,
            drag_in_solve: false,
        })
        .collect();
    out.push(Method {
        label: "implicit-euler ×10 Newton".into(),
        integrator: Integrator::ImplicitEuler,
        iterations: Iterations { newton: 10, ..d },
        drag_in_solve: false,
    });
    out.push(Method {
        label: "projective-dynamics ×50".into(),
        integrator: Integrator::ProjectiveDynamics,
        iterations: Iterations {
            projective: 50,
            ..d
        },
        drag_in_solve: false,
    });
    out.push(Method {
        label: "projective-dynamics μ in solve".into(),
        integrator: Integrator::ProjectiveDynamics,
        iterations: d,
        drag_in_solve: true,
    });
    out.push(Method {
        label: "xpbd 10×5".into(),
        integrator: Integrator::Xpbd,
        iterations: Iterations {
            xpbd_sweeps: 5,
            ..d
        },
        drag_in_solve: false,
    });
    out.push(Method {
        label: "xpbd tol 1e-3".into(),
        integrator: Integrator::Xpbd,
        iterations: Iterations {
            xpbd_tolerance: 1e-3,
            ..d
        },
        drag_in_solve: false,
    });
    out.push(Method {
        label: "vbd ×3".into(),
        integrator: Integrator::Vbd,
        iterations: Iterations { vbd: 3, ..d },
        drag_in_solve: false,
    });
    out.push(Method {
        label: "vbd ×50".into(),
        integrator: Integrator::Vbd,
        iterations: Iterations { vbd: 50, ..d },
        drag_in_solve: false,
    });
    out
}

/// A scene of the study and its reference step.
pub struct Problem {
    /// The scene's name.
    pub name: &'static str,
    scene: Scene,
    reference_dt: f64,
}

impl Problem {
    /// The scene (no ground, released from rest).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
}

fn scene(path: &str) -> Result<Scene, String> {
    let mut s = presets::resolve(path)
        .map_err(|e| e.to_string())?
        .scene
        .clone();
    s.ground = None;
    s.start_paused = false;
    Ok(s)
}

/// The four scenes (see the module docs).
pub fn problems() -> Result<Vec<Problem>, String> {
    let mut stiff = scene("cloth32")?;
    for g in &mut stiff.generate {
        if let crate::scene::Generator::Grid { stiffness, .. } = g {
            *stiffness = 1e6;
        }
    }
    Ok(vec![
        Problem {
            name: "cloth32",
            scene: scene("cloth32")?,
            reference_dt: 1e-4,
        },
        Problem {
            name: "cloth64",
            scene: scene("assets/scenes/bench/cloth64.ron")?,
            reference_dt: 1e-4,
        },
        Problem {
            name: "stiff-cloth32",
            scene: stiff,
            reference_dt: 1e-5,
        },
        Problem {
            name: "mass-ratio",
            scene: scene("assets/scenes/hard/mass_ratio.ron")?,
            reference_dt: 1e-5,
        },
    ])
}

/// The swept steps: 1/30 to 1/960 s.
pub const DTS: [f64; 6] = [
    1.0 / 30.0,
    1.0 / 60.0,
    1.0 / 120.0,
    1.0 / 240.0,
    1.0 / 480.0,
    1.0 / 960.0,
];

/// One run: a method at a dt on a scene.
#[derive(Debug, Clone)]
pub struct LargeRow {
    /// Error and wall time, as the work-precision study records them.
    pub row: Row,
    /// What the iterative methods did.
    pub stats: SolveStats,
}

/// The static sag of a method at dt = 1/60 s: how far its settled shape is from the true one.
#[derive(Debug, Clone)]
pub struct Sag {
    /// The scene.
    pub scene: String,
    /// The method's label.
    pub method: String,
    /// The largest distance of a particle from the equilibrium after settling, m; `None` when
    /// the method is unstable there.
    pub distance: Option<f64>,
    /// The equilibrium's largest drop below the starting shape, m (the scale of the sag).
    pub sag: f64,
}

/// A run for the performance targets: a method on a big cloth at dt = 1/60 s.
#[derive(Debug, Clone)]
pub struct TargetRow {
    /// The cloth.
    pub scene: String,
    /// The method's label.
    pub method: String,
    /// Wall time per step after the one-time setup, s (ECS sync included): the median of
    /// the rounds.
    pub step_s: f64,
    /// The one-time setup (projective dynamics' factorisation), s: the median of the rounds.
    pub setup_s: f64,
    /// Its error against the reference over 0.5 s, m.
    pub error: f64,
}

/// The cost of the first step after a cut of the 256² cloth.
#[derive(Debug, Clone)]
pub struct CutRow {
    /// The method's label.
    pub method: String,
    /// A usual step (the median of 5), s.
    pub usual_s: f64,
    /// The first step after the cut, s.
    pub after_cut_s: f64,
    /// Of it, the method's own precomputation redone (factorisations, colouring; XPBD's
    /// colouring is not timed), s.
    pub precompute_s: f64,
}

/// The study's results.
pub struct Report {
    /// Every run.
    pub rows: Vec<LargeRow>,
    /// The static sags.
    pub sags: Vec<Sag>,
    /// The target runs (64² and 256² at dt = 1/60 s).
    pub targets: Vec<TargetRow>,
    /// The first step after a cut of the 256² cloth, per large-step method.
    pub cuts: Vec<CutRow>,
    /// How each reference was obtained and how converged it is.
    pub notes: Vec<String>,
}

fn with(scene: &Scene, m: &Method, dt: f64) -> Scene {
    Scene {
        integrator: m.integrator,
        iterations: m.iterations,
        drag_in_solve: m.drag_in_solve,
        dt,
        ..scene.clone()
    }
}

/// Runs the study; `progress` is told what runs.
pub fn run(problems: &[Problem], mut progress: impl FnMut(&str)) -> Result<Report, String> {
    let (mut rows, mut sags, mut notes) = (vec![], vec![], vec![]);
    let rk4 = Method {
        label: "rk4".into(),
        integrator: Integrator::Rk4,
        iterations: Iterations::default(),
        drag_in_solve: false,
    };
    for p in problems {
        let dt = p.reference_dt;
        progress(&format!("{}: reference rk4 at dt = {dt:e}", p.name));
        let reference = trajectory::run(&with(&p.scene, &rk4, dt), T_END, CHECKPOINTS)?;
        let half = trajectory::run(&with(&p.scene, &rk4, dt / 2.0), T_END, CHECKPOINTS)?;
        let converged = max_position_error(&reference, &half.checkpoints);
        notes.push(format!(
            "{}: reference = rk4 at dt = {dt:.0e} s; rk4 at dt/2 differs from it by \
             {converged:.1e} m.",
            p.name
        ));
        for m in methods() {
            for dt in DTS {
                progress(&format!("{}: {} dt = 1/{:.0}", p.name, m.label, 1.0 / dt));
                let t = trajectory::run(&with(&p.scene, &m, dt), T_END, CHECKPOINTS)?;
                let error = max_position_error(&t, &reference.checkpoints);
                rows.push(LargeRow {
                    row: Row::of(p.name, &m.label, dt, &t, error),
                    stats: t.stats,
                });
            }
        }
        sags.extend(static_sags(p, &mut progress)?);
    }
    let targets = target_runs(&mut notes, &mut progress)?;
    let cuts = cut_costs(&mut progress)?;
    Ok(Report {
        rows,
        sags,
        targets,
        cuts,
        notes,
    })
}

/// The performance targets' scenes and methods: the 64² and 256² cloths at dt = 1/60 s over
/// 0.5 s (30 steps), XPBD, projective dynamics and implicit Euler at their defaults, each with
/// its error against RK4 at 1e-4 s.
fn target_runs(
    notes: &mut Vec<String>,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<TargetRow>, String> {
    let (t_end, dt) = (0.5, 1.0 / 60.0);
    let mut out = vec![];
    let d = Iterations::default();
    let rk4 = Method {
        label: "rk4".into(),
        integrator: Integrator::Rk4,
        iterations: d,
        drag_in_solve: false,
    };
    for (name, path) in [
        ("cloth64", "assets/scenes/bench/cloth64.ron"),
        ("cloth256", "assets/scenes/bench/cloth256.ron"),
    ] {
        let cloth = scene(path)?;
        progress(&format!("targets: {name} reference rk4 at dt = 1e-4"));
        let reference = trajectory::run(&with(&cloth, &rk4, 1e-4), t_end, CHECKPOINTS)?;
        notes.push(format!(
            "targets, {name}: reference = rk4 at dt = 1e-4 s over {t_end} s."
        ));
        let methods: Vec<Method> = [
            Integrator::Xpbd,
            Integrator::ProjectiveDynamics,
            Integrator::ImplicitEuler,
            Integrator::Bdf2,
            Integrator::Vbd,
        ]
        .into_iter()
        .map(|integrator| Method {
            label: integrator.cli_name().into(),
            integrator,
            iterations: d,
            drag_in_solve: false,
        })
        .collect();
        // The methods in alternating rounds, so that a slow spell of the machine falls on all.
        let mut runs: Vec<Vec<Trajectory>> = vec![vec![]; methods.len()];
        for round in 0..TARGET_ROUNDS {
            for (m, out) in methods.iter().zip(&mut runs) {
                progress(&format!(
                    "targets: {name} {} (round {})",
                    m.label,
                    round + 1
                ));
                out.push(trajectory::run(&with(&cloth, m, dt), t_end, CHECKPOINTS)?);
            }
        }
        for (m, rounds) in methods.into_iter().zip(runs) {
            // The one-time setup: the factorisations (BDF2's two, and projective dynamics').
            let setup =
                |t: &Trajectory| t.stats.factorization_seconds + t.stats.bdf2_factorization_seconds;
            let step = |t: &Trajectory| (t.wall_s - setup(t)) / t.steps.max(1) as f64;
            out.push(TargetRow {
                scene: name.into(),
                method: m.label,
                step_s: median(rounds.iter().map(step).collect()),
                setup_s: median(rounds.iter().map(setup).collect()),
                error: max_position_error(&rounds[0], &reference.checkpoints),
            });
        }
    }
    Ok(out)
}

/// Rounds of the targets' runs.
const TARGET_ROUNDS: usize = 3;

/// The large-step methods on the 256² cloth at dt = 1/60 s: 5 steps, then 5 timed one by one
/// (the usual step, their median), then a cut across the cloth's middle (the springs whose
/// ends lie on both sides of its middle row, over its middle half) and the one step after it,
/// timed: what a change of the spring graph costs each (a refactorisation for projective
/// dynamics and BDF2, a recolouring for XPBD and VBD).
fn cut_costs(progress: &mut impl FnMut(&str)) -> Result<Vec<CutRow>, String> {
    use crate::sim::{Position, Spring};
    let cloth = scene("assets/scenes/bench/cloth256.ron")?;
    let d = Iterations::default();
    let mut out = vec![];
    for integrator in [
        Integrator::ProjectiveDynamics,
        Integrator::Bdf2,
        Integrator::Vbd,
        Integrator::Xpbd,
        Integrator::ImplicitEuler,
    ] {
        progress(&format!("cut: cloth256 {integrator}"));
        let m = Method {
            label: integrator.cli_name().into(),
            integrator,
            iterations: d,
            drag_in_solve: false,
        };
        let loaded = LoadedScene::from_scene(with(&cloth, &m, 1.0 / 60.0), None)
            .map_err(|e| e.to_string())?;
        let mut app = crate::running_app(&loaded)?;
        let world = app.world_mut();
        sim::advance(world, 5);
        let mut usual = vec![];
        for _ in 0..5 {
            let t = std::time::Instant::now();
            sim::advance(world, 1);
            usual.push(t.elapsed().as_secs_f64());
        }
        // The cut: springs across the middle height, over the middle half of the width.
        let ys: Vec<f64> = world
            .query::<&Position>()
            .iter(world)
            .map(|p| p.0.y)
            .collect();
        let (lo, hi) = ys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &y| {
                (l.min(y), h.max(y))
            });
        let xs: Vec<f64> = world
            .query::<&Position>()
            .iter(world)
            .map(|p| p.0.x)
            .collect();
        let (left, right) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                (l.min(x), h.max(x))
            });
        let (mid, quarter) = ((lo + hi) / 2.0, (right - left) / 4.0);
        let centre = (left + right) / 2.0;
        let mut cut = vec![];
        for (e, s) in world
            .query::<(bevy::prelude::Entity, &Spring)>()
            .iter(world)
        {
            let (Some(a), Some(b)) = (world.get::<Position>(s.a), world.get::<Position>(s.b))
            else {
                continue;
            };
            let crosses = (a.0.y - mid) * (b.0.y - mid) < 0.0;
            let inside = ((a.0.x + b.0.x) / 2.0 - centre).abs() < quarter;
            if crosses && inside {
                cut.push(e);
            }
        }
        for e in cut {
            world.despawn(e);
        }
        let precomputed = |world: &bevy::prelude::World| {
            let st = world.resource::<sim::Solver>().solve_stats();
            st.factorization_seconds + st.bdf2_factorization_seconds + st.vbd_colouring_seconds
        };
        let before = precomputed(world);
        let t = std::time::Instant::now();
        sim::advance(world, 1);
        let after_cut_s = t.elapsed().as_secs_f64();
        out.push(CutRow {
            method: m.label,
            usual_s: median(usual),
            after_cut_s,
            precompute_s: precomputed(world) - before,
        });
    }
    Ok(out)
}

/// Each method settled for 10 s at dt = 1/60 s, against the equilibrium found by minimising
/// the potential from the best settled shape.
fn static_sags(p: &Problem, progress: &mut impl FnMut(&str)) -> Result<Vec<Sag>, String> {
    let dt = 1.0 / 60.0;
    progress(&format!("{}: static sag", p.name));
    let mut settled = vec![];
    for m in methods() {
        let loaded =
            LoadedScene::from_scene(with(&p.scene, &m, dt), None).map_err(|e| e.to_string())?;
        let mut app = crate::running_app(&loaded)?;
        let taken = sim::advance(app.world_mut(), (10.0 / dt) as u64);
        let solver = app.world().resource::<sim::Solver>();
        let ok = taken == (10.0 / dt) as u64 && solver.state_is_finite();
        settled.push((m.label, ok.then(|| solver.x().to_vec())));
    }
    // The equilibrium, and the starting shape, from the packed scene.
    let loaded = LoadedScene::from_scene(with(&p.scene, &methods()[0], dt), None)
        .map_err(|e| e.to_string())?;
    let app = crate::running_app(&loaded)?;
    let solver = app.world().resource::<sim::Solver>();
    let gravity = DVec2::from(p.scene.gravity);
    let start = settled
        .iter()
        .find(|(label, _)| label == "implicit-euler ×10 Newton")
        .and_then(|(_, x)| x.clone())
        .unwrap_or_else(|| solver.x().to_vec());
    let (eq, residual) = equilibrium(solver, &start, gravity);
    progress(&format!(
        "{}: equilibrium found, largest residual force {residual:.1e} N",
        p.name
    ));
    let sag = solver
        .x()
        .iter()
        .zip(&eq)
        .map(|(a, b)| a.y - b.y)
        .fold(0.0, f64::max);
    Ok(settled
        .into_iter()
        .map(|(method, x)| Sag {
            scene: p.name.to_string(),
            method,
            distance: x.map(|x| {
                x.iter()
                    .zip(&eq)
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f64::max)
            }),
            sag,
        })
        .collect())
}

/// The rows as CSV, with a header.
pub fn csv(rows: &[LargeRow]) -> String {
    let mut s = String::from(
        "scene,method,dt,steps,wall_s,wall_per_sim_s,error,stable,newton_per_step,\
         cg_per_step,pd_iterations_per_step,factorizations,factorization_s,xpbd_sweeps_per_step\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.2}"));
    for LargeRow { row: r, stats } in rows {
        let _ = writeln!(
            s,
            "{},{},{:?},{},{:.6e},{:.6e},{:.6e},{},{},{},{},{},{:.4e},{}",
            r.scene,
            r.integrator,
            r.dt,
            r.steps,
            r.wall_s,
            r.wall_s / T_END,
            r.error,
            r.stable,
            opt(stats.newton_iterations_per_step),
            opt(stats.cg_iterations_per_step),
            opt(stats.projective_iterations_per_step),
            stats.factorizations,
            stats.factorization_seconds,
            opt(stats.xpbd_sweeps_per_step),
        );
    }
    s
}

/// The report: per scene, a table of `error / wall time per simulated second` (a row per dt,
/// a column per method), and the static sags.
pub fn markdown(report: &Report, machine: &str, command: &str) -> String {
    let mut s = String::from("# Large steps\n\n");
    let _ = writeln!(
        s,
        "Every method at dt = 1/30 to 1/960 s. Made by `{command}` on {machine}, all solver \
         threads. A cell reads `error / wall time per simulated second`: error = the largest \
         distance (m) of any particle from the reference over 10 checkpoints up to T = 1 s; \
         *unstable* = non-finite or error ≥ {UNSTABLE_ERROR} m. The scenes keep their damping \
         μ = 10 and have no ground. The wall time includes the ECS sync of every tick (one \
         step a tick at these dt).\n"
    );
    for n in &report.notes {
        let _ = writeln!(s, "- {n}");
    }
    let labels: Vec<String> = methods().into_iter().map(|m| m.label).collect();
    let mut scenes: Vec<&str> = report.rows.iter().map(|r| r.row.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let rows: Vec<&LargeRow> = report
            .rows
            .iter()
            .filter(|r| r.row.scene == scene)
            .collect();
        let _ = writeln!(
            s,
            "\n## {scene}\n\n![large steps {scene}](large-steps-{scene}.png)\n"
        );
        table_header(&mut s, &[("dt (s)", "---:")], &labels);
        for dt in DTS {
            let _ = write!(s, "| 1/{:.0} |", 1.0 / dt);
            for l in &labels {
                let cell = rows
                    .iter()
                    .find(|r| r.row.dt == dt && &r.row.integrator == l)
                    .map(|r| {
                        if r.row.stable {
                            format!("{:.1e} / {}", r.row.error, fmt_time(r.row.wall_s / T_END))
                        } else {
                            "unstable".into()
                        }
                    })
                    .unwrap_or_default();
                let _ = write!(s, " {cell} |");
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "\nIterations per step at dt = 1/60: {}.",
            iteration_summary(&rows)
        );
    }
    let _ = writeln!(
        s,
        "\n## Targets: the 64² and 256² cloths at dt = 1/60 s\n\nWall time per step (ECS sync \
         included) over 0.5 s (30 steps) from rest, the median of {TARGET_ROUNDS} rounds that \
         alternate the methods; the one-time setup (projective dynamics' factorisation) apart; \
         and the error that buys against RK4 at 1e-4 s (largest distance over 10 \
         checkpoints).\n\n| cloth | method | time per step | one-time setup | error (m) |\n\
         | --- | --- | ---: | ---: | ---: |"
    );
    for t in &report.targets {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1e} |",
            t.scene,
            t.method,
            fmt_time(t.step_s),
            if t.setup_s > 0.0 {
                fmt_time(t.setup_s)
            } else {
                "none".into()
            },
            t.error
        );
    }
    let _ = writeln!(
        s,
        "\n## The first step after a cut of the 256² cloth\n\nAt dt = 1/60 s: a usual step \
         (the median of 5, ECS sync included), and the one step after a cut across the \
         cloth's middle (about 400 springs despawned), which redoes what the method \
         precomputes from the spring graph (timed apart: projective dynamics' and BDF2's \
         factorisations, VBD's colouring; XPBD's colouring is not timed), besides the ECS \
         layer's repacking of the state, which every method pays (implicit Euler precomputes \
         nothing).\n\n| method | usual step | first step after the cut | ratio | of it, the \
         method's precomputation |\n| --- | ---: | ---: | ---: | ---: |"
    );
    for c in &report.cuts {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} | {} |",
            c.method,
            fmt_time(c.usual_s),
            fmt_time(c.after_cut_s),
            c.after_cut_s / c.usual_s,
            fmt_time(c.precompute_s)
        );
    }
    let _ = writeln!(
        s,
        "\n## Static sag\n\nEach method settled for 10 s at dt = 1/60 s, against the true \
         equilibrium (the potential minimised directly by Newton's method with a line search). \
         A cell reads the largest distance (m) of a particle from it, and that as a fraction of \
         the equilibrium's largest sag.\n"
    );
    table_header(&mut s, &[("scene", "---"), ("sag (m)", "---:")], &labels);
    let mut scenes: Vec<&str> = report.sags.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let mine: Vec<&Sag> = report.sags.iter().filter(|r| r.scene == scene).collect();
        let sag = mine.first().map_or(0.0, |r| r.sag);
        let _ = write!(s, "| {scene} | {sag:.3e} |");
        for l in &labels {
            let cell = mine
                .iter()
                .find(|r| &r.method == l)
                .map(|r| match r.distance {
                    Some(d) => format!("{d:.1e} ({:.1} %)", 100.0 * d / sag.max(1e-300)),
                    None => "unstable".into(),
                })
                .unwrap_or_default();
            let _ = write!(s, " {cell} |");
        }
        s.push('\n');
    }
    s
}

/// "implicit-euler: 1 Newton, 47 CG; ..." for the iterative methods at dt = 1/60.
fn iteration_summary(rows: &[&LargeRow]) -> String {
    let mut parts = vec![];
    for r in rows.iter().filter(|r| r.row.dt == 1.0 / 60.0) {
        let st = &r.stats;
        let text = if let (Some(n), Some(cg)) =
            (st.newton_iterations_per_step, st.cg_iterations_per_step)
        {
            format!("{n:.0} Newton, {cg:.0} CG")
        } else if let Some(it) = st.projective_iterations_per_step {
            format!(
                "{it:.0} local/global, {} factorisation(s) of {} nonzeros in {}",
                st.factorizations,
                st.factor_nonzeros,
                fmt_time(st.factorization_seconds)
            )
        } else if let Some(sw) = st.xpbd_sweeps_per_step {
            format!("{sw:.0} sweeps over {} colours", st.xpbd_colours)
        } else if let Some(it) = st.bdf2_iterations_per_step {
            format!(
                "{it:.0} local/global, {} factorisation(s) in {}",
                st.bdf2_factorizations,
                fmt_time(st.bdf2_factorization_seconds)
            )
        } else if let Some(it) = st.vbd_iterations_per_step {
            format!("{it:.0} iterations over {} colours", st.vbd_colours)
        } else {
            continue;
        };
        parts.push(format!("{} {text}", r.row.integrator));
    }
    parts.join("; ")
}
