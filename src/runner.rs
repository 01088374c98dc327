//! Headless runs of a scene through the same ECS systems as the app (`hooke run`).

use crate::scene::{LoadedScene, load_into_world};
use crate::sim::{self, Integrator, SimClock, SimParams, SimStatus, Solver};
use crate::solver::MAX_THREADS;
use bevy::ecs::world::World;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// How long to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Duration {
    /// This many steps.
    Steps(u64),
    /// Simulated seconds; rounded to the nearest whole number of steps.
    Time(f64),
}

/// Where the steps run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Device {
    /// The CPU, in f64: every method and feature.
    #[default]
    Cpu,
    /// The graphics card (the `gpu` feature): symplectic and explicit Euler with obstacles, the
    /// ground's contact, contact between particles, dashpots and tearing, and XPBD with the
    /// same; a scene that needs more (contact by outlines, pressure, muscles, plasticity) runs on the CPU and the
    /// run says why.
    Gpu,
}

/// The card's number width (`--gpu-precision`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GpuPrecision {
    /// f32, every card's native width.
    #[default]
    F32,
    /// f64, on adapters with `SHADER_F64`.
    F64,
}

impl GpuPrecision {
    /// The width as the flag and the JSON write it: `f32`, `f64`.
    pub fn name(self) -> &'static str {
        match self {
            GpuPrecision::F32 => "f32",
            GpuPrecision::F64 => "f64",
        }
    }
}

/// Overrides applied on top of the scene.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// Integrator (overrides the scene's).
    pub integrator: Option<Integrator>,
    /// Time step, s (overrides the scene's).
    pub dt: Option<f64>,
    /// Stiffness of every spring, N/m.
    pub stiffness: Option<f64>,
    /// Damping rate μ, 1/s (overrides the scene's).
    pub damping: Option<f64>,
    /// The dashpot c of every spring without its own, N·s/m (overrides the scene's
    /// `spring_damping`).
    pub spring_damping: Option<f64>,
    /// Take the damping inside the solve (projective dynamics, VBD).
    pub drag_in_solve: bool,
    /// Tearing strain (overrides the scene's `tear`).
    pub tear: Option<f64>,
    /// Implicit Euler's Newton steps per step (overrides the scene's).
    pub newton_iterations: Option<u32>,
    /// Projective dynamics' local/global iterations per step (overrides the scene's).
    pub pd_iterations: Option<u32>,
    /// XPBD's substeps per step (overrides the scene's).
    pub xpbd_substeps: Option<u32>,
    /// XPBD's constraint sweeps per substep (overrides the scene's).
    pub xpbd_iterations: Option<u32>,
    /// XPBD's constraint tolerance (overrides the scene's `xpbd_tolerance`).
    pub xpbd_tolerance: Option<f64>,
    /// XPBD's cap on sweeps toward the tolerance (overrides the scene's).
    pub xpbd_max_sweeps: Option<u32>,
    /// BDF2's local/global iterations per step (overrides the scene's).
    pub bdf2_iterations: Option<u32>,
    /// VBD's iterations per step (overrides the scene's).
    pub vbd_iterations: Option<u32>,
    /// VBD's Chebyshev ρ (overrides the scene's `vbd_chebyshev`).
    pub vbd_chebyshev: Option<f64>,
    /// Solver threads (default: all cores).
    pub threads: Option<usize>,
    /// Time each pass of the step (the report's `pass_seconds`).
    pub profile: bool,
    /// Run the particle passes as separate systems instead of one fused sweep
    /// ([`sim::ParticleSweep`]), so that `profile` times each of them.
    pub separate_passes: bool,
    /// Where the steps run.
    pub device: Device,
    /// The card's number width, with `device` the GPU.
    pub gpu_precision: GpuPrecision,
    /// Show the run's progress on stderr, on one line rewritten in place, once it has run a
    /// second (`hooke run` sets it where stderr is a terminal). The CPU's steps then run in
    /// stretches of whole ticks, and the card's tell after each read-back, so the result is
    /// the same bit for bit.
    pub progress: bool,
}

