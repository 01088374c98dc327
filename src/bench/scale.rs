//! Scale: what the biggest cloths cost to load and to step (`hooke bench scale`).
//!
//! For cloths of 1 M to 16 M springs (500×500 to 2000×2000 particles, structural and shear
//! springs), the load's phases (validate and expand the generator, spawn the entities, pack
//! the solver), the peak memory the load added per spring, and the symplectic-Euler step rate
//! against the memory-bandwidth bound measured in the same run. Loading should scale linearly:
//! the table gives the seconds per million springs of each size.

use super::{perf, traffic};
use crate::scene::LoadedScene;
use crate::sim::{self, Integrator, SimParams, SolverThreads};
use std::fmt::Write as _;
use std::time::Instant;

/// Widths of the cloths: about 1, 2, 4, 8 and 16 million springs.
pub const WIDTHS: [usize; 5] = [500, 707, 1000, 1414, 2000];

/// One cloth's load and step figures.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Row {
    /// Particles per side.
    pub width: usize,
    /// Particles.
    pub particles: usize,
    /// Springs.
    pub springs: usize,
    /// Validating the scene and expanding its generator, s.
    pub expand_s: f64,
    /// Spawning the particle and spring entities, s.
    pub spawn_s: f64,
    /// Packing them into the solver, s.
    pub pack_s: f64,
    /// The resident memory the load and the steps added at their peak, bytes (`None` where
    /// the OS does not say).
    pub peak_bytes: Option<u64>,
    /// Of the load's wall time, the kernel's (mostly the first touch of new memory: page
    /// faults), s.
    pub kernel_s: Option<f64>,
    /// The page faults the load took.
    pub faults: Option<u64>,
    /// The resident memory the spawn added (the entities), bytes.
    pub spawn_bytes: Option<u64>,
    /// The resident memory the pack added (the solver's arrays), bytes.
    pub pack_bytes: Option<u64>,
    /// Symplectic-Euler steps: per thread count, (threads, spring updates per second), the
    /// median of the runs.
    pub rates: Vec<(usize, f64)>,
    /// The same, the fastest run: the figure measured like the bound, which is the best of
    /// its sweeps ([`traffic::bandwidth`]).
    pub best: Vec<(usize, f64)>,
    /// Per thread count, the bandwidth bound on the step, spring updates per second.
    pub bounds: Vec<(usize, f64)>,
}

impl Row {
    /// The whole load, s.
    pub fn load_s(&self) -> f64 {
        self.expand_s + self.spawn_s + self.pack_s
    }
}

