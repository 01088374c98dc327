//! `hooke bench gpu`: the peer cloth's symplectic-Euler step on the CPU and on the graphics
//! card side by side in one run, in million spring updates per second, with one step a submit
//! and many steps a submit, in f32 and (where the adapter has it) f64.

use super::perf;
use crate::scene::LoadedScene;
use crate::sim::{self, Integrator, SimParams, Solver};
use crate::solver::gpu::{Gpu, GpuError, GpuStep};
use std::time::Instant;

/// The cloths measured by default: 0.26 M, 4.2 M and 16.8 M springs (the sizes).
pub const WIDTHS: [usize; 3] = [256, 1024, 2048];

/// One measured figure.
#[derive(Debug, Clone)]
pub struct Row {
    /// Particles per side.
    pub width: usize,
    /// Springs.
    pub springs: usize,
    /// "cpu" or the adapter's name.
    pub device: String,
    /// "f64" on the CPU; the card's precision.
    pub precision: &'static str,
    /// Steps recorded into one submit (0 on the CPU).
    pub per_submit: u64,
    /// Steps timed.
    pub steps: u64,
    /// The best of the runs' wall times, s (NaN when the figure could not be measured).
    pub wall_s: f64,
    /// Why a figure is missing (the cloth does not fit the adapter's buffers).
    pub note: Option<String>,
}

impl Row {
    /// The figure in a line, for the progress log: a run cut short still leaves what it
    /// measured.
    pub fn line(&self) -> String {
        match &self.note {
            Some(why) => format!(
                "cloth{}: {}, {}: {why}",
                self.width, self.device, self.precision
            ),
            None => format!(
                "cloth{}: {}, {}, {} a submit: {:.0} M spring updates/s, {:.2} µs a step",
                self.width,
                self.device,
                self.precision,
                if self.per_submit == 0 {
                    "-".to_string()
                } else {
                    self.per_submit.to_string()
                },
                self.rate_m(),
                self.us_per_step()
            ),
        }
    }

    /// Million spring updates per second.
    pub fn rate_m(&self) -> f64 {
        self.springs as f64 * self.steps as f64 / self.wall_s / 1e6
    }
    /// Microseconds per step.
    pub fn us_per_step(&self) -> f64 {
        self.wall_s * 1e6 / self.steps as f64
    }
}