impl Overrides {
    /// Checks the values a user typed; names the flag at fault.
    pub fn validate(&self) -> Result<(), String> {
        if let Some((dt, rule)) = self.dt.and_then(|d| Some((d, sim::dt_problem(d)?))) {
            return Err(format!("--dt {rule}, got {dt}"));
        }
        if let Some(k) = self.stiffness.filter(|k| !(k.is_finite() && *k >= 0.0)) {
            return Err(format!("--stiffness must be finite and >= 0, got {k}"));
        }
        if let Some(mu) = self.damping.filter(|m| !(m.is_finite() && *m >= 0.0)) {
            return Err(format!("--damping must be finite and >= 0, got {mu}"));
        }
        if let Some(c) = self
            .spring_damping
            .filter(|c| !(c.is_finite() && *c >= 0.0))
        {
            return Err(format!("--spring-damping must be finite and >= 0, got {c}"));
        }
        if let Some(s) = self.tear.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("--tear must be finite and > 0, got {s}"));
        }
        let counts = [
            ("--newton-iterations", self.newton_iterations),
            ("--pd-iterations", self.pd_iterations),
            ("--xpbd-substeps", self.xpbd_substeps),
            ("--xpbd-iterations", self.xpbd_iterations),
            ("--xpbd-max-sweeps", self.xpbd_max_sweeps),
            ("--bdf2-iterations", self.bdf2_iterations),
            ("--vbd-iterations", self.vbd_iterations),
        ];
        for (flag, n) in counts {
            if let Some(n) = n.filter(|&n| !sim::Iterations::allowed(n)) {
                return Err(format!("{flag} {}, got {n}", sim::Iterations::RULE));
            }
        }
        if let Some(t) = self
            .xpbd_tolerance
            .filter(|t| !(t.is_finite() && *t >= 0.0))
        {
            return Err(format!("--xpbd-tolerance must be finite and >= 0, got {t}"));
        }
        if let Some(r) = self.vbd_chebyshev.filter(|r| !(0.0..1.0).contains(r)) {
            return Err(format!("--vbd-chebyshev must be in [0, 1), got {r}"));
        }
        if let Some(t) = self.threads {
            check_threads(t)?;
        }
        Ok(())
    }
}

/// A `--threads` value: 1 to [`MAX_THREADS`] (what [`crate::solver::Threads::new`] accepts),
/// checked before anything is loaded or measured.
pub fn check_threads(threads: usize) -> Result<(), String> {
    if !(1..=MAX_THREADS).contains(&threads) {
        return Err(format!(
            "--threads must be between 1 and {MAX_THREADS}, got {threads}"
        ));
    }
    Ok(())
}

