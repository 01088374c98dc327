//! The `hooke` command: the desktop app, and headless runs of scenes.

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use hooke::readable::number;
use hooke::runner::{self, Duration, Overrides};
use hooke::scene::presets;
use hooke::sim::Integrator;
use std::path::PathBuf;
use std::process::ExitCode;

/// An interactive 2D mass-spring simulator.
#[derive(Parser, Debug)]
#[command(name = "hooke", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    app: AppArgs,
}

/// Options of the desktop app (no subcommand).
#[derive(Args, Debug, Clone)]
struct AppArgs {
    /// Scene file to open, or a built-in scene name (the list: `scene_help`).
    #[arg(long, default_value = presets::DEFAULT_SCENE)]
    scene: String,
    /// Start running even if the scene starts paused.
    #[arg(long)]
    run: bool,
    /// Start with the panel's GPU switch on: the steps run on the graphics card where it runs
    /// the scene.
    #[arg(long)]
    gpu: bool,
    /// Save a screenshot to this PNG after --screenshot-after seconds.
    #[arg(long, hide = true)]
    screenshot: Option<PathBuf>,
    #[arg(long, hide = true, default_value_t = 2.0)]
    screenshot_after: f64,
    /// Quit after this many seconds (for scripted runs).
    #[arg(long, hide = true)]
    exit_after: Option<f64>,
    /// Write a JSON status line (particles, springs, steps, fps, ...) to this file twice a second.
    #[arg(long, hide = true)]
    report: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene headless (no window) and report.
    #[command(allow_negative_numbers = true)]
    Run(RunArgs),
    /// Measured reports: work-precision, stability limits, performance.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// Error against wall time for every integrator over a sweep of dt; writes CSV, a markdown
    /// table and SVG/PNG diagrams.
    ///
    /// About 5 minutes on 2 cores (the card's rows on a software renderer included).
    WorkPrecision {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
        /// Shorter sweeps (a smoke run, not the committed report).
        #[arg(long)]
        quick: bool,
    },
    /// Spring updates per second against scene size (1k to 1M springs), integrator and thread
    /// count; writes CSV and a markdown table.
    ///
    /// About 6 minutes on 2 cores.
    Perf {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
        /// Thread counts to measure, each 1 to 256 (default: 1 and all cores).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, value_delimiter = ',')]
        threads: Vec<usize>,
        /// Spring updates per run (sets the number of steps).
        #[arg(long, default_value_t = 3e7)]
        budget: f64,
        /// Runs per figure (the median is reported; thread counts alternate between runs).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, default_value_t = 3)]
        repeat: usize,
    },
    /// Loading and stepping cloths of 1 M to 16 M springs: the load's phases and peak memory
    /// per spring, and the symplectic-Euler rate against the bandwidth bound; writes CSV and
    /// a markdown table.
    ///
    /// About half a minute on 2 cores, with 3 GB of memory for the 16 M springs.
    Scale {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
        /// Cloth widths (particles per side; default about 1, 2, 4, 8 and 16 M springs).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, value_delimiter = ',')]
        widths: Vec<usize>,
        /// Thread counts to measure, each 1 to 256 (default: 1 and all cores).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, value_delimiter = ',')]
        threads: Vec<usize>,
        /// Steps per run.
        #[arg(long, value_parser = hooke::readable::whole::<u64>, default_value_t = 20)]
        steps: u64,
        /// Runs per figure (the median is reported; thread counts alternate between runs).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, default_value_t = 3)]
        repeat: usize,
        /// Measure one cloth of this width in this process and print its row as JSON (what
        /// the report runs each cloth in a process of its own with).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, hide = true)]
        one: Option<usize>,
    },
    /// Every method at real-time steps (dt = 1/30 to 1/960 s) on four scenes: error against a
    /// fine RK4 reference, wall time per simulated second, iterations, and the static sag
    /// against the true equilibrium; writes CSV, markdown and diagrams.
    ///
    /// About 5 minutes on 2 cores.
    LargeSteps {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
    },
    /// The shipped pile under every method at dt = 1/600, 1/240 and 1/60 s: deepest
    /// penetration, closest pair, energy gain, time to rest, cells turned and cost; writes CSV,
    /// markdown and a diagram.
    ///
    /// About 40 seconds on 2 cores.
    Contact {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
    },
    /// The cloth's symplectic-Euler step on the CPU and on the graphics card side by side
    /// (256², 1024² and 2048² particles; f32, and f64 where the adapter has it; one step and
    /// many steps a submit); writes CSV and a markdown table. Needs the `gpu` feature.
    Gpu {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
        /// Cloth widths (particles per side).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, value_delimiter = ',')]
        widths: Vec<usize>,
        /// Spring updates per figure (sets the number of steps).
        #[arg(long, default_value_t = 2e8)]
        budget: f64,
        /// Runs per figure (the best is reported).
        #[arg(long, value_parser = hooke::readable::whole::<usize>, default_value_t = 3)]
        repeat: usize,
    },
    /// Largest stable dt per hard scene and integrator (bisection) against the theoretical
    /// limit, and the energy change at half that dt; writes CSV and a markdown table.
    ///
    /// About a minute on 2 cores.
    Stability {
        /// Directory to write into.
        #[arg(long, default_value = "docs/reports")]
        out: PathBuf,
        /// Directory of the hard scenes.
        #[arg(long, default_value = "assets/scenes/hard")]
        scenes: PathBuf,
        /// Steps per trial.
        #[arg(long, value_parser = hooke::readable::whole::<u64>, default_value_t = 3000)]
        steps: u64,
    },
}

