//! Work-precision: for each problem and integrator, error against wall time over a sweep of dt.
//!
//! * `oscillator`: one spring (k = 1e4, m = 1, ω = 100 rad/s) to a pinned particle, displaced
//!   0.1 m, no gravity; exact solution x(t) = 0.7 + 0.1 cos(ωt). T = 1 s.
//! * `cloth32`: the 32×32 cloth (k = 1e4) without damping and ground, released from rest.
//!   T = 0.4 s. No closed form: the reference is RK4 at a step 8× below the smallest swept, shown
//!   converged by comparing it with RK4 at half that step.
//! * `cloth32-damped`: the same cloth with a dashpot of c = 5 N·s/m along every spring
//!   ([`DAMPED_CLOTH_DASHPOT`]), so that the diagram covers the damping term: c/k = 5e-4 s
//!   damps the fastest mode (ω ≈ 280 rad/s) at γ = (c/k)ω² ≈ 40 /s and the slow swing hardly
//!   at all. Same T, sweep and reference.
//!
//! Error: the largest distance of any particle from the reference over 10 evenly spaced
//! checkpoints up to T (so that a method cannot look good by meeting the solution at T only).
//! A run is *stable* when it stays finite and its error stays below 1 m (the scene's size).

use super::trajectory::{self, Trajectory, max_position_error};
use crate::scene::{Scene, presets};
use crate::sim::Integrator;
use bevy::math::DVec2;
use serde::Serialize;
use std::fmt::Write as _;

const CHECKPOINTS: u64 = 10;
/// Errors above this (metres) count as unstable: the scene is 1 m across.
pub const UNSTABLE_ERROR: f64 = 1.0;

#[derive(Debug, Clone, Serialize)]
/// One run of the study: an integrator at a dt on a problem, its error and its cost.
pub struct Row {
    /// The problem's name.
    pub scene: String,
    /// The integrator's CLI name.
    pub integrator: String,
    /// Time step, s.
    pub dt: f64,
    /// Steps to the end time.
    pub steps: u64,
    /// Wall time, s.
    pub wall_s: f64,
    /// Largest position error against the reference over the checkpoints, m.
    pub error: f64,
    /// Whether the run stayed finite and bounded.
    pub stable: bool,
    /// Mean CG iterations per step (implicit Euler; 0 otherwise).
    pub cg_iterations_per_step: f64,
}

impl Row {
    /// The row of a run of `label` at `dt` on `scene`, with its error against the reference.
    pub fn of(scene: &str, label: &str, dt: f64, t: &Trajectory, error: f64) -> Row {
        Row {
            scene: scene.to_string(),
            integrator: label.to_string(),
            dt,
            steps: t.steps,
            wall_s: t.wall_s,
            error,
            stable: t.finite && error < UNSTABLE_ERROR,
            cg_iterations_per_step: t.stats.cg_iterations_per_step.unwrap_or(0.0),
        }
    }
}

/// A problem of the study.
pub struct Problem {
    /// The problem's name (`oscillator`, `cloth32`).
    pub name: &'static str,
    scene: Scene,
    t_end: f64,
    dts: Vec<f64>,
    reference: Reference,
}

#[derive(Clone, Copy)]
enum Reference {
    Exact(fn(f64) -> Vec<DVec2>),
    /// RK4 at this dt (and, to show it converged, at half of it).
    Rk4(f64),
}

/// The study's results.
pub struct Report {
    /// Every run.
    pub rows: Vec<Row>,
    /// How each reference was obtained and how converged it is.
    pub notes: Vec<String>,
}

const OMEGA: f64 = 100.0;

/// The dashpot of every spring of `cloth32-damped`, N·s/m.
pub const DAMPED_CLOTH_DASHPOT: f64 = 5.0;

fn oscillator_exact(t: f64) -> Vec<DVec2> {
    vec![
        DVec2::new(0.2, 0.5),
        DVec2::new(0.7 + 0.1 * (OMEGA * t).cos(), 0.5),
    ]
}

