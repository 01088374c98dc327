//! The `hooke run` command end to end: reports, CSV output, exit codes, bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hooke(args: &[&str]) -> Output {
    hooke_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

/// `hooke` run in `dir`.
fn hooke_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hooke"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the hooke binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON object ({e}): {}",
            String::from_utf8_lossy(&o.stdout)
        )
    })
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hooke-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Exit code 2, no panic, and a message on stderr that contains `needle`.
fn assert_bad_input(o: &Output, needle: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(needle), "expected {needle:?} in: {err}");
}

#[test]
fn run_reports_json_and_writes_a_round_tripping_csv() {
    let csv = temp("cloth.csv");
    let o = hooke(&[
        "run",
        "--scene",
        "assets/scenes/cloth32.ron",
        "--steps",
        "1000",
        "--json",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&o);
    for key in [
        "integrator",
        "dt",
        "steps",
        "particles",
        "springs",
        "wall_s",
        "steps_per_s",
        "spring_updates_per_s",
        "energy_start",
        "energy_end",
        "finite",
    ] {
        assert!(r.get(key).is_some(), "missing {key} in {r}");
    }
    assert_eq!(r["integrator"], "symplectic-euler");
    assert_eq!(
        (r["steps"].as_u64(), r["particles"].as_u64()),
        (Some(1000), Some(1024))
    );
    assert_eq!(r["springs"], 3906);
    assert_eq!(r["finite"], true);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("id,x,y,vx,vy"));
    let sum: f64 = lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            f[1] + f[2]
        })
        .sum();
    // The reference Σ(x+y) (shared/reference.md), read back from the printed CSV.
    assert!((sum - 998.4039018283542).abs() < 1e-9, "{sum}");
}

