//! Speed: spring updates per second against scene size, integrator and thread count, on cloths
//! generated at about 1k, 10k, 100k and 1M springs plus the 256×256 cloth (`hooke bench perf`).
//! Every run steps the full schedule (sync, force, integrate, damping, ground, advance) of the
//! cloth with damping and ground on, as `hooke run` does.

use super::traffic;
use crate::scene::{Generator, LoadedScene, Pin, Scene};
use crate::sim::{self, Integrator, SimParams, SolverThreads};
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;

#[derive(Debug, Clone, Serialize)]
/// One measured figure: an integrator on a cloth at a thread count.
pub struct Row {
    /// The cloth (`cloth17`, ... `cloth501`).
    pub scene: String,
    /// Particles in the cloth.
    pub particles: usize,
    /// Springs in the cloth.
    pub springs: usize,
    /// The integrator's CLI name.
    pub integrator: String,
    /// Solver threads.
    pub threads: usize,
    /// Steps taken (the median run's).
    pub steps: u64,
    /// Wall time of the median run, s.
    pub wall_s: f64,
    /// Spring updates per second (springs × steps / wall).
    pub spring_updates_per_s: f64,
    /// Nanoseconds per spring update.
    pub ns_per_spring_update: f64,
}

/// A cloth of `w`×`w` particles with structural and shear springs, pinned along its top row.
pub fn cloth(w: usize) -> Scene {
    Scene {
        generate: vec![Generator::Grid {
            cols: w,
            rows: w,
            min: (0.0, 0.0),
            max: (1.0, 1.0),
            mass: 1.0,
            stiffness: 1e4,
            shear: true,
            pin: Pin::First,
            vel: (0.0, 0.0),
            damping: None,
            plastic: None,
        }],
        ..Scene::default()
    }
}

/// Cloth widths: about 1k, 10k, 100k and 1M springs, and the 256×256 cloth.
pub const WIDTHS: [usize; 5] = [17, 51, 159, 256, 501];

/// Relative cost of a step against symplectic Euler's (force evaluations and CG).
fn cost(i: Integrator) -> f64 {
    match i {
        Integrator::ExplicitEuler | Integrator::SymplecticEuler => 1.0,
        Integrator::VelocityVerlet => 2.0,
        Integrator::Rk4 => 4.0,
        Integrator::ImplicitEuler => 6.0,
        Integrator::ProjectiveDynamics => 4.0,
        Integrator::Xpbd => 10.0,
        Integrator::Bdf2 => 4.0,
        Integrator::Vbd => 12.0,
    }
}

/// How long a cloth took to load (validate, expand the generator, spawn, pack).
#[derive(Debug, Clone)]
pub struct LoadTime {
    /// The cloth.
    pub scene: String,
    /// Its springs.
    pub springs: usize,
    /// Load time, s.
    pub seconds: f64,
}

/// Runs the table. `budget` = spring updates per run (sets the steps); each row is the median
/// wall time of `repeats` runs, the thread counts alternating from run to run so that they
/// share the machine's noise. Returns the rows and the load time of each cloth.
pub fn run(
    widths: &[usize],
    threads: &[usize],
    budget: f64,
    repeats: usize,
    mut progress: impl FnMut(&str),
) -> Result<(Vec<Row>, Vec<LoadTime>), String> {
    let mut rows = vec![];
    let mut loads = vec![];
    for &w in widths {
        let name = format!("cloth{w}");
        progress(&format!("{name}: loading"));
        let start = Instant::now();
        let loaded = LoadedScene::from_scene(cloth(w), None).map_err(|e| e.to_string())?;
        let mut app = crate::running_app(&loaded)?;
        let world = app.world_mut();
        let springs = world.resource::<sim::Solver>().spring_count();
        let particles = world.resource::<sim::Solver>().particle_count();
        loads.push(LoadTime {
            scene: name.clone(),
            springs,
            seconds: start.elapsed().as_secs_f64(),
        });
        for integrator in Integrator::ALL {
            world.resource_mut::<SimParams>().integrator = integrator;
            let steps = (budget / (springs as f64 * cost(integrator))).clamp(10.0, 50_000.0) as u64;
            progress(&format!(
                "{name}: {integrator}, {steps} steps, {repeats} x threads {threads:?}"
            ));
            let pools = threads
                .iter()
                .map(|&t| SolverThreads::new(t))
                .collect::<Result<Vec<_>, _>>()?;
            let mut runs = vec![vec![]; threads.len()];
            for _ in 0..repeats.max(1) {
                for (pool, runs) in pools.iter().zip(&mut runs) {
                    world.insert_resource(pool.clone());
                    sim::advance(world, 2); // warm the buffers
                    let start = Instant::now();
                    let taken = sim::advance(world, steps);
                    runs.push((start.elapsed().as_secs_f64(), taken));
                }
            }
            for (&t, mut runs) in threads.iter().zip(runs) {
                runs.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (wall_s, taken) = runs[runs.len() / 2];
                let updates = springs as f64 * taken as f64;
                rows.push(Row {
                    scene: name.clone(),
                    particles,
                    springs,
                    integrator: integrator.cli_name().to_string(),
                    threads: t,
                    steps: taken,
                    wall_s,
                    spring_updates_per_s: updates / wall_s,
                    ns_per_spring_update: wall_s * 1e9 / updates,
                });
            }
        }
    }
    Ok((rows, loads))
}