/// The default problems. `quick` shortens the sweeps (for a smoke run).
pub fn problems(quick: bool) -> Vec<Problem> {
    let sweep = |start: f64, n: usize| -> Vec<f64> {
        (0..n).map(|j| start / f64::powi(2.0, j as i32)).collect()
    };
    let mut osc = Scene {
        gravity: (0.0, 0.0),
        damping: 0.0,
        ground: None,
        ..Scene::default()
    };
    osc.particles = vec![
        crate::scene::ParticleDef {
            pos: (0.2, 0.5),
            vel: (0.0, 0.0),
            mass: 1.0,
            pinned: true,
        },
        crate::scene::ParticleDef {
            pos: (0.8, 0.5),
            vel: (0.0, 0.0),
            mass: 1.0,
            pinned: false,
        },
    ];
    osc.springs = vec![crate::scene::SpringDef::new(0, 1, 0.5, OMEGA * OMEGA)];
    let mut cloth = presets::resolve("cloth32")
        .map(|l| l.scene)
        .unwrap_or_default();
    cloth.damping = 0.0;
    cloth.ground = None;
    let damped = Scene {
        spring_damping: DAMPED_CLOTH_DASHPOT,
        ..cloth.clone()
    };
    let (n_osc, n_cloth) = if quick { (5, 4) } else { (9, 7) };
    let cloth_reference = Reference::Rk4(4e-3 / f64::powi(2.0, n_cloth as i32 + 2));
    vec![
        Problem {
            name: "oscillator",
            scene: osc,
            t_end: 1.0,
            dts: sweep(0.02, n_osc),
            reference: Reference::Exact(oscillator_exact),
        },
        Problem {
            name: "cloth32",
            scene: cloth,
            t_end: 0.4,
            dts: sweep(4e-3, n_cloth),
            reference: cloth_reference,
        },
        Problem {
            name: "cloth32-damped",
            scene: damped,
            t_end: 0.4,
            dts: sweep(4e-3, n_cloth),
            reference: cloth_reference,
        },
    ]
}

fn with(scene: &Scene, integrator: Integrator, dt: f64) -> Scene {
    Scene {
        integrator,
        dt,
        ..scene.clone()
    }
}

/// The methods the card runs, whose f32 points the report shows beside the CPU's f64 ones.
pub const ON_THE_CARD: [Integrator; 2] = [Integrator::SymplecticEuler, Integrator::Xpbd];

/// A card row's label: the method's name and where it ran.
pub fn card_label(i: Integrator) -> String {
    format!("{} card f32", i.cli_name())
}

/// The graphics card the study also runs [`ON_THE_CARD`] on, in f32 (the `gpu` feature).
#[cfg(feature = "gpu")]
pub type Card<'a> = Option<&'a crate::solver::gpu::Gpu>;
/// Without the `gpu` feature there is no card.
#[cfg(not(feature = "gpu"))]
pub type Card<'a> = Option<&'a std::convert::Infallible>;

/// Runs the study; `progress` is told what runs. With a card, [`ON_THE_CARD`] run there too.
pub fn run(
    problems: &[Problem],
    card: Card,
    mut progress: impl FnMut(&str),
) -> Result<Report, String> {
    let mut rows = vec![];
    let mut notes = vec![];
    for p in problems {
        let reference: Vec<Vec<DVec2>> = match p.reference {
            Reference::Exact(f) => {
                notes.push(format!("{}: exact solution.", p.name));
                (1..=CHECKPOINTS)
                    .map(|j| f(p.t_end * j as f64 / CHECKPOINTS as f64))
                    .collect()
            }
            Reference::Rk4(dt) => {
                progress(&format!("{}: reference rk4 at dt = {dt:e}", p.name));
                let r =
                    trajectory::run(&with(&p.scene, Integrator::Rk4, dt), p.t_end, CHECKPOINTS)?;
                let half = trajectory::run(
                    &with(&p.scene, Integrator::Rk4, dt / 2.0),
                    p.t_end,
                    CHECKPOINTS,
                )?;
                let converged = max_position_error(&r, &half.checkpoints);
                notes.push(format!(
                    "{}: reference = rk4 at dt = {dt:.4e} s; rk4 at dt/2 differs from it by \
                     {converged:.2e} m (the reference's own error is about that).",
                    p.name
                ));
                r.checkpoints
            }
        };
        for integrator in Integrator::ALL {
            for &dt in &p.dts {
                progress(&format!("{}: {integrator} dt = {dt:e}", p.name));
                let t: Trajectory =
                    trajectory::run(&with(&p.scene, integrator, dt), p.t_end, CHECKPOINTS)?;
                let error = max_position_error(&t, &reference);
                rows.push(Row::of(p.name, integrator.cli_name(), dt, &t, error));
            }
        }
        #[cfg(feature = "gpu")]
        if let Some(gpu) = card {
            for integrator in ON_THE_CARD {
                for &dt in &p.dts {
                    progress(&format!(
                        "{}: {integrator} on the card, dt = {dt:e}",
                        p.name
                    ));
                    let t = trajectory::run_on_card(
                        &with(&p.scene, integrator, dt),
                        p.t_end,
                        CHECKPOINTS,
                        gpu,
                        crate::solver::gpu::Precision::F32,
                    )?;
                    let error = max_position_error(&t, &reference);
                    rows.push(Row::of(p.name, &card_label(integrator), dt, &t, error));
                }
            }
        }
    }
    if let Some(gpu) = card {
        #[cfg(feature = "gpu")]
        notes.push(format!(
            "On the card: {} in f32 on {} (the CPU's rows are f64).",
            crate::readable::list(&ON_THE_CARD.map(|i| i.cli_name())),
            gpu.adapter()
        ));
        #[cfg(not(feature = "gpu"))]
        match *gpu {}
    }
    Ok(Report { rows, notes })
}