/// Loads each cloth, measures its load, then steps it `steps` steps with symplectic Euler on
/// each thread count (the median of `repeat` runs, thread counts alternating), and measures
/// the bandwidth at its working set.
pub fn run(
    widths: &[usize],
    threads: &[usize],
    steps: u64,
    repeat: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Row>, String> {
    let pools = threads
        .iter()
        .map(|&t| SolverThreads::new(t))
        .collect::<Result<Vec<_>, _>>()?;
    let mut rows = vec![];
    for &w in widths {
        progress(&format!("cloth{w}: loading"));
        let base = memory::reset_peak();
        let cpu_before = memory::cpu();
        let start = Instant::now();
        let loaded = LoadedScene::from_scene(perf::cloth(w), None).map_err(|e| e.to_string())?;
        let expand_s = start.elapsed().as_secs_f64();
        let mut app = crate::headless_app();
        let world = app.world_mut();
        let before_spawn = memory::resident();
        let start = Instant::now();
        crate::scene::load_into_world(world, &loaded);
        let spawn_s = start.elapsed().as_secs_f64();
        let before_pack = memory::resident();
        let start = Instant::now();
        sim::pack(world)?;
        let pack_s = start.elapsed().as_secs_f64();
        let after_pack = memory::resident();
        let cpu_after = memory::cpu();
        let (kernel_s, faults) = match (cpu_before, cpu_after) {
            (Some(a), Some(b)) => (Some(b.kernel_s - a.kernel_s), Some(b.faults - a.faults)),
            _ => (None, None),
        };
        let grew = |a: Option<u64>, b: Option<u64>| Some(b?.saturating_sub(a?));
        let (spawn_bytes, pack_bytes) = (
            grew(before_spawn, before_pack),
            grew(before_pack, after_pack),
        );
        {
            let mut p = world.resource_mut::<SimParams>();
            p.paused = false;
            p.integrator = Integrator::SymplecticEuler;
        }
        let (particles, springs) = {
            let s = world.resource::<sim::Solver>();
            (s.particle_count(), s.spring_count())
        };
        progress(&format!(
            "cloth{w}: {springs} springs, {steps} steps, {repeat} x threads {threads:?}"
        ));
        let mut runs = vec![vec![]; pools.len()];
        for _ in 0..repeat.max(1) {
            for (pool, runs) in pools.iter().zip(&mut runs) {
                world.insert_resource(pool.clone());
                sim::advance(world, 2); // warm the buffers and the thread split
                let start = Instant::now();
                let taken = sim::advance(world, steps);
                let wall = start.elapsed().as_secs_f64();
                runs.push(springs as f64 * taken as f64 / wall);
            }
        }
        let best: Vec<(usize, f64)> = threads
            .iter()
            .zip(&runs)
            .map(|(&t, r)| (t, r.iter().copied().fold(0.0, f64::max)))
            .collect();
        let rates: Vec<(usize, f64)> = threads
            .iter()
            .zip(runs)
            .map(|(&t, r)| (t, super::median(r)))
            .collect();
        // The peak of the load and the steps together, with the scene still held as `hooke run`
        // holds it.
        let peak_bytes = base.and_then(|b| Some(memory::peak()?.saturating_sub(b)));
        drop((app, loaded));
        progress(&format!("cloth{w}: bandwidth"));
        let bytes = traffic::working_set(particles, springs);
        let per_update = traffic::bytes_per_step(particles, springs) / springs as f64;
        let bounds = threads
            .iter()
            .map(|&t| Ok((t, traffic::bandwidth(bytes, t)? / per_update)))
            .collect::<Result<Vec<_>, String>>()?;
        rows.push(Row {
            width: w,
            particles,
            springs,
            expand_s,
            spawn_s,
            pack_s,
            peak_bytes,
            kernel_s,
            faults,
            spawn_bytes,
            pack_bytes,
            rates,
            best,
            bounds,
        });
    }
    Ok(rows)
}

/// [`run`] with each cloth in a process of its own (`exe bench scale --one W ...`, which prints
/// its row as JSON): a process that loaded a smaller cloth first keeps some of its freed memory
/// resident, and the next cloth's allocations reuse it without raising the resident size, which
/// would understate their peak.
pub fn run_isolated(
    exe: &std::path::Path,
    widths: &[usize],
    threads: &[usize],
    steps: u64,
    repeat: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Row>, String> {
    let list: Vec<String> = threads.iter().map(|t| t.to_string()).collect();
    let mut rows = vec![];
    for &w in widths {
        progress(&format!("cloth{w}: in a process of its own"));
        let out = std::process::Command::new(exe)
            .args(["bench", "scale", "--one", &w.to_string()])
            .args(["--threads", &list.join(",")])
            .args([
                "--steps",
                &steps.to_string(),
                "--repeat",
                &repeat.to_string(),
            ])
            .stderr(std::process::Stdio::inherit())
            .output()
            .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text.lines().rev().find(|l| l.starts_with('{'));
        let row = line
            .filter(|_| out.status.success())
            .ok_or_else(|| format!("cloth{w}: the measuring process failed ({})", out.status))?;
        rows.push(serde_json::from_str(row).map_err(|e| format!("cloth{w}: {e}"))?);
    }
    Ok(rows)
}

/// The report as markdown, with the machine and the command that made it.
pub fn markdown(rows: &[Row], machine: &str, command: &str) -> String {
    let mut s = String::from("# Scale: loading and stepping millions of springs\n\n");
    let _ = writeln!(
        s,
        "Made by `{command}` on {machine}. Cloths of w×w particles with structural and shear \
         springs (the `Grid` generator), pinned along the top row. The load's phases: validate \
         the scene and expand its generator; spawn one entity per particle and per spring; pack \
         them into the solver. Memory is resident memory (`/proc/self/status`) per spring: \
         what the spawn added (the entities), what the pack added (the solver's arrays), and \
         the peak of the load and the steps together (`VmHWM` after resetting it), particles' \
         share included; each cloth is measured in a process of its own. Kernel time is the load's time in the kernel, mostly page faults: the \
         first touch of new memory, which on a VM can cost far more than the copy itself.\n"
    );
    let _ = writeln!(
        s,
        "| cloth | springs | expand (s) | spawn (s) | pack (s) | load (s) | s per M springs | of it kernel (s) | page faults | spawn B / spring | pack B / spring | peak B / spring |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for r in rows {
        let per = |b: Option<u64>| {
            b.map_or("n/a".into(), |b| {
                format!("{:.0}", b as f64 / r.springs as f64)
            })
        };
        let (spawn, pack, peak) = (per(r.spawn_bytes), per(r.pack_bytes), per(r.peak_bytes));
        let kernel = r.kernel_s.map_or("n/a".into(), |k| format!("{k:.2}"));
        let faults = r.faults.map_or("n/a".into(), |f| f.to_string());
        let _ = writeln!(
            s,
            "| cloth{} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {kernel} | {faults} | {spawn} | {pack} | {peak} |",
            r.width,
            r.springs,
            r.expand_s,
            r.spawn_s,
            r.pack_s,
            r.load_s(),
            r.load_s() / (r.springs as f64 / 1e6),
        );
    }
    let _ = writeln!(
        s,
        "\nSymplectic Euler with damping and ground, the full schedule, against the bandwidth \
         bound (the bytes a step moves, `src/bench/traffic.rs`, at the read-modify-write \
         bandwidth measured over the step's working set on as many threads, the best of its \
         sweeps), M spring updates/s; the step as the median of its runs and as the best run, \
         which is measured like the bound:\n"
    );
    let _ = writeln!(
        s,
        "| cloth | threads | median (M/s) | best run (M/s) | bound (M/s) | median of bound | best of bound |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for r in rows {
        for ((&(t, rate), &(_, bound)), &(_, best)) in r.rates.iter().zip(&r.bounds).zip(&r.best) {
            let _ = writeln!(
                s,
                "| cloth{} | {t} | {:.1} | {:.1} | {:.0} | {:.0} % | {:.0} % |",
                r.width,
                rate / 1e6,
                best / 1e6,
                bound / 1e6,
                100.0 * rate / bound,
                100.0 * best / bound
            );
        }
    }
    s
}

/// The rows as CSV, one per cloth and thread count, with a header.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "width,particles,springs,expand_s,spawn_s,pack_s,peak_bytes,threads,spring_updates_per_s,best_spring_updates_per_s,bound\n",
    );
    for r in rows {
        for ((&(t, rate), &(_, bound)), &(_, best)) in r.rates.iter().zip(&r.bounds).zip(&r.best) {
            let peak = r.peak_bytes.map_or(String::new(), |b| b.to_string());
            let _ = writeln!(
                s,
                "{},{},{},{:.3},{:.3},{:.3},{peak},{t},{rate:.0},{best:.0},{bound:.0}",
                r.width, r.particles, r.springs, r.expand_s, r.spawn_s, r.pack_s
            );
        }
    }
    s
}