/// What a run reports (`--json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunReport {
    /// The scene's path.
    pub scene: String,
    /// The integrator's CLI name.
    pub integrator: String,
    /// Time step, s.
    pub dt: f64,
    /// Steps asked for.
    pub steps: u64,
    /// Steps taken (fewer when a step blew up).
    pub steps_taken: u64,
    /// Simulated time at the end, s.
    pub sim_time: f64,
    /// Particles.
    pub particles: usize,
    /// Springs at the end.
    pub springs: usize,
    /// Solver threads.
    pub threads: usize,
    /// Wall time of the stepping, s.
    pub wall_s: f64,
    /// Steps per wall-clock second.
    pub steps_per_s: f64,
    /// Spring updates per wall-clock second.
    pub spring_updates_per_s: f64,
    /// Total energy before the first step, J: the particles', and with the `avian` feature the
    /// rigid bodies' (kinetic, turning and in gravity).
    pub energy_start: f64,
    /// Total energy at the end, J.
    pub energy_end: f64,
    /// The largest total energy at the end of any step, J (the start's when no step was
    /// taken): above `energy_start`, the run gained energy somewhere.
    pub energy_max: f64,
    /// dt · ω_max at the start (power-iteration estimate of the fastest mode).
    pub h_omega_max: f64,
    /// The largest stable dt for this scene and integrator; `null` when unconditional.
    pub stable_dt: Option<f64>,
    /// Gershgorin upper bound on ω_max, rad/s.
    pub omega_max_bound: f64,
    /// The dashpots' damping rate of the fastest mode, (c/k)_max ω_max², 1/s; absent without
    /// dashpots.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dashpot_rate: Option<f64>,
    /// Whether every step stayed finite (and the energy watch, when on, never stopped it).
    pub finite: bool,
    /// Springs broken by tearing during the run (0 when tearing is off).
    pub springs_torn: u64,
    /// Contacts resolved in the last step, particle–surface (ground and obstacles) and particle
    /// pairs together; 0 when the scene has no obstacles and no contact settings (the contact
    /// pass does not run).
    pub contacts: usize,
    /// Of those, the particle pairs (0 unless `contact.particles` is on).
    pub pair_contacts: usize,
    /// Mean conjugate-gradient iterations per step (implicit Euler only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cg_iterations_per_step: Option<f64>,
    /// The iteration counts in effect.
    pub iterations: sim::Iterations,
    /// What the iterative methods did: Newton steps, projective dynamics' iterations and
    /// factorisations (count, wall time, factor size), XPBD's sweeps and colours.
    pub solve: sim::SolveStats,
    /// Wall time per pass, summed over the run (`--profile` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pass_seconds: Option<sim::PassTimes>,
    /// The contact pass's wall time over the run (`--profile` only), s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_seconds: Option<f64>,
    /// Where the steps ran: "cpu" or "gpu" (a scene the card does not run runs on the CPU,
    /// and `device_note` says why).
    pub device: Device,
    /// The graphics adapter, when the steps ran on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    /// The card's number width, when the steps ran on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precision: Option<GpuPrecision>,
    /// Why a run asked for on the GPU ran on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub device_note: Option<String>,
    /// The 1-based step that produced a non-finite value, or a state whose energy is not finite
    /// (with [`crate::sim::watch::EnergyPeak`], which `hooke run` keeps), if one did. The final state (and
    /// `--out`) is then the last finite one, at the end of the tick before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blowup_step: Option<u64>,
    /// The rigid bodies where the run left them, as a scene writes them (shape at its pose,
    /// mass, velocity, spin, fixed); absent in a scene without them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<crate::scene::BodyDef>,
}

/// A finished run: the report and the world, to read the final state from.
pub struct Run {
    /// What the run reports.
    pub report: RunReport,
    /// The headless app, holding the final state.
    pub app: bevy::app::App,
}

impl Run {
    /// The final packed state.
    pub fn solver(&self) -> &Solver {
        self.app.world().resource::<Solver>()
    }

    /// Writes the final state as CSV: `id,x,y,vx,vy`, one row per particle in scene order,
    /// floats printed so that they parse back to the same f64.
    pub fn write_csv(&self, out: &mut impl Write) -> std::io::Result<()> {
        let s = self.solver();
        writeln!(out, "id,x,y,vx,vy")?;
        for (i, (x, v)) in s.x.iter().zip(&s.v).enumerate() {
            writeln!(out, "{i},{:?},{:?},{:?},{:?}", x.x, x.y, v.x, v.y)?;
        }
        Ok(())
    }

    /// Writes [`Run::write_csv`]'s CSV to a file.
    pub fn save_csv(&self, path: &Path) -> std::io::Result<()> {
        let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
        self.write_csv(&mut f)?;
        f.flush()
    }
}