/// Measures each cloth: `budget` spring updates a figure (which sets the steps, at least 3),
/// the best of `repeat` runs, the CPU on all its threads.
pub fn run(
    gpu: &Gpu,
    widths: &[usize],
    budget: f64,
    repeat: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Row>, String> {
    let mut rows = vec![];
    for &w in widths {
        progress(&format!("cloth{w}: loading"));
        let loaded = LoadedScene::from_scene(perf::cloth(w), None).map_err(|e| e.to_string())?;
        let mut app = crate::running_app(&loaded)?;
        let world = app.world_mut();
        world.resource_mut::<SimParams>().integrator = Integrator::SymplecticEuler;
        let springs = world.resource::<Solver>().spring_count();
        let steps = ((budget / springs as f64).round() as u64).clamp(3, 100_000);
        progress(&format!("cloth{w}: {springs} springs, CPU, {steps} steps"));
        sim::advance(world, 2);
        let mut best = f64::INFINITY;
        for _ in 0..repeat.max(1) {
            let start = Instant::now();
            let taken = sim::advance(world, steps);
            if taken < steps {
                return Err(format!("cloth{w} blew up on the CPU"));
            }
            best = best.min(start.elapsed().as_secs_f64());
        }
        rows.push(Row {
            width: w,
            springs,
            device: "CPU".into(),
            precision: "f64",
            per_submit: 0,
            steps,
            wall_s: best,
            note: None,
        });
        progress(&rows[rows.len() - 1].line());
        let params = world.resource::<SimParams>().clone();
        let settings = sim::gpu::settings(&params, steps);
        for precision in gpu.precisions() {
            let made = GpuStep::new(
                gpu,
                &world.resource::<Solver>().state,
                &settings,
                &[],
                precision,
            );
            let mut card = match made {
                Ok(card) => card,
                Err(e @ GpuError::TooLarge(_)) => {
                    progress(&format!("cloth{w}: {e}"));
                    rows.push(Row {
                        width: w,
                        springs,
                        device: gpu.adapter(),
                        precision: precision.name(),
                        per_submit: 0,
                        steps: 0,
                        wall_s: f64::NAN,
                        note: Some(e.to_string()),
                    });
                    continue;
                }
                Err(e) => return Err(e.to_string()),
            };
            card.run(3);
            card.finish().map_err(|e| e.to_string())?;
            for per_submit in [1, steps] {
                progress(&format!(
                    "cloth{w}: {}, {}, {steps} steps, {per_submit} a submit",
                    gpu.adapter(),
                    precision.name()
                ));
                let mut best = f64::INFINITY;
                for _ in 0..repeat.max(1) {
                    let start = Instant::now();
                    let mut left = steps;
                    while left > 0 {
                        let n = left.min(per_submit);
                        card.run(n as u32);
                        left -= n;
                    }
                    card.finish().map_err(|e| e.to_string())?;
                    best = best.min(start.elapsed().as_secs_f64());
                }
                rows.push(Row {
                    width: w,
                    springs,
                    device: gpu.adapter(),
                    precision: precision.name(),
                    per_submit,
                    steps,
                    wall_s: best,
                    note: None,
                });
                progress(&rows[rows.len() - 1].line());
            }
        }
    }
    Ok(rows)
}

/// One figure of XPBD at a frame's step: the time a step takes on the CPU or the card.
#[derive(Debug, Clone)]
pub struct FrameRow {
    /// Particles per side.
    pub width: usize,
    /// Springs.
    pub springs: usize,
    /// "CPU" or the adapter's name.
    pub device: String,
    /// "f64" on the CPU; the card's precision.
    pub precision: &'static str,
    /// Steps timed (all in one submit on the card).
    pub steps: u64,
    /// The best of the runs' wall times, s (NaN when the cloth does not fit the card).
    pub wall_s: f64,
    /// Particle pairs collide (at a radius of [`PAIR_RADIUS`] spacings).
    pub pairs: bool,
}

/// The contact radius of the cloths with particle pairs on, in spacings: the self-colliding
/// cloths' (the shipped folding strip's).
pub const PAIR_RADIUS: f64 = 0.45;

/// The widest cloth timed with particle pairs.
pub const PAIRS_UP_TO: usize = 1024;

impl FrameRow {
    /// The figure in a line, for the progress log.
    pub fn line(&self) -> String {
        let what = if self.pairs {
            "with pairs"
        } else {
            "without contact"
        };
        format!(
            "cloth{}: XPBD at 1/60 s {what}, {}, {}: {:.2} ms a step",
            self.width,
            self.device,
            self.precision,
            self.ms_per_step()
        )
    }

    /// Milliseconds a step.
    pub fn ms_per_step(&self) -> f64 {
        self.wall_s * 1e3 / self.steps as f64
    }
}

/// The cloths of [`run`] (their top rows pinned) under XPBD at dt = 1/60 s with its default 10
/// substeps and one sweep, without contact and with particle pairs colliding, on the CPU and on
/// the card in f32: `budget` spring projections a figure (2 to 120 steps: two seconds of frames),
/// the best of `repeat` runs, the card and the CPU each from the state after the first step.
pub fn run_frames(
    gpu: &Gpu,
    widths: &[usize],
    budget: f64,
    repeat: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<FrameRow>, String> {
    let mut rows = vec![];
    // With pairs up to the 1024²: beyond, the CPU's step takes minutes (2048² on two
    // cores had not done its seven steps in eight minutes, 2026-12-05).
    let cases = widths.iter().flat_map(|&w| [(w, false), (w, true)]);
    for (w, pairs) in cases.filter(|&(w, pairs)| !pairs || w <= PAIRS_UP_TO) {
        let what = if pairs {
            "with pairs"
        } else {
            "without contact"
        };
        progress(&format!("cloth{w}: XPBD at 1/60 s {what}, loading"));
        let loaded = LoadedScene::from_scene(perf::cloth(w), None).map_err(|e| e.to_string())?;
        let mut app = crate::running_app(&loaded)?;
        let world = app.world_mut();
        {
            let mut p = world.resource_mut::<SimParams>();
            p.integrator = Integrator::Xpbd;
            p.dt = 1.0 / 60.0;
            if pairs {
                p.contact = Some(crate::solver::ContactSettings {
                    radius: PAIR_RADIUS / (w.max(2) - 1) as f64,
                    friction: 0.3,
                    particles: true,
                    ..Default::default()
                });
            }
        }
        let params = world.resource::<SimParams>().clone();
        let springs = world.resource::<Solver>().spring_count();
        let substeps = params.iterations.xpbd_substeps.max(1);
        let steps =
            ((budget / (springs as f64 * f64::from(substeps))).round() as u64).clamp(2, 120);
        // The card first, from the state the CPU starts its timing at: with pairs the cost
        // grows as the cloth folds, so both time the same stretch of the fold, and a run cut
        // short while the CPU's slower steps run keeps the card's figure.
        sim::advance(world, 1);
        let settings = sim::gpu::settings(&params, steps);
        let made = GpuStep::new(
            gpu,
            &world.resource::<Solver>().state,
            &settings,
            &[],
            crate::solver::gpu::Precision::F32,
        );
        let mut best = f64::NAN;
        match made {
            Ok(mut card) => {
                progress(&format!("cloth{w}: XPBD on the card, {steps} steps"));
                card.run(1);
                card.finish().map_err(|e| e.to_string())?;
                best = f64::INFINITY;
                for _ in 0..repeat.max(1) {
                    let start = Instant::now();
                    card.run(steps as u32);
                    card.finish().map_err(|e| e.to_string())?;
                    best = best.min(start.elapsed().as_secs_f64());
                }
            }
            Err(e @ GpuError::TooLarge(_)) => progress(&format!("cloth{w}: {e}")),
            Err(e) => return Err(e.to_string()),
        }
        let on_card = FrameRow {
            width: w,
            springs,
            device: gpu.adapter(),
            precision: "f32",
            steps,
            wall_s: best,
            pairs,
        };
        progress(&on_card.line());
        progress(&format!("cloth{w}: XPBD on the CPU, {steps} steps"));
        let mut best = f64::INFINITY;
        for _ in 0..repeat.max(1) {
            let start = Instant::now();
            sim::advance(world, steps);
            best = best.min(start.elapsed().as_secs_f64());
        }
        let on_cpu = FrameRow {
            width: w,
            springs,
            device: "CPU".into(),
            precision: "f64",
            steps,
            wall_s: best,
            pairs,
        };
        progress(&on_cpu.line());
        rows.extend([on_cpu, on_card]);
    }
    Ok(rows)
}

/// XPBD's table: milliseconds a step and the share of a 1/60 s frame it takes.
pub fn frames_markdown(rows: &[FrameRow]) -> String {
    let mut s = String::from(
        "\n## XPBD at a frame's step\n\nThe same cloths under XPBD at dt = 1/60 s (10 substeps, one \
         sweep each, 8 colours), hanging from one corner, without contact and with particle pairs \
         colliding up to 1024² (radius 0.45 spacings, friction 0.3: the grid rebuilt and the pairs \
         pushed apart after every substep, then the iterations and the velocity pass after the step): a \
         step's time on the CPU (f64, all threads) and on the card (f32, all steps in one \
         submit). Real time needs a step under 16.7 ms.\n\n\
         | cloth | springs | contact | device | precision | steps | ms a step | real-time factor |\n\
         |---|---:|---|---|---|---:|---:|---:|\n",
    );
    for r in rows {
        let contact = if r.pairs { "pairs" } else { "none" };
        if r.wall_s.is_nan() {
            s += &format!(
                "| {w}² | {:.2} M | {contact} | {} | {} | – | does not fit | – |\n",
                r.springs as f64 / 1e6,
                r.device,
                r.precision,
                w = r.width
            );
            continue;
        }
        s += &format!(
            "| {w}² | {:.2} M | {contact} | {} | {} | {} | {:.2} | {:.2}× |\n",
            r.springs as f64 / 1e6,
            r.device,
            r.precision,
            r.steps,
            r.ms_per_step(),
            (1000.0 / 60.0) / r.ms_per_step(),
            w = r.width
        );
    }
    s
}

/// The rows as CSV.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "width,springs,device,precision,per_submit,steps,wall_s,m_spring_updates_per_s,us_per_step\n",
    );
    for r in rows {
        s += &format!(
            "{},{},\"{}\",{},{},{},{:.6},{:.1},{:.2}\n",
            r.width,
            r.springs,
            r.device,
            r.precision,
            r.per_submit,
            r.steps,
            r.wall_s,
            r.rate_m(),
            r.us_per_step()
        );
    }
    s
}