#[test]
fn time_and_overrides() {
    let o = hooke(&[
        "run",
        "--scene",
        "rope",
        "--time",
        "0.05",
        "--dt",
        "2e-4",
        "--integrator",
        "explicit-euler",
        "--damping",
        "0",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&o);
    assert_eq!(r["steps"], 250);
    assert_eq!(r["dt"], 2e-4);
    assert_eq!(r["integrator"], "explicit-euler");

    // --stiffness replaces every spring's stiffness: the sagging rope ends elsewhere.
    let soft = json(&hooke(&[
        "run", "--scene", "rope", "--steps", "100", "--json",
    ]));
    let stiff = json(&hooke(&[
        "run",
        "--scene",
        "rope",
        "--steps",
        "100",
        "--json",
        "--stiffness",
        "1e6",
    ]));
    assert_ne!(soft["energy_end"], stiff["energy_end"]);
}

/// --profile adds the wall time of each pass, which together fit in the run's wall time and
/// leave the result unchanged; without it the report has no pass times.
#[test]
fn profile_reports_time_per_pass() {
    let args = ["run", "--scene", "cloth32", "--steps", "200", "--json"];
    let plain = json(&hooke(&args));
    assert!(plain.get("pass_seconds").is_none());
    let o = hooke(&[&args[..], &["--profile"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&o);
    assert_eq!(r["energy_end"], plain["energy_end"]);
    let passes = &r["pass_seconds"];
    let mut total = 0.0;
    for pass in ["forces", "integrate", "damping", "ground", "advance"] {
        let s = passes[pass].as_f64().unwrap_or(-1.0);
        assert!(s > 0.0, "{pass}: {s}");
        total += s;
    }
    assert!(
        total <= r["wall_s"].as_f64().unwrap(),
        "{passes} in {}",
        r["wall_s"]
    );
}

#[test]
fn a_blow_up_stops_the_run_with_exit_code_3() {
    let o = hooke(&[
        "run",
        "--scene",
        "cloth32",
        "--integrator",
        "explicit-euler",
        "--damping",
        "0",
        "--stiffness",
        "1e9",
        "--dt",
        "1e-3",
        "--steps",
        "5000",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"));
    let r = json(&o);
    assert_eq!(r["finite"], false);
    let step = r["blowup_step"].as_u64().expect("names the step");
    assert!(step > 1 && step < 5000, "{step}");
    assert_eq!(r["steps_taken"].as_u64(), Some(step));
    assert!(
        stderr(&o).contains("explicit-euler is unstable at any step without damping"),
        "{}",
        stderr(&o)
    );
}

/// The rope under explicit Euler at a frame's step, 330 times its stable step: it blows up at
/// its 299th step while its state stays finite.
const ROPE_PAST_ITS_STABLE_STEP: &[&str] = &[
    "run",
    "--scene",
    "rope",
    "--integrator",
    "explicit-euler",
    "--dt",
    "1/60",
    "--time",
    "5",
];

/// A state can stay finite while its energy overflows (speeds past 1e154 m/s): the rope under
/// explicit Euler at a frame's step reached positions of 1e151 m and ended "finite" with exit
/// 0. It is a blow-up, and the message names the stable step it passed.
#[test]
fn an_overflowing_energy_is_a_blow_up() {
    let o = hooke(&[ROPE_PAST_ITS_STABLE_STEP, &["--json"]].concat());
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let r = json(&o);
    assert_eq!(r["finite"], false);
    let step = r["blowup_step"].as_u64().expect("names the step");
    assert!(step > 1 && step < 300, "{step}");
    // What is reported is the last state before it: energies a number, not null.
    assert!(r["energy_end"].as_f64().is_some_and(f64::is_finite), "{r}");
    assert!(r["energy_max"].as_f64().is_some_and(f64::is_finite), "{r}");
    let err = stderr(&o);
    assert!(
        err.contains(
            "dt 0.016666666666666666 s is past this scene's stable step under \
             explicit-euler, 5.052e-5 s: give a smaller --dt, or an --integrator stable at any \
             step (implicit-euler, projective-dynamics, xpbd, bdf2 and vbd)"
        ),
        "{err}"
    );
}

#[test]
fn bad_scene_files() {
    assert_bad_input(&hooke(&["run", "--scene", "no/such.ron"]), "no/such.ron");

    let broken = temp("broken.ron");
    std::fs::write(
        &broken,
        "(\n    gravity: (0.0, -9.8),\n    damping: oops,\n)",
    )
    .unwrap();
    assert_bad_input(
        &hooke(&["run", "--scene", broken.to_str().unwrap()]),
        &format!("{}:3:", broken.display()),
    );

    // A newcomer's first scene with a typo: it used to run with mass 1, unpinned, and exit 0.
    let typo = temp("typo.ron");
    std::fs::write(
        &typo,
        "(gravity: (0.0, -9.8), damping: 1.0, ground: None, integrator: SymplecticEuler, \
         dt: 0.001,\n particles: [(pos: (0.5, 0.5), masss: 5.0, pined: true)])",
    )
    .unwrap();
    let o = hooke(&["run", "--scene", typo.to_str().unwrap()]);
    assert_bad_input(&o, &format!("{}:2:", typo.display()));
    assert!(
        stderr(&o).contains("unknown field `masss` in a particle; did you mean `mass`?"),
        "{}",
        stderr(&o)
    );

    let invalid = temp("invalid.ron");
    std::fs::write(
        &invalid,
        "(gravity: (0.0, -9.8), damping: 1.0, ground: None, integrator: SymplecticEuler, \
         dt: 0.001, particles: [(pos: (0.0, 0.0), mass: -1.0)], \
         springs: [(a: 0, b: 3, stiffness: 1.0, rest: 0.1)])",
    )
    .unwrap();
    let o = hooke(&["run", "--scene", invalid.to_str().unwrap()]);
    assert_bad_input(&o, "particles[0]: mass must be finite and > 0");
    assert!(stderr(&o).contains("springs[0]: b = 3 is out of range"));

    let zero = temp("zero-iterations.ron");
    std::fs::write(
        &zero,
        "(gravity: (0.0, -9.8), damping: 1.0, ground: None, integrator: Xpbd, dt: 0.01, \
         particles: [(pos: (0.0, 0.0))], iterations: (xpbd_sweeps: 0))",
    )
    .unwrap();
    let o = hooke(&["run", "--scene", zero.to_str().unwrap()]);
    assert_bad_input(
        &o,
        "iterations.xpbd_sweeps: must be between 1 and 100000, got 0",
    );
}

/// The large-step methods through the CLI: the iteration flags take effect and the report
/// says what the solvers did (projective dynamics' factorisation and contact line searches, XPBD's
/// sweeps).
#[test]
fn large_step_methods_report_their_iterations() {
    let common = [
        "run", "--scene", "cloth32", "--dt", "0.02", "--steps", "5", "--json",
    ];
    let mut args = common.to_vec();
    args.extend_from_slice(&[
        "--integrator",
        "projective-dynamics",
        "--pd-iterations",
        "7",
    ]);
    let r = json(&hooke(&args));
    assert_eq!(r["finite"], true);
    assert_eq!(r["iterations"]["projective"], 7);
    assert_eq!(r["solve"]["projective_iterations_per_step"], 7.0);
    // Its lower edge reaches the ground in the second step: the contact forces' line search
    // runs after some of the iterations from then on.
    let searches = r["solve"]["projective_line_searches_per_step"]
        .as_f64()
        .unwrap();
    assert!(
        searches > 0.0 && searches < 6.0,
        "{searches} line searches a step"
    );
    assert_eq!(r["solve"]["factorizations"], 1);
    assert!(r["solve"]["factorization_seconds"].as_f64().unwrap() > 0.0);
    // The 32² cloth's factor is too small to share between threads.
    assert_eq!(r["solve"]["factor_halves"], 1);
    assert!(r["stable_dt"].is_null());
    // The rope hangs clear of its ground: no contact in the solve, no line search. The soft
    // box landing at 1/30 s: a line search after each of its iterations but the last, while
    // contact acts.
    let mut args = common.to_vec();
    args[2] = "rope";
    args.extend_from_slice(&["--integrator", "projective-dynamics"]);
    let r = json(&hooke(&args));
    assert_eq!(r["solve"]["projective_line_searches_per_step"], 0.0);
    let r = json(&hooke(&[
        "run",
        "--scene",
        "soft_box",
        "--integrator",
        "projective-dynamics",
        "--dt",
        "1/30",
        "--time",
        "2",
        "--json",
    ]));
    let searches = r["solve"]["projective_line_searches_per_step"]
        .as_f64()
        .unwrap();
    assert!(
        searches > 1.0 && searches <= 9.0,
        "{searches} line searches a step"
    );
    let mut args = common.to_vec();
    args.extend_from_slice(&["--integrator", "xpbd", "--xpbd-substeps", "4"]);
    args.extend_from_slice(&["--xpbd-iterations", "3"]);
    let r = json(&hooke(&args));
    assert_eq!(r["solve"]["xpbd_sweeps_per_step"], 12.0);
    assert_eq!(r["solve"]["xpbd_colours"], 8);
    let mut args = common.to_vec();
    args.extend_from_slice(&["--integrator", "implicit-euler", "--newton-iterations", "3"]);
    let r = json(&hooke(&args));
    assert_eq!(r["solve"]["newton_iterations_per_step"], 3.0);
}

#[test]
fn bad_flags() {
    let cases: [(&[&str], &str); 19] = [
        (&["--dt", "-1"], "--dt must be finite and > 0, got -1"),
        (&["--dt", "1e19"], "--dt must be at most 1e9 s, got 1e19"),
        (
            &["--threads", "0"],
            "--threads must be between 1 and 256, got 0",
        ),
        (
            &["--threads", "100000"],
            "--threads must be between 1 and 256, got 100000",
        ),
        (
            &["--pd-iterations", "0"],
            "--pd-iterations must be between 1 and 100000, got 0",
        ),
        (
            &["--xpbd-substeps", "1000000"],
            "--xpbd-substeps must be between 1 and 100000",
        ),
        (
            &["--newton-iterations", "-2"],
            "must be a whole number of 0 or more, got -2",
        ),
        (
            &["--xpbd-iterations", "many"],
            "must be a whole number, got many",
        ),
        (
            &["--steps", "1.5"],
            "must be a whole number, written without a decimal point or an exponent, got 1.5",
        ),
        (&["--dt", "NaN"], "--dt must be finite and > 0, got NaN"),
        (
            &["--stiffness", "-3"],
            "--stiffness must be finite and >= 0",
        ),
        (&["--damping", "inf"], "--damping must be finite and >= 0"),
        (&["--time", "-1"], "--time must be finite and >= 0, got -1"),
        // 1e34 steps at the scene's dt: refused, not run as u64::MAX steps.
        (&["--time", "1e30"], "more than a run counts"),
        (&["--integrator", "leapfrog"], "leapfrog"),
        (&["--steps", "ten"], "ten"),
        (&["--steps", "5", "--time", "1"], "cannot be used with"),
        // A width for the card on a run that stays on the CPU (which computes in f64).
        (
            &["--gpu-precision", "f64"],
            "--gpu-precision f64 applies to the card's steps: add --device gpu",
        ),
        (
            &["--device", "cpu", "--gpu-precision", "f32"],
            "--gpu-precision f32 applies to the card's steps",
        ),
    ];
    for (flags, needle) in cases {
        let mut args = vec!["run", "--scene", "rope"];
        args.extend_from_slice(flags);
        assert_bad_input(&hooke(&args), needle);
    }
}

/// A scene file's name for an integrator (`ProjectiveDynamics`, as one copied from a scene)
/// runs that integrator, as its command-line name does.
#[test]
fn the_integrator_by_its_scene_file_name() {
    for (scene_name, cli_name) in [
        ("ProjectiveDynamics", "projective-dynamics"),
        ("Xpbd", "xpbd"),
        ("SymplecticEuler", "symplectic-euler"),
    ] {
        let o = hooke(&[
            "run",
            "--scene",
            "rope",
            "--integrator",
            scene_name,
            "--steps",
            "10",
            "--json",
        ]);
        assert!(o.status.success(), "{scene_name}: {}", stderr(&o));
        assert_eq!(json(&o)["integrator"], cli_name);
    }
}

/// `--out` names a file the run could not write (no such folder, or a folder): refused before
/// the run, not after it, when the run's result would be lost. The run asked for here is
/// 1e9 steps of cloth32 (hours), so a check after it would not end within the test.
#[test]
fn an_unwritable_out_is_refused_before_the_run() {
    let folder = temp("out-folder");
    std::fs::create_dir_all(&folder).unwrap();
    let missing = temp("no-such-folder").join("state.csv");
    for (out, needle) in [
        (&missing, "there is no folder"),
        (&folder, "it is a folder"),
    ] {
        let start = std::time::Instant::now();
        let o = hooke(&[
            "run",
            "--scene",
            "cloth32",
            "--steps",
            "1000000000",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_bad_input(&o, needle);
        assert!(stderr(&o).contains("--out: cannot write"), "{}", stderr(&o));
        assert!(start.elapsed().as_secs() < 60, "it ran first");
    }
}

/// Outside the repository (an installed `hooke`) the report scenes are built in: a run of one
/// by its path, and the stability report over the hard cases, from an empty folder.
#[test]
fn shipped_scenes_run_from_any_folder() {
    let empty = temp("elsewhere");
    std::fs::create_dir_all(&empty).unwrap();
    let elsewhere = |args: &[&str]| hooke_in(&empty, args);
    let o = elsewhere(&[
        "run",
        "--scene",
        "assets/scenes/hard/impact.ron",
        "--steps",
        "10",
        "--json",
    ]);
    assert_eq!(json(&o)["steps_taken"], 10, "{}", stderr(&o));
    let o = elsewhere(&["bench", "stability", "--steps", "1", "--out", "report"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = std::fs::read_to_string(empty.join("report/stability.md")).unwrap();
    for name in ["cloth_light", "impact", "mass_ratio"] {
        assert!(report.contains(&format!("| {name} |")), "{name}: {report}");
    }
    // A folder named that does not exist, and is none of the built-in ones, is still refused.
    let o = elsewhere(&["bench", "stability", "--scenes", "nowhere", "--steps", "1"]);
    assert_bad_input(&o, "no scene files in nowhere");

    // The app's scenes by their shipped paths too, as the guide writes them.
    let o = elsewhere(&["run", "--scene", "assets/scenes/pile.ron", "--steps", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A built-in's name with `.ron`, where no such file is: the name is pointed to.
    let o = elsewhere(&["run", "--scene", "rope.ron", "--steps", "1"]);
    assert_bad_input(&o, "cannot read scene rope.ron: ");
    assert_bad_input(
        &o,
        "; the built-in scene of that name is `rope`, without `.ron`",
    );
}

/// The summary counts in words that agree with their numbers: one particle and one step are
/// not "1 particles" and "1 steps".
#[test]
fn the_summary_says_one_particle() {
    let one = temp("one.ron");
    std::fs::write(&one, "(particles: [(pos: (0.5, 0.5))])").unwrap();
    let o = hooke(&["run", "--scene", one.to_str().unwrap(), "--steps", "1"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains(": 1 particle, 0 springs, symplectic-euler x 1 step of 0.0001 s"),
        "{out}"
    );
}

/// The summary names the energy's peak where it rose above the start, which the end can hide
/// (the walker's muscles put in 5 J and friction takes it out again), and only there.
#[test]
fn the_summary_names_a_peak_the_end_hides() {
    let o = hooke(&["run", "--scene", "walker", "--time", "1", "--json"]);
    let r = json(&o);
    let (start, peak) = (
        r["energy_start"].as_f64().unwrap(),
        r["energy_max"].as_f64().unwrap(),
    );
    assert!(peak > 2.0 * start, "{r}");
    let o = hooke(&["run", "--scene", "walker", "--time", "1"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("(at most {peak:.6} J)")), "{text}");
    // Damped and unforced, the rope only loses energy: nothing to name.
    let o = hooke(&["run", "--scene", "rope", "--time", "1"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(!text.contains("at most"), "{text}");
}

/// XPBD's soft springs are named in the summary as the panel names them: the README's first
/// scene, a light cloth at a frame's step, carries about a third of k's force, which is why its
/// energy, counted at k, rises.
#[test]
fn the_summary_says_when_xpbd_is_softer_than_k() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let start = readme.find("```ron\n").expect("the README shows a scene") + 7;
    let scene = &readme[start..start + readme[start..].find("```").unwrap()];
    assert!(scene.contains("integrator: Xpbd"), "{scene}");
    let file = temp("readme_cloth.ron");
    std::fs::write(&file, scene).unwrap();
    let o = hooke(&["run", "--scene", file.to_str().unwrap(), "--time", "2"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("XPBD: constraint error") && text.contains("of the force k asks"),
        "{text}"
    );
    // Converged, it says nothing.
    let o = hooke(&[
        "run",
        "--scene",
        file.to_str().unwrap(),
        "--time",
        "2",
        "--xpbd-tolerance",
        "1e-3",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(!text.contains("XPBD:"), "{text}");
}

/// A `--time` shorter than half a step runs no step, and says so rather than passing unsaid.
#[test]
fn a_time_under_half_a_step_says_no_step_ran() {
    let o = hooke(&["run", "--scene", "rope", "--time", "0.00004"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--time 0.00004 s is under half a step (dt 0.0001 s): no step ran"),
        "{}",
        stderr(&o)
    );
    // A time of 0 asks for no step: nothing to say.
    let o = hooke(&["run", "--scene", "rope", "--time", "0"]);
    assert_eq!(stderr(&o), "");
}

/// `--separate-passes` runs the particle passes as systems of their own: the same state bit for
/// bit (the JSON's floats round-trip).
#[test]
fn separate_passes_give_the_fused_result() {
    let args = [
        "run",
        "--scene",
        "cloth32",
        "--steps",
        "300",
        "--json",
        "--profile",
    ];
    let fused = json(&hooke(&args));
    let o = hooke(&[&args[..], &["--separate-passes"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let separate = json(&o);
    assert_eq!(separate["energy_end"], fused["energy_end"]);
    assert_eq!(separate["finite"], serde_json::Value::Bool(true));
}

/// `hooke bench scale` on two small cloths, each measured in a process of its own: a report
/// with a row per cloth and thread count, the machine named, and the memory figures present.
#[test]
fn bench_scale_writes_its_report() {
    let out = temp("scale");
    let args = [
        "bench",
        "scale",
        "--widths",
        "20,30",
        "--threads",
        "1",
        "--steps",
        "2",
    ];
    let o = hooke(
        &[
            &args[..],
            &["--repeat", "1", "--out", out.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(out.join("scale.md")).unwrap();
    assert!(
        md.contains("cores") && md.contains("| cloth20 |") && md.contains("| cloth30 |"),
        "{md}"
    );
    let csv = std::fs::read_to_string(out.join("scale.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    // width 20: 400 particles, 19·20·2 + 2·19·19 = 1482 springs; peak bytes measured on Linux.
    let first: Vec<&str> = rows[0].split(',').collect();
    assert_eq!(&first[..3], &["20", "400", "1482"]);
    if cfg!(target_os = "linux") {
        assert!(first[6].parse::<u64>().is_ok(), "peak bytes: {}", rows[0]);
    }
    for (flags, needle) in [
        (&["--widths", "1"][..], "every width must be at least 2"),
        (
            &["--steps", "0"][..],
            "--steps and --repeat must be at least 1",
        ),
    ] {
        let bad = temp("scale-bad");
        let mut a = vec!["bench", "scale", "--out", bad.to_str().unwrap()];
        a.extend_from_slice(flags);
        assert_bad_input(&hooke(&a), needle);
        assert!(!bad.join("scale.csv").exists());
    }
}

/// `hooke bench perf` checks its flags before measuring anything.
#[test]
fn bad_bench_flags() {
    let cases: [(&[&str], &str); 5] = [
        (&["--repeat", "0"], "--repeat must be at least 1"),
        (&["--repeat", "2.5"], "written without a decimal point"),
        (
            &["--threads", "1,0"],
            "--threads must be between 1 and 256, got 0",
        ),
        (
            &["--threads", "2,300"],
            "--threads must be between 1 and 256, got 300",
        ),
        (&["--budget=-1"], "--budget must be finite and > 0"),
    ];
    for (flags, needle) in cases {
        let out = temp("bench-flags");
        let mut args = vec!["bench", "perf", "--out", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        assert_bad_input(&hooke(&args), needle);
        assert!(!out.join("perf.csv").exists());
    }
}

/// Every report checks its `--out` folder before it measures: a file there, where the folder
/// goes, is refused at once, not after minutes of measurement (`bench scale` and `bench gpu`
/// measured first and lost their figures at the end).
#[test]
fn every_bench_refuses_an_out_that_is_a_file_before_measuring() {
    let file = temp("a-file-not-a-folder");
    std::fs::write(&file, "").unwrap();
    let out = file.to_str().unwrap();
    for bench in [
        "work-precision",
        "stability",
        "large-steps",
        "contact",
        "perf",
        "scale",
        "gpu",
    ] {
        let o = hooke(&["bench", bench, "--out", out]);
        if bench == "gpu" && stderr(&o).contains("built without the `gpu` feature") {
            continue;
        }
        assert_bad_input(
            &o,
            &format!("--out: {out} is a file; a report goes into a folder"),
        );
        // The refusal is all it printed: no measurement's progress before it.
        assert_eq!(stderr(&o).lines().count(), 1, "{bench}: {}", stderr(&o));
    }
}

/// Every bad-scene case, through the real binary: exit code 2, and stderr names the file and
/// the problem.
#[test]
fn every_bad_scene_case_through_the_cli() {
    let good = "(gravity: (0.0, -9.8), damping: 10.0, ground: Some(0.0), integrator: SymplecticEuler, \
                dt: 0.0001, particles: [(pos: (0.5, 0.9), mass: 1.0, pinned: true), \
                (pos: (0.5, 0.8), mass: 1.0)], springs: [(a: 0, b: 1, stiffness: 10000.0, rest: 0.1)])";
    let cases: [(&str, &str, &str); 11] = [
        ("b: 1,", "b: 5,", "springs[0]: b = 5 is out of range"),
        ("a: 0, b: 1", "a: 1, b: 1", "springs[0]: a and b are both 1"),
        (
            "(pos: (0.5, 0.8), mass: 1.0)",
            "(pos: (0.5, 0.8), mass: 0.0)",
            "particles[1]: mass must be finite and > 0",
        ),
        (
            "(pos: (0.5, 0.8), mass: 1.0)",
            "(pos: (0.5, 0.8), mass: NaN)",
            "particles[1]: mass must be finite and > 0",
        ),
        ("dt: 0.0001", "dt: 0.0", "dt: must be finite and > 0"),
        ("dt: 0.0001", "dt: inf", "dt: must be finite and > 0"),
        ("dt: 0.0001", "dt: 1e19", "dt: must be at most 1e9 s"),
        (
            "stiffness: 10000.0",
            "stiffness: -1.0",
            "springs[0]: stiffness must be finite and >= 0",
        ),
        (
            "pos: (0.5, 0.8)",
            "pos: (0.5, NaN)",
            "particles[1]: pos must be finite",
        ),
        (
            "gravity: (0.0, -9.8)",
            "gravity: (inf, -9.8)",
            "gravity: must be finite",
        ),
        (
            "damping: 10.0,",
            "damping: 10.0",
            "a comma is missing before `ground`",
        ),
    ];
    for (i, (from, to, needle)) in cases.iter().enumerate() {
        let text = good.replacen(from, to, 1);
        assert_ne!(text, good, "case {i} edits the scene");
        let path = temp(&format!("bad-{i}.ron"));
        std::fs::write(&path, text).unwrap();
        let o = hooke(&["run", "--scene", path.to_str().unwrap(), "--steps", "1"]);
        assert_bad_input(&o, needle);
        assert!(
            stderr(&o).contains(path.to_str().unwrap()),
            "names the file: {}",
            stderr(&o)
        );
    }
}

/// `hooke --help` names every built-in scene and every integrator, both written from the code;
/// the package's description counts the integrators right.
#[test]
fn help_names_every_scene_and_integrator() {
    let o = hooke(&["--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = String::from_utf8_lossy(&o.stdout).into_owned();
    let run = String::from_utf8_lossy(&hooke(&["run", "--help"]).stdout).into_owned();
    for name in hooke::scene::presets::names() {
        assert!(
            help.contains(name),
            "`hooke --help` does not name the scene {name}"
        );
        assert!(
            run.contains(name),
            "`hooke run --help` does not name the scene {name}"
        );
    }
    let count = hooke::readable::count(hooke::sim::Integrator::ALL.len());
    assert!(help.contains(&format!("{count} integrators")), "{help}");
    assert!(
        env!("CARGO_PKG_DESCRIPTION").contains(&format!("{count} integrators")),
        "Cargo.toml's description: {}",
        env!("CARGO_PKG_DESCRIPTION")
    );
    for m in hooke::sim::Integrator::ALL {
        assert!(
            help.contains(m.cli_name()),
            "`hooke --help` does not name {}",
            m.cli_name()
        );
    }
}

/// A scene name that is neither a file nor a built-in: the near built-in names, or all of them.
#[test]
fn a_misspelled_scene_name_gets_a_suggestion() {
    assert_bad_input(&hooke(&["run", "--scene", "pil"]), "did you mean `pile`?");
    assert_bad_input(
        &hooke(&["run", "--scene", "clth32"]),
        "did you mean `cloth32`?",
    );
    let o = hooke(&["run", "--scene", "xyzzy"]);
    for name in hooke::scene::presets::names() {
        assert_bad_input(&o, name);
    }
    // A path keeps the file's own error.
    assert_bad_input(
        &hooke(&["run", "--scene", "no/such.ron"]),
        "cannot read scene",
    );
}

/// `--dt` and `--time` take a fraction p/q: the same run as its decimal; bad fractions are
/// refused with exit 2, naming the flag.
#[test]
fn dt_and_time_take_fractions() {
    let run = |dt: &str, time: &str| {
        let o = hooke(&[
            "run", "--scene", "rope", "--dt", dt, "--time", time, "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = json(&o);
        (r["dt"].clone(), r["steps"].clone(), r["energy_end"].clone())
    };
    assert_eq!(run("1/60", "1/2"), run("0.016666666666666666", "0.5"));
    for (flag, value, needle) in [
        ("--dt", "1/0", "--dt must not divide by zero"),
        (
            "--dt",
            "a/b",
            "--dt must be a number of seconds or a fraction",
        ),
        ("--dt", "-1/60", "--dt must be finite and > 0"),
        ("--time", "1/0", "--time must not divide by zero"),
        ("--time", "-1/60", "--time must be finite and >= 0"),
    ] {
        assert_bad_input(&hooke(&["run", "--scene", "rope", flag, value]), needle);
    }
}

/// Every optional field of the scene format takes a plain value as well as `Some(..)`: the two
/// files load to the same scene and `hooke run` gives the same JSON for both.
#[test]
fn optional_fields_take_plain_values() {
    let spring =
        |extra: &str| format!("springs: [(a: 0, b: 1, stiffness: 100.0, rest: 0.1{extra})],");
    let grid = |extra: &str| {
        format!(
            "generate: [Grid(cols: 3, rows: 3, min: (0.4, 0.5), max: (0.5, 0.6), mass: 0.1, \
             stiffness: 1000.0, shear: true, pin: First{extra})],"
        )
    };
    let ring = |extra: &str| {
        format!("generate: [Ring(center: (0.5, 0.5), radius: 0.1, segments: 8{extra})],")
    };
    // (the field, written plain, written with Some)
    let cases: Vec<(&str, String, String)> = vec![
        ("ground", "ground: 0.0,".into(), "ground: Some(0.0),".into()),
        (
            "click",
            "click: (radius: 0.1),".into(),
            "click: Some((radius: 0.1)),".into(),
        ),
        ("tear", "tear: 0.5,".into(), "tear: Some(0.5),".into()),
        (
            "contact",
            "ground: 0.0, contact: (radius: 0.01, friction: 0.3),".into(),
            "ground: 0.0, contact: Some((radius: 0.01, friction: 0.3)),".into(),
        ),
        (
            "a spring's damping",
            spring(", damping: 5.0"),
            spring(", damping: Some(5.0)"),
        ),
        (
            "a spring's actuation",
            spring(", actuation: (amplitude: 0.1, frequency: 2.0)"),
            spring(", actuation: Some((amplitude: 0.1, frequency: 2.0))"),
        ),
        (
            "a spring's plastic",
            spring(", plastic: (yield: 0.01, rate: 1.0)"),
            spring(", plastic: Some((yield: 0.01, rate: 1.0))"),
        ),
        (
            "a grid's damping",
            grid(", damping: 2.0"),
            grid(", damping: Some(2.0)"),
        ),
        (
            "a grid's plastic",
            grid(", plastic: (yield: 0.01, rate: 1.0)"),
            grid(", plastic: Some((yield: 0.01, rate: 1.0))"),
        ),
        (
            "a ring's damping",
            ring(", damping: 2.0"),
            ring(", damping: Some(2.0)"),
        ),
    ];
    let scene = |body: &str| {
        format!(
            "(gravity: (0.0, -9.8), damping: 1.0, integrator: SymplecticEuler, dt: 0.001, \
             particles: [(pos: (0.5, 0.9), pinned: true), (pos: (0.6, 0.9))], {body})"
        )
    };
    let timing = ["scene", "wall_s", "steps_per_s", "spring_updates_per_s"];
    for (i, (field, plain, some)) in cases.iter().enumerate() {
        let (a, b) = (
            temp(&format!("plain{i}.ron")),
            temp(&format!("some{i}.ron")),
        );
        std::fs::write(&a, scene(plain)).unwrap();
        std::fs::write(&b, scene(some)).unwrap();
        let (la, lb) = (
            hooke::scene::LoadedScene::read(&a).unwrap_or_else(|e| panic!("{field}: {e}")),
            hooke::scene::LoadedScene::read(&b).unwrap_or_else(|e| panic!("{field}: {e}")),
        );
        assert_eq!(la.scene, lb.scene, "{field}");
        let run = |p: &PathBuf| {
            let o = hooke(&[
                "run",
                "--scene",
                p.to_str().unwrap(),
                "--steps",
                "200",
                "--json",
            ]);
            assert!(o.status.success(), "{field}: {}", stderr(&o));
            let mut r = json(&o);
            for t in timing {
                r.as_object_mut().unwrap().remove(t);
            }
            r
        };
        assert_eq!(run(&a), run(&b), "{field}");
    }
}

/// `--device gpu`: the same JSON, with the adapter; a scene the card does not run runs on the
/// CPU and says why on stderr (exit 0); a bad `--device` exits 2. Where the machine has no
/// adapter, the run exits 2 naming it (unless `HOOKE_REQUIRE_GPU` asks for one).
#[test]
fn run_on_the_gpu_reports_the_adapter_or_why_not() {
    if !cfg!(feature = "gpu") {
        let o = hooke(&[
            "run", "--scene", "cloth32", "--steps", "10", "--device", "gpu",
        ]);
        assert_bad_input(&o, "without the `gpu` feature");
        return;
    }
    let o = hooke(&[
        "run", "--scene", "cloth32", "--steps", "100", "--device", "gpu", "--json",
    ]);
    if o.status.code() == Some(2) && std::env::var_os("HOOKE_REQUIRE_GPU").is_none() {
        println!("skipped: {}", stderr(&o));
        return;
    }
    assert!(o.status.success(), "{}", stderr(&o));
    // Quiet: no driver chatter on a machine without a desktop session (see `main`).
    assert!(stderr(&o).is_empty(), "stderr: {}", stderr(&o));
    let j = json(&o);
    assert_eq!(j["device"], "gpu");
    assert!(j["adapter"].as_str().is_some_and(|a| !a.is_empty()), "{j}");
    assert_eq!(j["precision"], "f32");
    assert_eq!(j["steps_taken"], 100);
    assert!(j["energy_end"].as_f64().unwrap() < j["energy_start"].as_f64().unwrap());
    // The summary names the width as the flag writes it.
    let o = hooke(&[
        "run", "--scene", "cloth32", "--steps", "10", "--device", "gpu",
    ]);
    let summary = String::from_utf8_lossy(&o.stdout);
    assert!(
        summary
            .lines()
            .any(|l| l.starts_with("on the GPU: ") && l.ends_with(", f32")),
        "{summary}"
    );
    // The pile's particle pairs run on the card, and their contacts come back.
    let o = hooke(&[
        "run", "--scene", "pile", "--steps", "3000", "--device", "gpu", "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j = json(&o);
    assert_eq!(j["device"], "gpu");
    assert!(j["pair_contacts"].as_u64().is_some_and(|n| n > 0), "{j}");
    // The balloon's pressure bodies (and outlines) do not: on the CPU, saying so.
    let o = hooke(&[
        "run", "--scene", "balloon", "--steps", "10", "--device", "gpu", "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json(&o)["device"], "cpu");
    let e = stderr(&o);
    assert!(
        e.contains("does not run") && e.contains("pressure bodies") && e.contains("on the CPU"),
        "{e}"
    );
    assert_bad_input(
        &hooke(&["run", "--scene", "cloth32", "--device", "tpu"]),
        "--device",
    );
    // --profile times the CPU's passes: on the card there are none to time, and it says so.
    let o = hooke(&[
        "run",
        "--scene",
        "cloth32",
        "--steps",
        "10",
        "--device",
        "gpu",
        "--profile",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(json(&o).get("pass_seconds").is_none());
    assert!(stderr(&o).contains("--profile"), "{}", stderr(&o));
    // A blow-up on the card is found where its state comes back, and the message says so.
    let o = hooke(&[ROPE_PAST_ITS_STABLE_STEP, &["--device", "gpu", "--json"]].concat());
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(json(&o)["finite"], false);
    assert!(
        stderr(&o).contains("at step 300, where the card's state came back"),
        "{}",
        stderr(&o)
    );
    // In f64 the card's state is still finite at step 300, its energy not: a blow-up there as
    // on the CPU (it ended "finite", exit 0, before the card's read took the energy's word).
    let o = hooke(
        &[
            ROPE_PAST_ITS_STABLE_STEP,
            &["--device", "gpu", "--gpu-precision", "f64", "--json"],
        ]
        .concat(),
    );
    let j = json(&o);
    if j["device"] == "gpu" && j["precision"] == "f64" {
        assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
        assert_eq!(j["finite"], false);
        assert!(
            stderr(&o).contains("at step 300, where the card's state came back"),
            "{}",
            stderr(&o)
        );
    } else {
        println!("skipped the card in f64: {}", stderr(&o));
    }
}

/// `hooke bench gpu` prints each figure as it measures it, so that a run on a lent card that
/// is cut short keeps what it measured, and ends with both tables.
#[test]
fn bench_gpu_prints_each_figure_as_it_goes() {
    if !cfg!(feature = "gpu") {
        return;
    }
    let out = temp("bench-gpu");
    let o = hooke(&[
        "bench",
        "gpu",
        "--widths",
        "8",
        "--budget",
        "1e4",
        "--repeat",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    if o.status.code() == Some(2) && std::env::var_os("HOOKE_REQUIRE_GPU").is_none() {
        println!("skipped: {}", stderr(&o));
        return;
    }
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    let figures = |needle: &str| e.lines().filter(|l| l.contains(needle)).count();
    // The CPU, then the card's one step and all steps a submit in each precision it has.
    assert!(figures("M spring updates/s") >= 3, "{e}");
    // XPBD without contact and with pairs, each on the CPU and the card.
    assert_eq!(figures("ms a step"), 4, "{e}");
    let md = std::fs::read_to_string(out.join("gpu.md")).unwrap();
    assert!(md.contains("M spring updates/s") && md.contains("## XPBD at a frame's step"));
}

/// With stderr a terminal, `hooke run` steps in stretches of whole ticks and says how far it
/// is after each; the result is that of one stretch, bit for bit: the pile of boxes (contact
/// between particles, walls) with its springs tearing, XPBD at a frame's step, the crates
/// (rigid bodies: a tick of one step) where the build has them, and the pile on the card
/// where there is one (its run tells after each read-back).
#[test]
fn a_run_in_stretches_ends_where_a_run_in_one_does() {
    use hooke::runner::{Duration, Overrides, run};
    use hooke::scene::presets;
    let mut cases = vec![
        (
            "pile",
            Overrides {
                tear: Some(0.05),
                ..Default::default()
            },
            30_000,
        ),
        (
            "folding_cloth",
            Overrides {
                integrator: Some(hooke::sim::Integrator::Xpbd),
                dt: Some(1.0 / 60.0),
                ..Default::default()
            },
            120,
        ),
    ];
    if cfg!(feature = "avian") {
        cases.push(("crates", Overrides::default(), 3000));
    }
    #[cfg(feature = "gpu")]
    if hooke::solver::gpu::Gpu::open().is_ok() {
        let on_card = Overrides {
            device: hooke::runner::Device::Gpu,
            tear: Some(0.05),
            ..Default::default()
        };
        cases.push(("pile", on_card, 3000));
    }
    for (name, overrides, steps) in cases {
        let loaded = presets::resolve(name).unwrap();
        let whole = run(&loaded, &overrides, Duration::Steps(steps)).unwrap();
        let in_stretches = Overrides {
            progress: true,
            ..overrides.clone()
        };
        let stretched = run(&loaded, &in_stretches, Duration::Steps(steps)).unwrap();
        let (a, b) = (whole.solver(), stretched.solver());
        assert_eq!(stretched.report.steps_taken, steps, "{name}");
        assert_eq!(a.x(), b.x(), "{name} on {:?}: positions", overrides.device);
        assert_eq!(a.v(), b.v(), "{name} on {:?}: velocities", overrides.device);
        assert_eq!(
            stretched.report.springs_torn, whole.report.springs_torn,
            "{name}"
        );
        println!(
            "{name} on {:?}: {} springs torn",
            overrides.device, whole.report.springs_torn
        );
    }
}

/// The app's scripted-run flags are checked before a window opens (no display is needed to
/// see it): a screenshot into a missing folder or not a PNG was an ERROR line of the renderer
/// after the window was up, with an empty file left behind for the latter, and an
/// `--exit-after nan` a run that never quit.
#[cfg(feature = "gui")]
#[test]
fn scripted_run_flags_are_checked_before_a_window_opens() {
    let missing = temp("missing-folder").join("shot.png");
    let jpeg = temp("shot.jpg");
    let missing_report = temp("missing-folder").join("status.json");
    let cases: [(&[&str], &str); 5] = [
        (
            &["--screenshot", missing.to_str().unwrap()],
            "--screenshot: cannot write",
        ),
        (
            &["--screenshot", jpeg.to_str().unwrap()],
            "does not end in .png",
        ),
        (
            &["--report", missing_report.to_str().unwrap()],
            "--report: cannot write",
        ),
        (
            &["--exit-after", "nan"],
            "--exit-after must be finite and >= 0, got NaN",
        ),
        (
            &["--screenshot-after", "inf"],
            "--screenshot-after must be finite and >= 0",
        ),
    ];
    for (flags, needle) in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_hooke"))
            .args(flags)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_bad_input(&o, needle);
    }
    assert!(!jpeg.exists(), "no file is left behind");
}

/// The app where no window can open: no DISPLAY (a shell over SSH), or one that does not
/// answer. bevy_winit panics building its event loop; hooke says why in a line, points to
/// what runs without a window and exits 2, instead of a panic with a backtrace.
#[cfg(feature = "gui")]
#[test]
fn the_app_without_a_display_says_so() {
    for (display, needle) in [
        (None, "no window can open here: DISPLAY is not set"),
        (Some(":9999"), "the X display :9999 does not answer"),
    ] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_hooke"));
        command
            .args(["--scene", "rope"])
            .env_remove("WAYLAND_DISPLAY");
        match display {
            Some(d) => command.env("DISPLAY", d),
            None => command.env_remove("DISPLAY"),
        };
        let o = command.output().unwrap();
        assert_bad_input(&o, needle);
        assert!(
            stderr(&o).contains("hooke run --scene NAME"),
            "{}",
            stderr(&o)
        );
    }
}

/// Output into a pipe whose reader has gone (`hooke run .. | head -1`) ends the run as it ends
/// `cat`, quietly: it printed "failed printing to stdout: Broken pipe" with a panic's
/// backtrace. The summary and the CSV on standard output, the reader closed before either.
#[cfg(target_os = "linux")]
#[test]
fn a_closed_pipe_ends_the_run_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    for args in [
        &["run", "--scene", "rope", "--time", "0.1", "--json"][..],
        &[
            "run",
            "--scene",
            "cloth32",
            "--time",
            "0.01",
            "--out",
            "/dev/stdout",
        ],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_hooke"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.is_empty(), "{args:?}: {err}");
        assert_eq!(out.status.signal(), Some(13), "{args:?}: {:?}", out.status);
    }
}

/// A scene with rigid bodies reports them: the summary counts them, and the JSON gives each
/// where the run left it, as a scene writes it (the three crates fell from where they start
/// into the net, the fixed ground body stayed); a scene without them has no `bodies`.
#[cfg(feature = "avian")]
#[test]
fn a_run_reports_its_rigid_bodies() {
    let o = hooke(&["run", "--scene", "crates", "--time", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("221 springs, 4 rigid bodies, xpbd"), "{out}");
    let j = json(&hooke(&[
        "run", "--scene", "crates", "--time", "2", "--json",
    ]));
    let bodies = j["bodies"].as_array().expect("a bodies array");
    assert_eq!(bodies.len(), 4, "{bodies:?}");
    let height = |b: &serde_json::Value| {
        let (_, shape) = b["shape"].as_object().unwrap().iter().next().unwrap();
        shape["center"][1].as_f64().unwrap()
    };
    // The scene's crates start at 0.6, 0.7 and 0.6 m; the net hangs at 0.4 m.
    for (b, start) in bodies.iter().zip([0.6, 0.7, 0.6]) {
        let y = height(b);
        assert!(y < start - 0.1 && y > 0.3, "{b}");
        assert!(b.get("fixed").is_none(), "{b}");
    }
    assert_eq!(bodies[3]["fixed"], true, "{}", bodies[3]);
    assert_eq!(height(&bodies[3]), 0.05f32 as f64);
    let rope = json(&hooke(&[
        "run", "--scene", "rope", "--time", "0.1", "--json",
    ]));
    assert!(rope.get("bodies").is_none(), "{rope}");
}

/// The summary says where the coupling with rigid bodies was measured not to hold: under
/// implicit Euler past 1/50 s and projective dynamics, BDF2 and VBD past 1/240 s (the panel
/// shows the same line), and not at the steps that held, nor under XPBD, nor without dynamic
/// bodies.
#[cfg(feature = "avian")]
#[test]
fn a_run_says_where_its_rigid_bodies_are_not_held() {
    let says = |args: &[&str]| {
        let o = hooke(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).contains("Rigid bodies: under")
    };
    for (m, held, not) in [
        ("implicit-euler", "1/50", "1/30"),
        ("projective-dynamics", "1/240", "1/60"),
        ("bdf2", "1/240", "1/60"),
        ("xpbd", "1/30", "1/20"),
        ("vbd", "1/15", "1/10"),
    ] {
        let run = [
            "run",
            "--scene",
            "crates",
            "--integrator",
            m,
            "--time",
            "0.1",
        ];
        assert!(says(&[&run[..], &["--dt", not]].concat()), "{m}");
        assert!(!says(&[&run[..], &["--dt", held]].concat()), "{m}");
    }
    let pile = [
        "run",
        "--scene",
        "pile",
        "--integrator",
        "vbd",
        "--dt",
        "1/60",
    ];
    assert!(!says(&[&pile[..], &["--time", "0.1"]].concat()));
}