/// Loads the scene into a headless app, applies the overrides and runs it.
pub fn run(loaded: &LoadedScene, overrides: &Overrides, duration: Duration) -> Result<Run, String> {
    overrides.validate()?;
    let mut app = crate::headless_app();
    if let Some(t) = overrides.threads {
        app.insert_resource(sim::SolverThreads::new(t)?);
    }
    if overrides.profile {
        sim::profile::enable(&mut app);
    }
    if overrides.separate_passes {
        app.insert_resource(sim::ParticleSweep { fused: false });
    }
    crate::add_bodies_for(&mut app, loaded);
    let world = app.world_mut();
    load_into_world(world, loaded);
    {
        let mut p = world.resource_mut::<SimParams>();
        p.paused = false;
        if let Some(i) = overrides.integrator {
            p.integrator = i;
        }
        if let Some(dt) = overrides.dt {
            p.dt = dt;
        }
        if let Some(mu) = overrides.damping {
            p.damping = mu;
        }
        if let Some(c) = overrides.spring_damping {
            p.spring_damping = c;
        }
        if overrides.drag_in_solve {
            p.drag_in_solve = true;
        }
        p.stiffness_override = overrides.stiffness;
        if overrides.tear.is_some() {
            p.tear = overrides.tear;
        }
        let it = &mut p.iterations;
        for (field, value) in [
            (&mut it.newton, overrides.newton_iterations),
            (&mut it.projective, overrides.pd_iterations),
            (&mut it.xpbd_substeps, overrides.xpbd_substeps),
            (&mut it.xpbd_sweeps, overrides.xpbd_iterations),
            (&mut it.xpbd_max_sweeps, overrides.xpbd_max_sweeps),
            (&mut it.bdf2, overrides.bdf2_iterations),
            (&mut it.vbd, overrides.vbd_iterations),
        ] {
            if let Some(v) = value {
                *field = v;
            }
        }
        if let Some(t) = overrides.xpbd_tolerance {
            it.xpbd_tolerance = t;
        }
        if let Some(r) = overrides.vbd_chebyshev {
            it.vbd_chebyshev = r;
        }
    }
    let params = world.resource::<SimParams>().clone();
    let steps = match duration {
        Duration::Steps(n) => n,
        Duration::Time(t) => {
            if !(t.is_finite() && t >= 0.0) {
                return Err(format!("--time must be finite and >= 0, got {t}"));
            }
            let n = (t / params.dt).round();
            // `as u64` saturates: a --time past what a run counts would run forever unsaid.
            if n >= u64::MAX as f64 {
                return Err(format!(
                    "--time {t} s at dt {} s is {n:.3e} steps, more than a run counts ({:.3e})",
                    params.dt,
                    u64::MAX as f64
                ));
            }
            n as u64
        }
    };
    // Check and pack the scene without stepping, so that the start energy is that of the loaded
    // state and the timed steps do not include the first tick's check of every spring.
    sim::check(world)?;
    sim::pack(world)?;
    let bodies_start = bodies_energy(world);
    let energy_start = world.resource::<Solver>().energy(params.gravity).total() + bodies_start;
    let stability = sim::stability::estimate(world.resource::<Solver>(), &params);

    world.insert_resource(sim::watch::EnergyPeak {
        bodies: bodies_start,
        ..Default::default()
    });
    let mut on = OnDevice::default();
    let card = match overrides.device {
        Device::Cpu => None,
        Device::Gpu => gpu::card(world, overrides.gpu_precision, &mut on)?,
    };
    let start = Instant::now();
    let mut progress = overrides.progress.then(|| Progress::new(steps));
    let taken = advance(world, card.as_ref(), steps, progress.as_mut())?;
    drop(progress);
    // The step's own time: the energy peak's evaluations are kept apart.
    let peak = *world.resource::<sim::watch::EnergyPeak>();
    let wall_s = (start.elapsed().as_secs_f64() - peak.seconds).max(0.0);
    let bodies = crate::scene::bodies::body_defs(world);
    let bodies_end = bodies_energy(world);

    let solver = world.resource::<Solver>();
    let solve = solver.solve_stats();
    let energy_end = solver.energy(params.gravity).total() + bodies_end;
    let status = *world.resource::<SimStatus>();
    let clock = *world.resource::<SimClock>();
    let blowup_step = match status {
        SimStatus::BlewUp { step, .. } | SimStatus::EnergyGrew { step, .. } => Some(step),
        SimStatus::Running | SimStatus::InvalidInput(_) => None,
    };
    let springs = solver.spring_count();
    let report = RunReport {
        scene: loaded
            .path
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        integrator: params.integrator.cli_name().to_string(),
        dt: params.dt,
        steps,
        steps_taken: taken,
        sim_time: clock.time,
        particles: solver.particle_count(),
        springs,
        threads: world.resource::<sim::SolverThreads>().threads(),
        wall_s,
        steps_per_s: taken as f64 / wall_s.max(1e-12),
        spring_updates_per_s: (springs as f64 * taken as f64) / wall_s.max(1e-12),
        energy_start,
        energy_end,
        energy_max: peak.max.unwrap_or(energy_start).max(energy_start),
        h_omega_max: stability.h_omega,
        stable_dt: stability
            .stable_dt
            .is_finite()
            .then_some(stability.stable_dt),
        omega_max_bound: stability.omega_bound,
        dashpot_rate: (stability.dashpot_rate > 0.0).then_some(stability.dashpot_rate),
        finite: blowup_step.is_none() && solver.state_is_finite(),
        springs_torn: world.resource::<sim::Tearing>().torn,
        contacts: world.resource::<sim::Obstacles>().contacts.total(),
        pair_contacts: world.resource::<sim::Obstacles>().contacts.pairs,
        cg_iterations_per_step: solve.cg_iterations_per_step,
        iterations: params.iterations,
        solve,
        // The passes' times are the CPU's: none when the steps ran on the card.
        pass_seconds: (on.device == Device::Cpu)
            .then(|| world.get_resource::<sim::PassTimes>().cloned())
            .flatten(),
        contact_seconds: (on.device == Device::Cpu)
            .then(|| world.get_resource::<sim::PassTimes>().map(|t| t.contact))
            .flatten(),
        device: on.device,
        adapter: on.adapter,
        precision: on.precision,
        device_note: on.note,
        blowup_step,
        bodies,
    };
    Ok(Run { report, app })
}