/// The report: a table a cloth, the CPU's row first, and each card row's speed-up over it.
pub fn markdown(rows: &[Row], machine: &str, command: &str) -> String {
    let mut s = String::from("# The step on the graphics card\n\n");
    s += &format!(
        "The peer cloth (pinned top row, structural and shear springs, k = 1e4, dt = 1e-4 s, \
         symplectic Euler) on the CPU and on the card in one run; the best of the runs. \
         Measured on {machine} with `{command}`.\n\n"
    );
    s += "| cloth | springs | device | precision | steps a submit | steps | M spring updates/s | µs a step | against the CPU |\n";
    s += "|---|---:|---|---|---:|---:|---:|---:|---:|\n";
    for r in rows {
        if let Some(note) = &r.note {
            s += &format!(
                "| {w}² | {:.2} M | {} | {} | – | – | – | – | {note} |\n",
                r.springs as f64 / 1e6,
                r.device,
                r.precision,
                w = r.width
            );
            continue;
        }
        let cpu = rows
            .iter()
            .find(|c| c.width == r.width && c.device == "CPU")
            .map_or(f64::NAN, |c| c.rate_m());
        s += &format!(
            "| {w}² | {:.2} M | {} | {} | {} | {} | {:.0} | {:.1} | {:.2}× |\n",
            r.springs as f64 / 1e6,
            r.device,
            r.precision,
            if r.device == "CPU" {
                "–".to_string()
            } else {
                r.per_submit.to_string()
            },
            r.steps,
            r.rate_m(),
            r.us_per_step(),
            r.rate_m() / cpu,
            w = r.width
        );
    }
    s
}