/// The process's resident memory, from Linux's /proc (elsewhere every figure is `None`).
mod memory {
    fn status_kb(field: &str) -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        line.split_whitespace().nth(1)?.parse().ok()
    }

    /// The process's kernel time and page faults so far.
    pub struct Cpu {
        pub kernel_s: f64,
        pub faults: u64,
    }

    /// From /proc/self/stat: fields 10 (minor faults) and 15 (kernel time, in the clock ticks
    /// of 1/100 s Linux reports it in).
    pub fn cpu() -> Option<Cpu> {
        let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
        // The fields after the command name, which is in parentheses and may hold spaces.
        let rest: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
        let field = |n: usize| rest.get(n - 3)?.parse::<u64>().ok();
        Some(Cpu {
            kernel_s: field(15)? as f64 / 100.0,
            faults: field(10)?,
        })
    }

    /// The resident memory now, bytes.
    pub fn resident() -> Option<u64> {
        Some(status_kb("VmRSS:")? * 1024)
    }

    /// Resets the peak resident memory to the current one and returns it, bytes.
    pub fn reset_peak() -> Option<u64> {
        std::fs::write("/proc/self/clear_refs", "5").ok()?;
        resident()
    }

    /// The peak resident memory since the last reset, bytes.
    pub fn peak() -> Option<u64> {
        Some(status_kb("VmHWM:")? * 1024)
    }
}