/// `steps` steps, on the card where there is one; with `progress`, telling it how far the run
/// is as it goes.
fn advance(
    world: &mut World,
    card: Option<&gpu::Card>,
    steps: u64,
    progress: Option<&mut Progress>,
) -> Result<u64, String> {
    match (card, progress) {
        (None, None) => Ok(sim::advance(world, steps)),
        (None, Some(progress)) => Ok(advance_in_stretches(world, steps, progress)),
        (Some(card), None) => gpu::advance(world, card, steps, |_| {}),
        (Some(card), Some(progress)) => gpu::advance(world, card, steps, |t| progress.note(t)),
    }
}

/// [`sim::advance`] in stretches of whole ticks of about half a second each, so that the
/// result is that of a single stretch, bit for bit, and `progress` hears after each.
fn advance_in_stretches(world: &mut World, steps: u64, progress: &mut Progress) -> u64 {
    let tick = sim::steps_per_tick(world).max(1);
    let mut taken = 0;
    let mut stretch = tick;
    while taken < steps {
        let n = stretch.min(steps - taken);
        let start = Instant::now();
        let done = sim::advance(world, n);
        taken += done;
        if done < n {
            break;
        }
        progress.note(taken);
        // The next: about half a second, at most four times this one, in whole ticks.
        let seconds = start.elapsed().as_secs_f64().max(1e-6);
        let aim = (n as f64 * 0.5 / seconds).min(4.0 * n as f64);
        stretch = ((aim / tick as f64).floor() as u64).max(1) * tick;
    }
    taken
}

/// A run's progress, on one line of stderr rewritten in place: from a second into the run, at
/// most twice a second, how many steps are done and about how long the rest will take. The
/// line is erased when the run ends.
struct Progress {
    steps: u64,
    start: Instant,
    shown: Option<Instant>,
}

impl Progress {
    fn new(steps: u64) -> Self {
        Progress {
            steps,
            start: Instant::now(),
            shown: None,
        }
    }