/// The rows as CSV, with a header.
pub fn csv(rows: &[Row]) -> String {
    let mut s =
        String::from("scene,integrator,dt,steps,wall_s,error,stable,cg_iterations_per_step\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{:?},{},{:.6e},{:.6e},{},{:.2}",
            r.scene,
            r.integrator,
            r.dt,
            r.steps,
            r.wall_s,
            r.error,
            r.stable,
            r.cg_iterations_per_step
        );
    }
    s
}

/// One table per scene: a row per dt, a column per integrator, "error / wall time".
pub fn markdown(report: &Report, command: &str) -> String {
    let mut s = String::from("# Work-precision\n\n");
    let _ = writeln!(
        s,
        "Error against wall time for every integrator over a sweep of dt. Made by `{command}`.\n\n\
         Error = the largest distance (m) of any particle from the reference over 10 checkpoints \
         up to T. A cell reads `error / wall time`; *unstable* = non-finite or error ≥ {UNSTABLE_ERROR} m. \
         implicit-euler also gives its mean conjugate-gradient iterations per step.\n"
    );
    for n in &report.notes {
        let _ = writeln!(s, "- {n}");
    }
    let mut scenes: Vec<&str> = report.rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.scene == scene).collect();
        let mut dts: Vec<f64> = rows.iter().map(|r| r.dt).collect();
        dts.sort_by(|a, b| b.total_cmp(a));
        dts.dedup();
        let _ = writeln!(
            s,
            "\n## {scene}\n\n![work-precision {scene}](work-precision-{scene}.png)\n"
        );
        table_header(&mut s, &[("dt (s)", "---:")], Integrator::ALL);
        for dt in dts {
            let _ = write!(s, "| {dt:.3e} |");
            for i in Integrator::ALL {
                let cell = rows
                    .iter()
                    .find(|r| r.dt == dt && r.integrator == i.cli_name())
                    .map(|r| {
                        if !r.stable {
                            "unstable".to_string()
                        } else if r.cg_iterations_per_step > 0.0 {
                            format!(
                                "{:.2e} / {} ({:.1} CG it.)",
                                r.error,
                                fmt_time(r.wall_s),
                                r.cg_iterations_per_step
                            )
                        } else {
                            format!("{:.2e} / {}", r.error, fmt_time(r.wall_s))
                        }
                    })
                    .unwrap_or_default();
                let _ = write!(s, " {cell} |");
            }
            s.push('\n');
        }
        card_table(&mut s, &rows);
    }
    s
}

/// The price of f32: the methods the card runs, their CPU f64 error beside their card f32
/// error at each dt (nothing when the study ran without a card).
fn card_table(s: &mut String, rows: &[&Row]) {
    let on_card = |i: Integrator| card_label(i);
    if !rows
        .iter()
        .any(|r| ON_THE_CARD.iter().any(|&i| r.integrator == on_card(i)))
    {
        return;
    }
    let _ = writeln!(
        s,
        "\nOn the card, f32 against the CPU's f64 (error / wall time):\n"
    );
    let mut labels = vec![];
    for i in ON_THE_CARD {
        labels.push(format!("{} (CPU f64)", i.cli_name()));
        labels.push(on_card(i));
    }
    table_header(s, &[("dt (s)", "---:")], labels.iter());
    let mut dts: Vec<f64> = rows.iter().map(|r| r.dt).collect();
    dts.sort_by(|a, b| b.total_cmp(a));
    dts.dedup();
    for dt in dts {
        let _ = write!(s, "| {dt:.3e} |");
        for i in ON_THE_CARD {
            for label in [i.cli_name().to_string(), on_card(i)] {
                let cell = rows
                    .iter()
                    .find(|r| r.dt == dt && r.integrator == label)
                    .map(|r| {
                        if r.stable {
                            format!("{:.2e} / {}", r.error, fmt_time(r.wall_s))
                        } else {
                            "unstable".to_string()
                        }
                    })
                    .unwrap_or_default();
                let _ = write!(s, " {cell} |");
            }
        }
        s.push('\n');
    }
}

/// A markdown table's header: the leading columns as (title, alignment rule), then one
/// right-aligned column per label.
pub fn table_header<L: std::fmt::Display>(
    s: &mut String,
    lead: &[(&str, &str)],
    labels: impl IntoIterator<Item = L> + Clone,
) {
    s.push('|');
    for (title, _) in lead {
        let _ = write!(s, " {title} |");
    }
    for l in labels.clone() {
        let _ = write!(s, " {l} |");
    }
    s.push_str("\n|");
    for (_, rule) in lead {
        let _ = write!(s, " {rule} |");
    }
    for _ in labels {
        s.push_str(" ---: |");
    }
    s.push('\n');
}

/// A duration for a table: µs, ms or s.
pub fn fmt_time(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.0} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.1} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}