#[derive(Args, Debug)]
struct RunArgs {
    /// Scene file, or a built-in scene name.
    #[arg(long)]
    scene: String,
    #[arg(long, value_enum)]
    integrator: Option<Integrator>,
    /// Time step in seconds (overrides the scene's): a number or a fraction, as 1/60.
    #[arg(long, value_parser = dt_value, allow_hyphen_values = true)]
    dt: Option<f64>,
    /// Number of steps to run.
    #[arg(long, value_parser = hooke::readable::whole::<u64>, conflicts_with = "time")]
    steps: Option<u64>,
    /// Simulated seconds to run (rounded to whole steps): a number or a fraction.
    #[arg(long, value_parser = time_value, allow_hyphen_values = true)]
    time: Option<f64>,
    /// Stiffness for every spring, N/m.
    #[arg(long)]
    stiffness: Option<f64>,
    /// Damping rate μ, 1/s (overrides the scene's): air drag, which slows every motion.
    #[arg(long)]
    damping: Option<f64>,
    /// Dashpot c along every spring without its own, N·s/m (overrides the scene's
    /// `spring_damping`): damps the springs' vibration, not free fall.
    #[arg(long, value_name = "C")]
    spring_damping: Option<f64>,
    /// Projective dynamics and VBD: take the damping μ inside the solve as the force −μ m v
    /// (BDF2 always does), not as exp(−μ dt) after the step.
    #[arg(long)]
    drag_in_solve: bool,
    /// Tearing: break springs stretched past (1 + STRAIN) × rest (overrides the scene's).
    #[arg(long, value_name = "STRAIN")]
    tear: Option<f64>,
    /// Implicit Euler: Newton steps per step (default 1, the classic linearised step).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    newton_iterations: Option<u32>,
    /// Projective dynamics: local/global iterations per step (default 10).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    pd_iterations: Option<u32>,
    /// XPBD: substeps per step (default 10).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    xpbd_substeps: Option<u32>,
    /// XPBD: constraint sweeps per substep (default 1; the least, with --xpbd-tolerance).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    xpbd_iterations: Option<u32>,
    /// XPBD: sweep each substep until the largest constraint error |C + α̃λ|/L is under TOL,
    /// up to --xpbd-max-sweeps (default 0: off).
    #[arg(long, value_name = "TOL")]
    xpbd_tolerance: Option<f64>,
    /// XPBD: the most sweeps a substep runs toward --xpbd-tolerance (default 100).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    xpbd_max_sweeps: Option<u32>,
    /// BDF2: local/global iterations per step (default 10).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    bdf2_iterations: Option<u32>,
    /// VBD: iterations per step (default 10).
    #[arg(long, value_parser = hooke::readable::whole::<u32>, value_name = "N")]
    vbd_iterations: Option<u32>,
    /// VBD: Chebyshev acceleration's spectral radius estimate ρ in [0, 1) (default 0: off).
    #[arg(long, value_name = "RHO")]
    vbd_chebyshev: Option<f64>,
    /// Solver threads, 1 to 256 (default: all cores).
    #[arg(long, value_parser = hooke::readable::whole::<usize>)]
    threads: Option<usize>,
    /// Write the final state as CSV (id,x,y,vx,vy).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object instead of a summary.
    #[arg(long)]
    json: bool,
    /// Also report the wall time of each pass of the step (forces, integrate, damping,
    /// ground, advance; with the fused particle sweep, advance holds all four).
    #[arg(long)]
    profile: bool,
    /// Run the particle passes (the Euler kick, damping, ground, the position update) as
    /// separate systems instead of one fused sweep: the same result bit for bit, slower, and
    /// `--profile` then times each pass.
    #[arg(long)]
    separate_passes: bool,
    /// Where the steps run: the CPU, or the graphics card (symplectic and explicit Euler, and
    /// XPBD with a fixed count of sweeps, with obstacles, the ground's contact, contact between
    /// particles, dashpots and tearing; a scene that needs more runs on the CPU, and the run
    /// says why).
    #[arg(long, value_enum, default_value_t = runner::Device::Cpu)]
    device: runner::Device,
    /// The card's number width with --device gpu: f32 (the default), or f64 where the adapter
    /// has it.
    #[arg(long, value_enum)]
    gpu_precision: Option<runner::GpuPrecision>,
}