    fn note(&mut self, taken: u64) {
        let elapsed = self.start.elapsed().as_secs_f64();
        let due = self.shown.is_none_or(|t| t.elapsed().as_secs_f64() >= 0.5);
        if elapsed < 1.0 || !due || taken == 0 || taken >= self.steps {
            return;
        }
        let left = elapsed * (self.steps - taken) as f64 / taken as f64;
        eprint!(
            "\rstep {taken} of {} ({:.1} %), {} so far, about {} left\x1b[K",
            self.steps,
            100.0 * taken as f64 / self.steps as f64,
            seconds_in_words(elapsed),
            seconds_in_words(left)
        );
        self.shown = Some(Instant::now());
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if self.shown.is_some() {
            eprint!("\r\x1b[K");
        }
    }
}

/// "42 s", "3 min 5 s", "2 h 10 min": a duration as a person reads it.
fn seconds_in_words(seconds: f64) -> String {
    let s = seconds.round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}

/// Where a run's steps ran, for its report.
#[derive(Debug, Default)]
struct OnDevice {
    device: Device,
    adapter: Option<String>,
    precision: Option<GpuPrecision>,
    note: Option<String>,
}

/// `--device gpu`: the card, opened before the timed steps.
#[cfg(feature = "gpu")]
mod gpu {
    use super::{GpuPrecision, OnDevice};
    use crate::sim;
    use crate::solver::gpu::{Gpu, Precision};
    use bevy::ecs::world::World;

    /// The card and the width it computes in.
    pub(super) type Card = (Gpu, Precision);

    /// The card to run on and its precision, or `None` (with `on.note` saying why) when the
    /// scene needs what the card does not run; an error when there is no card.
    pub(super) fn card(
        world: &mut World,
        precision: GpuPrecision,
        on: &mut OnDevice,
    ) -> Result<Option<Card>, String> {
        world
            .run_system_cached(sim::obstacles::gather_obstacles)
            .map_err(|e| e.to_string())?;
        if let Some(why) = sim::gpu::unsupported(world) {
            on.note = Some(format!("{why}; the steps ran on the CPU"));
            return Ok(None);
        }
        let gpu = Gpu::open().map_err(|e| format!("--device gpu: {e}"))?;
        let precision = match precision {
            GpuPrecision::F32 => Precision::F32,
            GpuPrecision::F64 if gpu.has_f64() => Precision::F64,
            GpuPrecision::F64 => {
                return Err(format!(
                    "--gpu-precision f64: {} does not compute in f64",
                    gpu.adapter()
                ));
            }
        };
        on.device = super::Device::Gpu;
        on.adapter = Some(gpu.adapter());
        on.precision = Some(match precision {
            Precision::F32 => GpuPrecision::F32,
            Precision::F64 => GpuPrecision::F64,
        });
        Ok(Some((gpu, precision)))
    }

    /// The steps on the card; `after_read` hears the steps taken after each read-back.
    pub(super) fn advance(
        world: &mut World,
        (gpu, precision): &Card,
        steps: u64,
        after_read: impl FnMut(u64),
    ) -> Result<u64, String> {
        sim::gpu::advance_on_gpu_telling(world, gpu, *precision, steps, after_read)
    }
}

/// Without the `gpu` feature: `--device gpu` says how to get it.
#[cfg(not(feature = "gpu"))]
mod gpu {
    use super::{GpuPrecision, OnDevice};
    use bevy::ecs::world::World;

    /// No card: a build without the `gpu` feature has none to run on.
    pub(super) type Card = std::convert::Infallible;

    pub(super) fn card(
        _: &mut World,
        _: GpuPrecision,
        _: &mut OnDevice,
    ) -> Result<Option<Card>, String> {
        Err(
            "--device gpu: this hooke was built without the `gpu` feature (build with \
             `--features gpu`)"
                .into(),
        )
    }

    pub(super) fn advance(
        _: &mut World,
        card: &Card,
        _: u64,
        _: impl FnMut(u64),
    ) -> Result<u64, String> {
        match *card {}
    }
}

/// The rigid bodies' energy in `world`, J (none without the `avian` feature).
fn bodies_energy(world: &mut World) -> f64 {
    #[cfg(feature = "avian")]
    {
        crate::sim::avian::bodies_energy(world)
    }
    #[cfg(not(feature = "avian"))]
    {
        let _ = world;
        0.0
    }
}