/// One symplectic-Euler row against the bandwidth bound: the modelled bytes per spring update
/// ([`super::traffic`]) at the bandwidth measured for the cloth's working set.
#[derive(Debug, Clone)]
pub struct Bound {
    /// The cloth.
    pub scene: String,
    /// Solver threads.
    pub threads: usize,
    /// Modelled bytes moved per spring update.
    pub bytes_per_update: f64,
    /// The step's working set, MB.
    pub working_set_mb: f64,
    /// Read-modify-write bandwidth measured at that size, GB/s.
    pub bandwidth_gb_s: f64,
    /// Spring updates per second the bandwidth allows.
    pub bound: f64,
    /// Spring updates per second measured.
    pub measured: f64,
}

/// The bandwidth bound of each symplectic-Euler row.
pub fn bounds(rows: &[Row]) -> Result<Vec<Bound>, String> {
    let symplectic = Integrator::SymplecticEuler.cli_name();
    rows.iter()
        .filter(|r| r.integrator == symplectic)
        .map(|r| {
            let bytes = traffic::working_set(r.particles, r.springs);
            let bandwidth = traffic::bandwidth(bytes, r.threads)?;
            let per_update = traffic::bytes_per_step(r.particles, r.springs) / r.springs as f64;
            Ok(Bound {
                scene: r.scene.clone(),
                threads: r.threads,
                bytes_per_update: per_update,
                working_set_mb: bytes as f64 / 1e6,
                bandwidth_gb_s: bandwidth / 1e9,
                bound: bandwidth / per_update,
                measured: r.spring_updates_per_s,
            })
        })
        .collect()
}

/// The rows as CSV, one per figure, with a header.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,particles,springs,integrator,threads,steps,wall_s,spring_updates_per_s,ns_per_spring_update\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.6},{:.0},{:.3}",
            r.scene,
            r.particles,
            r.springs,
            r.integrator,
            r.threads,
            r.steps,
            r.wall_s,
            r.spring_updates_per_s,
            r.ns_per_spring_update
        );
    }
    s
}

/// The report as markdown: the figures, the load times and the bandwidth bounds, with the
/// machine and the command that made it.
pub fn markdown(
    rows: &[Row],
    loads: &[LoadTime],
    bounds: &[Bound],
    machine: &str,
    command: &str,
) -> String {
    let mut s = String::from("# Performance\n\n");
    let _ = writeln!(
        s,
        "Made by `{command}` on {machine}. Million spring updates per second (springs × steps / wall time) \
         for the full step schedule on cloths with damping and ground on; f64. A multi-stage \
         method updates each spring several times a step (Verlet 2, RK4 4, implicit Euler 1 \
         plus its CG products), and is counted once per step here. Each figure is the median \
         of the runs (thread counts alternating).\n"
    );
    let mut threads: Vec<usize> = rows.iter().map(|r| r.threads).collect();
    threads.sort_unstable();
    threads.dedup();
    let _ = write!(s, "| cloth | springs | integrator |");
    for t in &threads {
        let _ = write!(s, " {t} thread{} (M/s) |", if *t == 1 { "" } else { "s" });
    }
    let _ = write!(s, "\n| --- | ---: | --- |");
    for _ in &threads {
        let _ = write!(s, " ---: |");
    }
    s.push('\n');
    let mut keys: Vec<(&str, usize, &str)> = rows
        .iter()
        .map(|r| (r.scene.as_str(), r.springs, r.integrator.as_str()))
        .collect();
    keys.dedup();
    for (scene, springs, integrator) in keys {
        let _ = write!(s, "| {scene} | {springs} | {integrator} |");
        for t in &threads {
            let v = rows
                .iter()
                .find(|r| r.scene == scene && r.integrator == integrator && r.threads == *t)
                .map_or("".into(), |r| {
                    format!("{:.1}", r.spring_updates_per_s / 1e6)
                });
            let _ = write!(s, " {v} |");
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "\nSymplectic Euler against the memory-bandwidth bound: bytes a step moves (a model, pass \
         by pass: {} per particle, {} per spring; see `src/bench/traffic.rs`) per spring update, and \
         the best read-modify-write bandwidth measured over an array of the step's working-set \
         size on as many threads:\n",
        traffic::PARTICLE_BYTES,
        traffic::SPRING_BYTES
    );
    let _ = writeln!(
        s,
        "| cloth | threads | bytes / update | working set (MB) | bandwidth (GB/s) | bound (M/s) | measured (M/s) | of bound |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for b in bounds {
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} | {:.1} | {:.1} | {:.0} | {:.1} | {:.0} % |",
            b.scene,
            b.threads,
            b.bytes_per_update,
            b.working_set_mb,
            b.bandwidth_gb_s,
            b.bound / 1e6,
            b.measured / 1e6,
            100.0 * b.measured / b.bound
        );
    }
    let _ = writeln!(
        s,
        "\nLoading (validate, expand the generator, spawn the entities, pack the solver):\n"
    );
    for l in loads {
        let _ = writeln!(
            s,
            "- {} ({} springs): {:.2} s",
            l.scene, l.springs, l.seconds
        );
    }
    s
}