/// Exit codes.
const BAD_INPUT: u8 = 2;
const BLEW_UP: u8 = 3;

/// The command line, with the text that names what the code holds written from the code: the
/// integrators in the description, the built-in scenes in the `--scene` help (a list written by
/// hand fell behind twice).
fn command() -> clap::Command {
    let methods: Vec<&str> = Integrator::ALL.iter().map(|m| m.cli_name()).collect();
    let about = format!(
        "An interactive 2D mass-spring simulator: {} integrators ({}), contact, materials, \
         cutting and tearing, a headless CLI",
        hooke::readable::count(methods.len()),
        methods.join(", ")
    );
    let scenes = presets::names().join(", ");
    let scene_help = format!("Scene file to open, or a built-in scene name ({scenes})");
    let run_help = format!("Scene file, or a built-in scene name ({scenes})");
    Cli::command()
        .about(about)
        .mut_arg("scene", |a| a.help(scene_help))
        .mut_subcommand("run", |c| c.mut_arg("scene", |a| a.help(run_help)))
}

fn main() -> ExitCode {
    quiet_device_select();
    let cli = match Cli::from_arg_matches(&command().get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    if cli.command.is_some() {
        end_quietly_on_a_closed_pipe();
    }
    match cli.command {
        None => open_app(cli.app),
        Some(Command::Run(args)) => run(args),
        Some(Command::Bench(BenchCommand::WorkPrecision { out, quick })) => {
            work_precision(&out, quick)
        }
        Some(Command::Bench(BenchCommand::Perf {
            out,
            threads,
            budget,
            repeat,
        })) => perf(&out, threads, budget, repeat),
        Some(Command::Bench(BenchCommand::Stability { out, scenes, steps })) => {
            stability(&out, &scenes, steps)
        }
        Some(Command::Bench(BenchCommand::LargeSteps { out })) => large_steps(&out),
        Some(Command::Bench(BenchCommand::Contact { out })) => contact(&out),
        Some(Command::Bench(BenchCommand::Gpu {
            out,
            widths,
            budget,
            repeat,
        })) => gpu(&out, widths, budget, repeat),
        Some(Command::Bench(BenchCommand::Scale {
            out,
            widths,
            threads,
            steps,
            repeat,
            one,
        })) => scale(&out, widths, threads, steps, repeat, one),
    }
}

/// Outside a desktop session (no `XDG_RUNTIME_DIR`: a server, CI, a container), Mesa's Vulkan
/// device-selection layer tries to reach a Wayland compositor when the first Vulkan instance
/// opens and prints "error: XDG_RUNTIME_DIR is invalid" to the terminal, though nothing failed.
/// hooke picks its adapter itself (wgpu's power preference), so the layer is switched off there
/// by its own variable. Called first in `main`, before any thread starts: setting a variable
/// is sound only while no other thread reads the environment.
fn quiet_device_select() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        // SAFETY: the process has one thread here (the first statement of `main`).
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// The command line's output into a pipe whose reader has gone (`hooke run .. --json | head
/// -c 100`) ends the process as it ends `cat`'s, quietly. Rust starts with SIGPIPE ignored, so
/// the next `println!` met the closed pipe as an error and panicked with a backtrace. Only for
/// `run` and `bench`: the app writes to no pipe of the user's.
fn end_quietly_on_a_closed_pipe() {
    #[cfg(target_os = "linux")]
    // SAFETY: restoring a signal's default action; no handler of ours is involved.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// `--dt`: seconds, or a fraction such as 1/60 ([`hooke::readable::seconds`]).
fn dt_value(text: &str) -> Result<f64, String> {
    hooke::readable::seconds(text).map_err(|e| format!("--dt {e}"))
}

/// `--time`: seconds, or a fraction, 0 allowed ([`hooke::readable::duration`]).
fn time_value(text: &str) -> Result<f64, String> {
    hooke::readable::duration(text).map_err(|e| format!("--time {e}"))
}

fn fail(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("hooke: {message}");
    ExitCode::from(BAD_INPUT)
}

fn run(args: RunArgs) -> ExitCode {
    // The CPU computes in f64 whatever the flag says: a run that names a width for the card
    // and does not go there would report figures of another precision than the one asked.
    if let Some(p) = args
        .gpu_precision
        .filter(|_| args.device != runner::Device::Gpu)
    {
        return fail(format!(
            "--gpu-precision {} applies to the card's steps: add --device gpu (the CPU computes in f64)",
            p.name()
        ));
    }
    // A CSV the run could not write would lose the run at its end: checked before it starts.
    if let Some(Err(e)) = args.out.as_deref().map(|p| writable_file("--out", p)) {
        return fail(e);
    }
    let loaded = match presets::resolve(&args.scene) {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    let duration = match (args.steps, args.time) {
        (Some(n), _) => Duration::Steps(n),
        (None, Some(t)) => Duration::Time(t),
        (None, None) => Duration::Time(1.0),
    };
    let overrides = Overrides {
        integrator: args.integrator,
        dt: args.dt,
        stiffness: args.stiffness,
        damping: args.damping,
        spring_damping: args.spring_damping,
        drag_in_solve: args.drag_in_solve,
        tear: args.tear,
        newton_iterations: args.newton_iterations,
        pd_iterations: args.pd_iterations,
        xpbd_substeps: args.xpbd_substeps,
        xpbd_iterations: args.xpbd_iterations,
        xpbd_tolerance: args.xpbd_tolerance,
        xpbd_max_sweeps: args.xpbd_max_sweeps,
        bdf2_iterations: args.bdf2_iterations,
        vbd_iterations: args.vbd_iterations,
        vbd_chebyshev: args.vbd_chebyshev,
        threads: args.threads,
        profile: args.profile,
        separate_passes: args.separate_passes,
        device: args.device,
        gpu_precision: args.gpu_precision.unwrap_or_default(),
        progress: std::io::IsTerminal::is_terminal(&std::io::stderr()),
    };
    let run = match runner::run(&loaded, &overrides, duration) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    if let Some(path) = &args.out
        && let Err(e) = run.save_csv(path)
    {
        return fail(format!("cannot write {}: {e}", path.display()));
    }
    let r = &run.report;
    if let Some(note) = &r.device_note {
        eprintln!("hooke: {note}");
    }
    // `--time` counts whole steps: one under half a step runs none, which would pass unsaid.
    if let Some(t) = args.time
        && t > 0.0
        && r.steps == 0
    {
        eprintln!(
            "hooke: --time {t} s is under half a step (dt {} s): no step ran; give a longer \
             --time, a smaller --dt or --steps",
            r.dt
        );
    }
    if args.profile && r.device == runner::Device::Gpu {
        eprintln!(
            "hooke: --profile times the CPU's passes; the steps ran on the GPU, untimed by pass"
        );
    }
    if args.json {
        match serde_json::to_string(r) {
            Ok(s) => println!("{s}"),
            Err(e) => return fail(e),
        }
    } else {
        let plural =
            |n: u64, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let bodies = match r.bodies.len() {
            0 => String::new(),
            n => format!(", {}", plural(n as u64, "rigid body", "rigid bodies")),
        };
        println!(
            "{}: {}, {}{bodies}, {} x {} of {} s = {} s simulated",
            r.scene,
            plural(r.particles as u64, "particle", "particles"),
            plural(r.springs as u64, "spring", "springs"),
            r.integrator,
            plural(r.steps_taken, "step", "steps"),
            // As given (0.016666666666666666 stays whole), unless it is far from any step.
            if (1e-9..1e3).contains(&r.dt) {
                r.dt.to_string()
            } else {
                format!("{:e}", r.dt)
            },
            number(r.sim_time, 4)
        );
        if let (Some(adapter), Some(precision)) = (&r.adapter, r.precision) {
            println!("on the GPU: {adapter}, {}", precision.name());
        }
        // A rise on the way (a large-step method's gain, a bounce) that the end hides: the peak.
        let peak = if r.energy_max > r.energy_start + 1e-9 * r.energy_start.abs().max(1.0) {
            format!(" (at most {} J)", number(r.energy_max, 6))
        } else {
            String::new()
        };
        println!(
            "wall {:.3} s: {:.0} steps/s, {:.2} M spring updates/s; energy {} J -> {} J{peak}",
            r.wall_s,
            r.steps_per_s,
            r.spring_updates_per_s / 1e6,
            number(r.energy_start, 6),
            number(r.energy_end, 6)
        );
        // XPBD's soft springs: what the panel's amber line says (the energy is counted at k).
        if let Some(line) = hooke::readable::xpbd_softness(&r.solve) {
            println!("{line}");
        }
        // Dynamic bodies at a step the coupling was measured unstable at: the panel's line.
        let method = <Integrator as clap::ValueEnum>::from_str(&r.integrator, true);
        if let Ok(method) = method
            && r.bodies.iter().any(|b| !b.fixed)
            && let Some(line) = hooke::readable::bodies_caution(method, r.dt)
        {
            println!("{line}");
        }
        if r.springs_torn > 0 {
            let torn = plural(r.springs_torn, "spring", "springs");
            println!("{torn} tore");
        }
        if r.contacts > 0 {
            println!(
                "{} in the last step ({} between particles)",
                plural(r.contacts as u64, "contact", "contacts"),
                r.pair_contacts
            );
        }
        if let Some(t) = &r.pass_seconds {
            let share = |s: f64| 100.0 * s / t.total().max(1e-12);
            println!(
                "passes: forces {:.3} s ({:.0}%), integrate {:.3} s ({:.0}%), damping {:.3} s ({:.0}%), ground {:.3} s ({:.0}%), advance {:.3} s ({:.0}%), contact {:.3} s ({:.0}%)",
                t.forces,
                share(t.forces),
                t.integrate,
                share(t.integrate),
                t.damping,
                share(t.damping),
                t.ground,
                share(t.ground),
                t.advance,
                share(t.advance),
                t.contact,
                share(t.contact)
            );
        }
    }
    if !r.finite {
        // The card's state comes back every 1000 steps: the blow-up is found there.
        let found = if r.device == runner::Device::Gpu {
            ", where the card's state came back (a run on the CPU finds the exact step)"
        } else {
            ""
        };
        eprintln!(
            "hooke: the simulation blew up (a non-finite state or energy) at step {}{found}",
            r.blowup_step.map_or("?".into(), |s| s.to_string())
        );
        // The likeliest cause a newcomer meets: a step past what the method can take.
        if let Some(stable) = r.stable_dt.filter(|&s| r.dt > s) {
            let any_step: Vec<&str> = Integrator::ALL
                .iter()
                .filter(|i| i.unconditionally_stable())
                .map(|i| i.cli_name())
                .collect();
            let past = if stable > 0.0 {
                format!(
                    "dt {} s is past this scene's stable step under {}, {stable:.3e} s: give a \
                     smaller --dt, or",
                    r.dt, r.integrator
                )
            } else {
                // Explicit Euler without damping: no step is small enough.
                format!(
                    "{} is unstable at any step without damping: give --damping > 0, or",
                    r.integrator
                )
            };
            eprintln!(
                "hooke: {past} an --integrator stable at any step ({})",
                hooke::readable::list(&any_step)
            );
        }
        return ExitCode::from(BLEW_UP);
    }
    ExitCode::SUCCESS
}

fn work_precision(out: &std::path::Path, quick: bool) -> ExitCode {
    use hooke::bench::{plot, work_precision as wp};
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let problems = wp::problems(quick);
    // The card's f32 points where this build and this machine have a card.
    #[cfg(feature = "gpu")]
    let gpu = match hooke::solver::gpu::Gpu::open() {
        Ok(g) => Some(g),
        Err(e) => {
            eprintln!("  {e}: the report leaves the card's points out");
            None
        }
    };
    #[cfg(not(feature = "gpu"))]
    let gpu: Option<std::convert::Infallible> = None;
    let report = match wp::run(&problems, gpu.as_ref(), |what| eprintln!("  {what}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let command = format!(
        "hooke bench work-precision{}",
        if quick { " --quick" } else { "" }
    );
    for p in &problems {
        let rows: Vec<&wp::Row> = report.rows.iter().filter(|r| r.scene == p.name).collect();
        let stem = out.join(format!("work-precision-{}", p.name));
        let title = format!("work-precision: {}", p.name);
        if let Err(e) = plot::write_diagram(&rows, &title, &stem) {
            return fail(e);
        }
    }
    let md = wp::markdown(&report, &command);
    write_report(
        out,
        &[
            ("work-precision.csv", &wp::csv(&report.rows)),
            ("work-precision.md", &md),
        ],
    )
}

fn contact(out: &std::path::Path) -> ExitCode {
    use hooke::bench::{contact as ct, plot};
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let machine = hooke::bench::machine();
    eprintln!("hooke bench contact on {machine}");
    let report = match ct::run(|what| eprintln!("  {what}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let rows = ct::diagram_rows(&report);
    let rows: Vec<&hooke::bench::work_precision::Row> = rows.iter().collect();
    let labels = (
        "wall time per simulated second (s)",
        "closest unjoined pair's overlap (share of 2r)",
    );
    let title = "contact: the pile at 1/600, 1/240 and 1/60 s";
    if let Err(e) = plot::write_diagram_with(&rows, title, labels, &out.join("contact")) {
        return fail(e);
    }
    let md = ct::markdown(&report, &machine, "hooke bench contact");
    write_report(
        out,
        &[("contact.csv", &ct::csv(&report)), ("contact.md", &md)],
    )
}

fn large_steps(out: &std::path::Path) -> ExitCode {
    use hooke::bench::{large_steps as ls, plot};
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let machine = hooke::bench::machine();
    eprintln!("hooke bench large-steps on {machine}");
    let problems = match ls::problems() {
        Ok(p) => p,
        Err(e) => return fail(e),
    };
    let report = match ls::run(&problems, |what| eprintln!("  {what}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    for p in &problems {
        let rows: Vec<&hooke::bench::work_precision::Row> = report
            .rows
            .iter()
            .filter(|r| r.row.scene == p.name)
            .map(|r| &r.row)
            .collect();
        let stem = out.join(format!("large-steps-{}", p.name));
        let title = format!("large steps: {} (dt = 1/30 to 1/960 s)", p.name);
        let x_label = "wall time per simulated second (s)";
        let labels = (x_label, "max position error (m)");
        if let Err(e) = plot::write_diagram_with(&rows, &title, labels, &stem) {
            return fail(e);
        }
    }
    let md = ls::markdown(&report, &machine, "hooke bench large-steps");
    write_report(
        out,
        &[
            ("large-steps.csv", &ls::csv(&report.rows)),
            ("large-steps.md", &md),
        ],
    )
}

fn perf(out: &std::path::Path, threads: Vec<usize>, budget: f64, repeat: usize) -> ExitCode {
    use hooke::bench::perf;
    let threads = match thread_counts(threads) {
        Ok(t) => t,
        Err(e) => return fail(e),
    };
    if !(budget.is_finite() && budget > 0.0) {
        return fail(format!("--budget must be finite and > 0, got {budget}"));
    }
    if repeat == 0 {
        return fail("--repeat must be at least 1");
    }
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let progress = |w: &str| eprintln!("  {w}");
    let (rows, loads) = match perf::run(&perf::WIDTHS, &threads, budget, repeat, progress) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    eprintln!("  bandwidth at each working set");
    let bounds = match perf::bounds(&rows) {
        Ok(b) => b,
        Err(e) => return fail(e),
    };
    let command = format!(
        "hooke bench perf{} --budget {budget:e} --repeat {repeat}",
        list_flag("--threads", &threads)
    );
    let md = perf::markdown(&rows, &loads, &bounds, &hooke::bench::machine(), &command);
    write_report(out, &[("perf.csv", &perf::csv(&rows)), ("perf.md", &md)])
}

fn scale(
    out: &std::path::Path,
    mut widths: Vec<usize>,
    threads: Vec<usize>,
    steps: u64,
    repeat: usize,
    one: Option<usize>,
) -> ExitCode {
    use hooke::bench::scale;
    let command = format!(
        "hooke bench scale{}{} --steps {steps} --repeat {repeat}",
        list_flag("--widths", &widths),
        list_flag("--threads", &threads)
    );
    if widths.is_empty() {
        widths = scale::WIDTHS.to_vec();
    }
    let threads = match thread_counts(threads) {
        Ok(t) => t,
        Err(e) => return fail(e),
    };
    if widths.iter().any(|&w| w < 2) {
        return fail("--widths: every width must be at least 2");
    }
    if steps == 0 || repeat == 0 {
        return fail("--steps and --repeat must be at least 1");
    }
    if let Some(w) = one {
        return match scale::run(&[w], &threads, steps, repeat, |p| eprintln!("    {p}")) {
            Ok(rows) => match serde_json::to_string(&rows[0]) {
                Ok(json) => {
                    println!("{json}");
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e.to_string()),
            },
            Err(e) => fail(e),
        };
    }
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let machine = hooke::bench::machine();
    eprintln!("hooke bench scale on {machine}");
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => return fail(format!("cannot find this program to run each cloth: {e}")),
    };
    let progress = |w: &str| eprintln!("  {w}");
    let rows = match scale::run_isolated(&exe, &widths, &threads, steps, repeat, progress) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let md = scale::markdown(&rows, &machine, &command);
    write_report(out, &[("scale.csv", &scale::csv(&rows)), ("scale.md", &md)])
}

/// ` --flag a,b` for a non-empty list, else nothing.
fn list_flag(flag: &str, values: &[usize]) -> String {
    if values.is_empty() {
        return String::new();
    }
    let list: Vec<String> = values.iter().map(|v| v.to_string()).collect();
    format!(" {flag} {}", list.join(","))
}

/// The thread counts asked for, or 1 and all cores; each checked ([`runner::check_threads`]).
fn thread_counts(threads: Vec<usize>) -> Result<Vec<usize>, String> {
    for &t in &threads {
        runner::check_threads(t)?;
    }
    if !threads.is_empty() {
        return Ok(threads);
    }
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    Ok(if all > 1 { vec![1, all] } else { vec![1] })
}

fn stability(out: &std::path::Path, scenes: &std::path::Path, steps: u64) -> ExitCode {
    use hooke::bench::stability as st;
    let scenes = match st::hard_scenes(scenes) {
        Ok(s) if !s.is_empty() => s,
        Ok(_) => return fail(format!("no scene files in {}", scenes.display())),
        Err(e) => return fail(e),
    };
    if steps == 0 {
        return fail("--steps must be at least 1");
    }
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let rows = match st::run(&scenes, steps, |what| eprintln!("  {what}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let command = format!("hooke bench stability --steps {steps}");
    let md = st::markdown(&rows, &command);
    write_report(
        out,
        &[("stability.csv", &st::csv(&rows)), ("stability.md", &md)],
    )
}

/// Writes a report's files into `out` and prints the last one (its markdown).
#[cfg(feature = "gpu")]
fn gpu(out: &std::path::Path, widths: Vec<usize>, budget: f64, repeat: usize) -> ExitCode {
    use hooke::bench::gpu;
    if !(budget.is_finite() && budget > 0.0) {
        return fail(format!("--budget must be finite and > 0, got {budget}"));
    }
    let widths = if widths.is_empty() {
        gpu::WIDTHS.to_vec()
    } else {
        widths
    };
    if let Some(w) = widths.iter().find(|&&w| !(2..=4096).contains(&w)) {
        return fail(format!("--widths: each from 2 to 4096, got {w}"));
    }
    if let Err(e) = report_folder(out) {
        return fail(e);
    }
    let card = match hooke::solver::gpu::Gpu::open() {
        Ok(c) => c,
        Err(e) => return fail(format!("bench gpu: {e}")),
    };
    let machine = hooke::bench::machine();
    eprintln!("hooke bench gpu on {machine} and {}", card.adapter());
    let rows = match gpu::run(&card, &widths, budget, repeat, |w| eprintln!("  {w}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let list: Vec<String> = widths.iter().map(|w| w.to_string()).collect();
    let command = format!(
        "hooke bench gpu --widths {} --budget {budget:e} --repeat {repeat}",
        list.join(",")
    );
    // The spring-update table is written before XPBD's is measured, so that a run cut short
    // (a card lent for minutes) keeps it.
    let md = gpu::markdown(&rows, &machine, &command);
    let csv = gpu::csv(&rows);
    if let Err(e) = write_files(out, &[("gpu.csv", &csv), ("gpu.md", &md)]) {
        return fail(e);
    }
    let frames = match gpu::run_frames(&card, &widths, budget, repeat, |w| eprintln!("  {w}")) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let md = md + &gpu::frames_markdown(&frames);
    write_report(out, &[("gpu.md", &md)])
}

#[cfg(not(feature = "gpu"))]
fn gpu(_: &std::path::Path, _: Vec<usize>, _: f64, _: usize) -> ExitCode {
    fail("bench gpu: this hooke was built without the `gpu` feature (build with `--features gpu`)")
}

/// Writes a report's files into `out`, then prints the last of them (its markdown).
fn write_report(out: &std::path::Path, files: &[(&str, &str)]) -> ExitCode {
    if let Err(e) = write_files(out, files) {
        return fail(e);
    }
    if let Some((_, text)) = files.last() {
        println!("{text}");
    }
    ExitCode::SUCCESS
}

/// Writes each (name, text) into `out`, made if missing; the error names the folder.
fn write_files(out: &std::path::Path, files: &[(&str, &str)]) -> Result<(), String> {
    std::fs::create_dir_all(out)
        .and_then(|()| {
            files
                .iter()
                .try_for_each(|(name, text)| std::fs::write(out.join(name), text))
        })
        .map_err(|e| format!("cannot write the report into {}: {e}", out.display()))
}

/// The folder a report goes into, made if missing and tried with a file, before anything is
/// measured: a report that could not be written would lose minutes of measurement at its end
/// (`bench scale`, `bench gpu` on a card lent for minutes).
fn report_folder(out: &std::path::Path) -> Result<(), String> {
    if out.exists() && !out.is_dir() {
        return Err(format!(
            "--out: {} is a file; a report goes into a folder (of several files)",
            out.display()
        ));
    }
    let probe = out.join(".hooke-write-check");
    std::fs::create_dir_all(out)
        .and_then(|()| std::fs::write(&probe, b""))
        .and_then(|()| std::fs::remove_file(&probe))
        .map_err(|e| format!("--out: cannot write into {}: {e}", out.display()))
}

/// Whether a file could be written at `path`, named by its `flag`: its folder exists, and the
/// path is not a folder itself. Checked before the work whose result it would hold.
fn writable_file(flag: &str, path: &std::path::Path) -> Result<(), String> {
    let folder = path
        .parent()
        .filter(|f| !f.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    if !folder.is_dir() {
        return Err(format!(
            "{flag}: cannot write {}: there is no folder {}",
            path.display(),
            folder.display()
        ));
    }
    if path.is_dir() {
        return Err(format!(
            "{flag}: cannot write {}: it is a folder; name a file in it",
            path.display()
        ));
    }
    Ok(())
}

/// The scripted run's flags, checked before a window opens: a screenshot or report the app
/// could not write, or a time it would never reach, is bad input named by its flag, not an
/// error line from the renderer (or a run that never quits) after the window is up.
#[cfg(feature = "gui")]
fn check_scripted_run(args: &AppArgs) -> Result<(), String> {
    for (flag, path) in [
        ("--screenshot", &args.screenshot),
        ("--report", &args.report),
    ] {
        if let Some(path) = path {
            writable_file(flag, path)?;
        }
    }
    if let Some(path) = &args.screenshot
        && !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        return Err(format!(
            "--screenshot: screenshots are PNG files, and {} does not end in .png",
            path.display()
        ));
    }
    for (flag, seconds) in [
        ("--screenshot-after", Some(args.screenshot_after)),
        ("--exit-after", args.exit_after),
    ] {
        if let Some(s) = seconds.filter(|s| !(s.is_finite() && *s >= 0.0)) {
            return Err(format!("{flag} must be finite and >= 0, got {s}"));
        }
    }
    Ok(())
}

#[cfg(feature = "gui")]
fn open_app(args: AppArgs) -> ExitCode {
    if let Err(e) = check_scripted_run(&args) {
        return fail(e);
    }
    let loaded = match presets::resolve(&args.scene) {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    let options = hooke::ui::AppOptions {
        start_running: args.run,
        screenshot: args.screenshot.map(|p| (p, args.screenshot_after)),
        exit_after: args.exit_after,
        report: args.report,
        gpu: args.gpu,
    };
    hooke::ui::run_app(loaded, options);
    ExitCode::SUCCESS
}

#[cfg(not(feature = "gui"))]
fn open_app(_args: AppArgs) -> ExitCode {
    fail("this build has no window (built without the `gui` feature); use `hooke run`")
}
