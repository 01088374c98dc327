//! Scene files: the shipped scenes load, bad input is refused with a clear error, and a saved
//! scene loads back unchanged.

mod common;
use common::*;
use hooke::scene::{LoadedScene, SceneError, load_into_world, presets, snapshot, to_ron};
use std::path::Path;

fn parse(text: &str) -> Result<LoadedScene, SceneError> {
    LoadedScene::parse(text, Path::new("bad.ron"))
}

/// A valid scene with one pinned particle, one free one and a spring; `edit` breaks it.
fn scene_text(edit: impl Fn(&str) -> String) -> String {
    edit(
        r#"(
    gravity: (0.0, -9.8),
    damping: 10.0,
    ground: Some(0.0),
    integrator: SymplecticEuler,
    dt: 0.0001,
    particles: [
        (pos: (0.5, 0.9), vel: (0.0, 0.0), mass: 1.0, pinned: true),
        (pos: (0.5, 0.8), vel: (0.0, 0.0), mass: 1.0, pinned: false),
    ],
    springs: [
        (a: 0, b: 1, stiffness: 10000.0, rest: 0.1),
    ],
)"#,
    )
}

fn invalid(edit: impl Fn(&str) -> String) -> String {
    match parse(&scene_text(edit)) {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        other => panic!("expected an invalid scene, got {other:?}"),
    }
}

#[test]
fn the_issue_schema_loads() {
    let loaded = parse(&scene_text(|s| s.to_string())).unwrap();
    assert_eq!(loaded.expanded().particles.len(), 2);
    assert_eq!(loaded.expanded().springs.len(), 1);
}

#[test]
fn every_shipped_scene_loads_and_runs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let files = presets::scene_files(&dir);
    assert!(files.len() >= 4, "{files:?}");
    for f in files {
        let Some(loaded) = unless_it_needs_avian(LoadedScene::read(&f), &f.display().to_string())
        else {
            continue;
        };
        let mut app = app_with(loaded.scene.clone());
        step(&mut app, 100);
        assert!(solver(&app).state_is_finite(), "{}", f.display());
    }
    for (name, _) in presets::BUILTIN {
        unless_it_needs_avian(presets::resolve(name), name);
    }
}

/// Every scene of `assets/scenes/` (its benchmarks and hard cases aside) is built in, so that
/// `--scene NAME` opens it from any directory, as the guide's list of shipped scenes promises:
/// `crates` once was listed there and could only be opened by its path.
#[test]
fn every_shipped_scene_is_built_in() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|x| x == "ron") {
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            let built_in = presets::BUILTIN.iter().find(|(n, _)| *n == name);
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                built_in.is_some_and(|(_, t)| *t == text),
                "{name} is shipped but not built in"
            );
        }
    }
}

/// A scene as Windows editors save it, with a byte-order mark and CRLF line ends, loads as
/// the file without them does (the mark was "1:1: Expected opening `(`"); one saved as UTF-16
/// is refused with what to do about it.
#[test]
fn a_scene_saved_on_windows_loads() {
    let dir = std::env::temp_dir().join(format!("hooke-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = presets::BUILTIN
        .iter()
        .find(|(n, _)| *n == "rope")
        .unwrap()
        .1;
    let windows = format!("\u{feff}{}", text.replace('\n', "\r\n"));
    let path = dir.join("rope-notepad.ron");
    std::fs::write(&path, windows).unwrap();
    let loaded = LoadedScene::read(&path).unwrap_or_else(|e| panic!("{e}"));
    let plain = LoadedScene::parse(text, Path::new("rope.ron")).unwrap();
    assert_eq!(
        format!("{:?}", loaded.scene),
        format!("{:?}", plain.scene),
        "the same scene"
    );

    let utf16: Vec<u8> = [0xfeffu16]
        .into_iter()
        .chain(text.encode_utf16())
        .flat_map(u16::to_le_bytes)
        .collect();
    let path = dir.join("rope-utf16.ron");
    std::fs::write(&path, utf16).unwrap();
    let e = LoadedScene::read(&path).expect_err("refused").to_string();
    assert!(
        e.contains("it is not UTF-8 text") && e.contains("save it as UTF-8"),
        "{e}"
    );
}

/// Every scene file the reports run (`assets/scenes/bench/`, `assets/scenes/hard/`) is built in
/// under its path, with the file's text, and nothing else is: `hooke bench stability` once found
/// no scenes outside the repository, and `hooke bench large-steps` could not read its cloth.
#[test]
fn every_report_scene_is_built_in() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![];
    for dir in ["assets/scenes/bench", "assets/scenes/hard"] {
        for path in presets::scene_files(&root.join(dir)) {
            let shipped = path
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .into_owned();
            let text = std::fs::read_to_string(&path).unwrap();
            let built_in = presets::REPORT_SCENES.iter().find(|(p, _)| *p == shipped);
            assert!(
                built_in.is_some_and(|(_, t)| *t == text),
                "{shipped} is shipped but not built in"
            );
            files.push(shipped);
        }
    }
    for (p, _) in presets::REPORT_SCENES {
        assert!(
            files.iter().any(|f| f == p),
            "{p} is built in but not shipped"
        );
    }
}

/// The app opens on the unit square: a built-in scene stays in it while it plays out (the
/// soft box, thrown at 1 m/s, once slid on over the frictionless ground to x = 1.3-1.6 and left
/// the user an empty canvas). 6 s simulated: the thrown box has then slid 99 % of its way.
#[test]
fn every_built_in_scene_stays_in_view() {
    for (name, _) in presets::BUILTIN {
        let Some(loaded) = unless_it_needs_avian(presets::resolve(name), name) else {
            continue;
        };
        let mut app = app_with(loaded.scene.clone());
        let steps = (6.0 / loaded.scene.dt).round() as u64;
        step(&mut app, steps);
        for (i, p) in solver(&app).x().iter().enumerate() {
            // The view's margins round the square in the default 1280×800 window: 0.19 left
            // and right, 0.06 above and below. A hanging cloth's foot spreads by 0.05.
            let inside = (-0.15..=1.15).contains(&p.x) && (-0.05..=1.05).contains(&p.y);
            assert!(inside, "{name}: particle {i} at {p} after 6 s");
        }
    }
}

#[test]
fn malformed_ron_names_file_line_and_column() {
    let e = parse(&scene_text(|s| {
        s.replace("damping: 10.0,", "damping: 10.0")
    }))
    .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, SceneError::Parse { line: 4, .. }), "{msg}");
    assert!(msg.starts_with("bad.ron:4:"), "{msg}");
}

/// A misspelled field anywhere in the format is an error that names it, the name it could
/// have meant and where it is; before, serde skipped it and the scene ran with the default
/// (the particle below weighed 1 kg and was free).
#[test]
fn a_misspelled_field_is_named_with_the_field_it_could_have_meant() {
    // A field misspelled where it stands: (the text, its typo, the line, what the message names).
    let mut cases = vec![
        (
            "pinned: true),",
            "pined: true),".to_string(),
            8,
            ["`pined`", "a particle", "`pinned`"],
        ),
        (
            "mass: 1.0, pinned: false",
            "masss: 5.0, pinned: false".into(),
            9,
            ["`masss`", "a particle", "`mass`"],
        ),
        (
            "stiffness: 10000.0, rest",
            "stifness: 10000.0, rest".into(),
            12,
            ["`stifness`", "a spring", "`stiffness`"],
        ),
    ];
    // An optional field written with a typo, on a line of its own after dt (line 7).
    let dt = "    dt: 0.0001,";
    for (line, names) in [
        ("taer: Some(0.2)", ["`taer`", "the scene", "`tear`"]),
        (
            "iterations: (xpbd_substep: 4)",
            ["`xpbd_substep`", "`iterations`", "`xpbd_substeps`"],
        ),
        (
            "click: Some((radus: 0.1))",
            ["`radus`", "`click`", "`radius`"],
        ),
        (
            "generate: [Grid(cols: 2, rows: 2, min: (0.0, 0.0), max: (1.0, 1.0), sheer: false)]",
            ["`sheer`", "`shear`", "`generate`"],
        ),
        (
            "generate: [Chain(from: (0.0, 0.0), to: (1.0, 0.0), segment: 3)]",
            ["`segment`", "`segments`", "`generate`"],
        ),
        (
            "obstacles: [Circle(centre: (0.5, 0.5), radius: 0.1)]",
            ["`centre`", "`center`", "`obstacles`"],
        ),
        (
            "contact: Some((frction: 0.5))",
            ["`frction`", "`friction`", "`contact`"],
        ),
    ] {
        cases.push((dt, format!("{dt}\n    {line},"), 7, names));
    }
    for (from, to, line, names) in cases {
        let text = scene_text(|s| s.replacen(from, &to, 1));
        assert_ne!(
            text,
            scene_text(|s| s.to_string()),
            "the edit {from:?} applies"
        );
        let e = parse(&text).expect_err(&to);
        let msg = e.to_string();
        assert!(
            matches!(e, SceneError::Parse { line: l, .. } if l == line),
            "{msg}"
        );
        assert!(msg.starts_with(&format!("bad.ron:{line}:")), "{msg}");
        for name in names {
            assert!(msg.contains(name), "{msg} should name {name}");
        }
    }
}

/// A misspelled variant is named with the variants it could have meant.
#[test]
fn a_misspelled_variant_is_named_with_the_variant_it_could_have_meant() {
    let e = parse(&scene_text(|s| s.replace("SymplecticEuler", "Xpdb"))).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("`Xpdb`") && msg.contains("did you mean `Xpbd`"),
        "{msg}"
    );
    assert!(
        msg.contains("SymplecticEuler"),
        "lists the integrators: {msg}"
    );
}

#[test]
fn unknown_integrator_is_a_parse_error() {
    let e = parse(&scene_text(|s| s.replace("SymplecticEuler", "Leapfrog"))).unwrap_err();
    assert!(e.to_string().contains("Leapfrog"), "{e}");
}

#[test]
fn spring_index_out_of_range() {
    let msg = invalid(|s| s.replace("(a: 0, b: 1,", "(a: 0, b: 7,"));
    assert!(
        msg.contains("bad.ron") && msg.contains("springs[0]: b = 7 is out of range"),
        "{msg}"
    );
    assert!(
        msg.contains("the scene has 2 particles: indices 0 to 1"),
        "{msg}"
    );
    let one = invalid(|s| {
        s.replace(
            "(pos: (0.5, 0.8), vel: (0.0, 0.0), mass: 1.0, pinned: false),",
            "",
        )
    });
    assert!(one.contains("the scene has 1 particle: index 0"), "{one}");
}

/// A scene's five parameters left out are the app's: a file of one generator runs as the app
/// runs it, where it once stopped at "Unexpected missing field named `gravity`".
#[test]
fn the_parameters_left_out_are_the_apps() {
    let loaded = parse("(generate: [Chain(from: (0.1, 0.9), to: (0.9, 0.9), segments: 8)])")
        .unwrap_or_else(|e| panic!("{e}"));
    let app = hooke::sim::SimParams::default();
    let s = &loaded.scene;
    assert_eq!(s.gravity, (app.gravity.x, app.gravity.y));
    assert_eq!(
        (s.damping, s.ground, s.integrator, s.dt),
        (app.damping, app.ground, app.integrator, app.dt)
    );
    // `ground: None` still takes the ground away.
    let open = parse("(ground: None)").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(open.scene.ground, None);
}

/// A field the format needs is named with its place, as a misspelled one is.
#[test]
fn a_missing_field_is_named_with_its_place() {
    for (from, to, names) in [
        (
            "(a: 0, b: 1, ",
            "(a: 0, ",
            ["missing field `b`", "in a spring"],
        ),
        (
            "(pos: (0.5, 0.9), ",
            "(",
            ["missing field `pos`", "in a particle"],
        ),
    ] {
        let msg = parse(&scene_text(|s| s.replacen(from, to, 1)))
            .expect_err(from)
            .to_string();
        for name in names {
            assert!(msg.contains(name), "{msg} should name {name}");
        }
        assert!(msg.contains("docs/scene-format.md"), "{msg}");
    }
}

/// The slips of someone who writes JSON, or the command line's fractions and hyphens, or who
/// leaves a comma out, are named with what RON wants, at their line, in place of ron's own words
/// ("Unexpected char '6'", "Expected opening `(`", "Expected identifier", "try the raw
/// identifier `r#projective-dynamics`", "Expected comma").
#[test]
fn a_slip_from_json_or_the_command_line_is_named_with_the_ron_for_it() {
    for (from, to, line, says) in [
        (
            "dt: 0.0001,",
            "dt: 1/60,",
            6,
            "RON has no fractions: write 1/60 as 0.016666666666666666",
        ),
        (
            "dt: 0.0001,",
            "dt: 1.0 / 3.0,",
            6,
            "write 1.0/3.0 as 0.3333333333333333",
        ),
        (
            "gravity: (0.0, -9.8),",
            "gravity: (0.0, -98/10),",
            2,
            "write -98/10 as -9.8",
        ),
        (
            "integrator: SymplecticEuler,",
            "integrator: \"Xpbd\",",
            5,
            "a name is written without quotes: `Xpbd`, not `\"Xpbd\"`",
        ),
        (
            "gravity: (0.0, -9.8),",
            "gravity: [0.0, -9.8],",
            2,
            "a pair or a struct is written in parentheses: (0.0, -9.8), not [0.0, -9.8]",
        ),
        (
            "(pos: (0.5, 0.8),",
            "(pos: [0.5, 0.8],",
            9,
            "in parentheses: (0.5, 0.8), not [0.5, 0.8]",
        ),
        (
            "springs: [",
            "springs: (",
            11,
            "a list is written in brackets: [ … ], not ( … )",
        ),
        (
            "integrator: SymplecticEuler,",
            "integrator: projective-dynamics,",
            5,
            "a name has no hyphens: `ProjectiveDynamics`, not `projective-dynamics`",
        ),
        (
            "dt: 0.0001,",
            "spring-damping: 2.0, dt: 0.0001,",
            6,
            "a field's name has no hyphens: `spring_damping`, not `spring-damping`",
        ),
        (
            "dt: 0.0001,",
            "dt: 0.0001 integrator: Rk4,",
            6,
            "a comma is missing before `integrator`",
        ),
        (
            "pinned: true),",
            "pinned: true)",
            9,
            "a comma is missing before `(pos`",
        ),
        (
            "(0.0, -9.8)",
            "(0.0 -9.8)",
            2,
            "a comma is missing before `-9.8`",
        ),
        ("dt: 0.0001,", "dt: 0.0001", 7, "a comma is missing"),
        (
            "(a: 0, b: 1,",
            "(a: 0, b: 1.5,",
            12,
            "`b` takes a whole number, written without a decimal point or an exponent, not `1.5`",
        ),
        (
            "(a: 0, b: 1,",
            "(a: 0, b: 1e1,",
            12,
            "`b` takes a whole number, written without a decimal point or an exponent, not `1e1`",
        ),
        (
            "(a: 0, b: 1,",
            "(a: -1, b: 1,",
            12,
            "`a` takes a whole number of 0 or more, not `-1`",
        ),
        (
            "(a: 0, b: 1,",
            "(a: 0, b: 99999999999999999999999,",
            12,
            "`b` takes a whole number no larger than its field holds, not `99999999999999999999999`",
        ),
        (
            "(a: 0, b: 1,",
            "(a: NaN, b: 1,",
            12,
            "`a` takes a whole number, not `NaN`",
        ),
    ] {
        let msg = parse(&scene_text(|s| s.replacen(from, to, 1)))
            .expect_err(to)
            .to_string();
        assert!(msg.starts_with(&format!("bad.ron:{line}:")), "{to}: {msg}");
        assert!(msg.contains(says), "{to}: {msg}");
    }
    // A `/` that is no fraction keeps ron's words.
    let msg = parse(&scene_text(|s| s.replacen("dt: 0.0001,", "dt: 1/x,", 1)))
        .unwrap_err()
        .to_string();
    assert!(!msg.contains("fraction"), "{msg}");
}

#[test]
fn spring_to_itself() {
    let msg = invalid(|s| s.replace("(a: 0, b: 1,", "(a: 1, b: 1,"));
    assert!(msg.contains("springs[0]: a and b are both 1"), "{msg}");
}

#[test]
fn bad_masses() {
    for bad in ["0.0", "-1.0", "NaN", "inf"] {
        let msg = invalid(|s| s.replacen("mass: 1.0", &format!("mass: {bad}"), 1));
        assert!(
            msg.contains("particles[0]: mass must be finite and > 0"),
            "{bad}: {msg}"
        );
    }
}

#[test]
fn bad_dt() {
    for bad in ["0.0", "-0.001", "NaN", "inf"] {
        let msg = invalid(|s| s.replace("dt: 0.0001", &format!("dt: {bad}")));
        assert!(msg.contains("dt: must be finite and > 0"), "{bad}: {msg}");
    }
    let msg = invalid(|s| s.replace("dt: 0.0001", "dt: 18446744073709551615"));
    assert!(msg.contains("dt: must be at most 1e9 s"), "{msg}");
}

/// A grid whose corners are swapped or equal in x or y, and a chain whose ends are one point,
/// are refused by name: they loaded as a mirrored grid (its pinned top row at the bottom) or as
/// particles piled on each other.
#[test]
fn generators_that_span_nothing() {
    let grid = |min: &str, max: &str| {
        invalid(|s| {
            s.replace(
                "particles: [",
                &format!(
                    "generate: [Grid(cols: 3, rows: 3, min: {min}, max: {max})],\n    particles: ["
                ),
            )
        })
    };
    for (min, max) in [
        ("(0.4, 0.4)", "(0.2, 0.2)"),
        ("(0.2, 0.4)", "(0.4, 0.2)"),
        ("(0.2, 0.2)", "(0.2, 0.4)"),
        ("(0.2, 0.2)", "(0.2, 0.2)"),
    ] {
        let msg = grid(min, max);
        assert!(
            msg.contains(&format!(
                "generate[0]: min {min} must lie below and left of max {max}"
            )),
            "{min} {max}: {msg}"
        );
    }
    let msg = invalid(|s| {
        s.replace(
            "particles: [",
            "generate: [Chain(from: (0.1, 0.5), to: (0.1, 0.5), segments: 4)],\n    particles: [",
        )
    });
    assert!(
        msg.contains("generate[0]: a chain needs two different ends, not from = to = (0.1, 0.5)"),
        "{msg}"
    );
}

#[test]
fn negative_stiffness() {
    let msg = invalid(|s| s.replace("stiffness: 10000.0", "stiffness: -5.0"));
    assert!(
        msg.contains("springs[0]: stiffness must be finite and >= 0, got -5"),
        "{msg}"
    );
}

#[test]
fn nan_or_infinity_anywhere() {
    let cases = [
        ("gravity: (0.0, -9.8)", "gravity: (0.0, -inf)", "gravity"),
        ("damping: 10.0", "damping: NaN", "damping"),
        ("ground: Some(0.0)", "ground: Some(NaN)", "ground"),
        ("pos: (0.5, 0.8)", "pos: (NaN, 0.8)", "particles[1]: pos"),
        (
            "vel: (0.0, 0.0), mass: 1.0, pinned: false",
            "vel: (inf, 0.0), mass: 1.0, pinned: false",
            "particles[1]: vel",
        ),
        ("rest: 0.1", "rest: inf", "springs[0]: rest"),
        (
            "stiffness: 10000.0",
            "stiffness: NaN",
            "springs[0]: stiffness",
        ),
    ];
    for (from, to, named) in cases {
        let msg = invalid(|s| s.replace(from, to));
        assert!(msg.contains(named), "{to}: {msg}");
    }
}

#[test]
fn every_problem_is_listed() {
    let msg = invalid(|s| {
        s.replace("dt: 0.0001", "dt: 0.0")
            .replace("(a: 0, b: 1,", "(a: 0, b: 9,")
    });
    // dt is checked first; the spring error is listed with it only when the header is valid.
    assert!(msg.contains("dt: must be finite"), "{msg}");
}

#[test]
fn missing_file_is_named() {
    let e = LoadedScene::read(Path::new("no/such/scene.ron")).unwrap_err();
    assert!(e.to_string().contains("no/such/scene.ron"), "{e}");
}

#[test]
fn generated_cloth_matches_the_peer_layout() {
    let loaded = presets::resolve("cloth32").unwrap();
    let e = &loaded.expanded();
    assert_eq!((e.particles.len(), e.springs.len()), (1024, 3906));
    // Particle p = r*32 + c at (c/31, 1 - r/31); row 0 pinned.
    let p = e.particles[2 * 32 + 5];
    assert_eq!(p.pos, (5.0 / 31.0, 1.0 - 2.0 / 31.0));
    assert!(e.particles[31].pinned && !e.particles[32].pinned);
    // Springs per (r, c): right, down, diagonal, anti-diagonal.
    let first: Vec<(usize, usize)> = e.springs[..4].iter().map(|s| (s.a, s.b)).collect();
    assert_eq!(first, vec![(0, 1), (0, 32), (0, 33), (1, 32)]);
}

#[test]
fn a_saved_scene_loads_back_unchanged() {
    let mut app = app_with(presets::resolve("rope").unwrap().scene);
    step(&mut app, 300);
    let saved = snapshot(app.world_mut());
    let text = to_ron(&saved).unwrap();
    let back = LoadedScene::parse(&text, Path::new("saved.ron")).unwrap();
    assert_eq!(back.scene, saved);
    let mut again = hooke::headless_app();
    load_into_world(again.world_mut(), &back);
    hooke::sim::pack(again.world_mut()).unwrap();
    assert_eq!(solver(&again).x(), solver(&app).x());
    assert_eq!(solver(&again).v(), solver(&app).v());
}

/// A scene saved from a running pile, its particle pairs colliding, opens again: its resting
/// contacts sit a little inside 2r, closest under implicit Euler at a frame's step (82 % of 2r
/// on the contact report's pile), and the check that pairs start apart refused such a file
/// ("particles 4 and 84 start 0.0100 m apart … closer than 2 × radius = 0.0100 m"). A pair
/// far inside 2r, as a generator too dense for its radius makes, is still refused.
#[test]
fn a_saved_pile_opens_again() {
    let mut scene = presets::resolve("pile").unwrap().scene;
    scene.integrator = hooke::sim::Integrator::ImplicitEuler;
    scene.dt = 1.0 / 60.0;
    let mut app = app_with(scene);
    step(&mut app, 180);
    let saved = snapshot(app.world_mut());
    let text = to_ron(&saved).unwrap();
    if let Err(e) = LoadedScene::parse(&text, Path::new("saved.ron")) {
        panic!("{e}");
    }
    let dense = "(contact: Some((radius: 0.05, particles: true)), \
                 particles: [(pos: (0.0, 0.5)), (pos: (0.07, 0.5))])";
    let e = LoadedScene::parse(dense, Path::new("dense.ron")).unwrap_err();
    assert!(e.to_string().contains("at most 0.0350 here"), "{e}");
}

/// A spring written without `rest` is at rest where the scene draws it: its ends may be
/// explicit particles or a generator's, and it may carry a material. Without gravity such a
/// network stays where it is; before, `rest` was required, and a person computed 0.206155 by
/// hand (the walker's diagonals).
#[test]
fn a_spring_without_rest_is_at_rest_where_drawn() {
    for dashpot in ["", ", damping: Some(0.5)"] {
        let text = format!(
            "(gravity: (0.0, 0.0), ground: None,
              particles: [(pos: (0.4, 0.5)), (pos: (0.6, 0.5)), (pos: (0.5, 0.7))],
              generate: [Chain(from: (0.7, 0.5), to: (0.9, 0.6), segments: 3)],
              springs: [(a: 0, b: 1{dashpot}), (a: 1, b: 2), (a: 2, b: 0, rest: 0.3),
                        (a: 2, b: 6), (a: 0, b: 5, stiffness: 500.0)])"
        );
        let loaded = parse(&text).unwrap_or_else(|e| panic!("{e}"));
        let mut app = hooke::headless_app();
        load_into_world(app.world_mut(), &loaded);
        hooke::sim::pack(app.world_mut()).unwrap();
        let s = solver(&app);
        let x = s.x().to_vec();
        let mut rests: Vec<f64> = s.springs().iter().map(|sp| sp.rest).collect();
        let d = |a: usize, b: usize| (x[a] - x[b]).length();
        // The explicit springs, then the chain's own three (the solver keeps its own order).
        let mut want = [
            d(0, 1),
            d(1, 2),
            0.3,
            d(2, 6),
            d(0, 5),
            d(3, 4),
            d(4, 5),
            d(5, 6),
        ];
        rests.sort_by(f64::total_cmp);
        want.sort_by(f64::total_cmp);
        assert_eq!(rests, want, "{dashpot}");
        app.world_mut()
            .resource_mut::<hooke::sim::SimParams>()
            .paused = false;
        step(&mut app, 200);
        let moved = max_difference(solver(&app).x(), &x);
        // Only the one spring written at 0.3 pulls.
        assert!(moved > 1e-6, "{dashpot}: the 0.3 spring pulls: {moved}");
        let at_rest = parse(&text.replace(", rest: 0.3", ""))
            .unwrap_or_else(|e| panic!("{e}"))
            .scene;
        let mut app = app_with(at_rest);
        step(&mut app, 200);
        let moved = max_difference(solver(&app).x(), &x);
        assert!(
            moved < 1e-12,
            "{dashpot}: at rest as drawn, yet moved {moved} m"
        );
    }
    // Saved, a rest length is written bare, as a person writes it.
    let saved = to_ron(&parse("(particles: [(pos: (0.0, 0.5)), (pos: (0.1, 0.5))], springs: [(a: 0, b: 1, rest: 0.25)])").unwrap().scene).unwrap();
    assert!(
        saved.contains("rest: 0.25") && !saved.contains("rest: Some"),
        "{saved}"
    );
    // And read bare by plain ron too (no implicit `Some`), as when the field was required.
    let plain: hooke::scene::Scene = ron::from_str(&saved).unwrap();
    assert_eq!(plain.springs[0].rest, Some(0.25));
}

#[test]
fn the_spatial_grid_finds_exactly_the_particles_within_the_radius() {
    use bevy::math::DVec2;
    use hooke::sim::grid::SpatialGrid;
    // A deterministic scatter, queried at many points against a brute-force scan.
    let points: Vec<DVec2> = (0..2000u64)
        .map(|i| {
            let h = |k: u64| {
                ((i * 2 + k).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64
            };
            DVec2::new(h(0) * 1.2 - 0.1, h(1) * 1.2 - 0.1)
        })
        .collect();
    let r = 0.15;
    let mut grid = SpatialGrid::new(r);
    for (i, p) in points.iter().enumerate() {
        grid.insert(*p, i);
    }
    for q in points.iter().step_by(37) {
        let mut found: Vec<usize> = grid.within(*q, r).into_iter().map(|(i, _)| i).collect();
        found.sort_unstable();
        let expected: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].distance(*q) <= r)
            .collect();
        assert_eq!(found, expected);
    }
}

/// A big scene's ids are reserved before its spawn, so that Bevy's per-entity metadata grows
/// once, to the scene plus a sixteenth of room. The 163² cloth has 131,869 entities, just past
/// 2^17: grown by doubling, the metadata would hold 262,144 records. The scene takes the ids
/// it reserved (one unbroken run in a fresh world: a batch that took a fresh id past them
/// would have grown it again), and loading the scene again over itself (its ids back from the
/// free list) grows nothing. What is spawned after the load (here the pack's cached system and
/// its id, a resource, then an empty entity) takes ids from the room below the scene's: a
/// resource is a sparse-set component, whose array spans the entity indices up to its own,
/// and past the scene it would span the whole scene (81 MB a resource at 16 M springs).
#[test]
fn a_big_scene_grows_the_entity_metadata_once() {
    use bevy::prelude::*;
    use hooke::sim::{Particle, Solver, Spring};
    let w = 163;
    let loaded = LoadedScene::from_scene(hooke::bench::perf::cloth(w), None)
        .expect("the bench cloth is valid");
    let mut app = hooke::headless_app();
    let world = app.world_mut();
    let indices = |world: &mut World| {
        let mut q = world.query_filtered::<Entity, Or<(With<Particle>, With<Spring>)>>();
        let mut v: Vec<u32> = q.iter(world).map(|e| e.index_u32()).collect();
        v.sort_unstable();
        v
    };
    let mut grown = 0;
    for load in 0..2 {
        load_into_world(world, &loaded);
        hooke::sim::pack(world).unwrap();
        let (particles, springs) = {
            let s = world.resource::<Solver>();
            (s.particle_count(), s.spring_count())
        };
        let count = particles + springs;
        assert_eq!(count, 131_869);
        let ids = indices(world);
        assert_eq!(ids.len(), count);
        let records = world.entities().len() as usize;
        assert!(
            records < count + count / 8,
            "load {load}: {records} metadata records for {count} entities"
        );
        if load == 0 {
            let (first, last) = (ids[0], *ids.last().unwrap());
            assert_eq!(last - first + 1, count as u32, "one unbroken run of ids");
            let later = world.spawn_empty().id().index_u32();
            assert!(
                later < first && first - later <= (count / 16) as u32,
                "a later spawn ({later}) takes an id from the room below the scene's {first}"
            );
            grown = records;
        } else {
            assert_eq!(records, grown, "the second load grew the metadata");
        }
    }
}

/// Scenes of other sizes loaded one over another (ids partly from the free list, partly
/// fresh) come out whole: every particle and spring, each spring joining the particles it
/// names, and the solver packs them all.
#[test]
fn big_scenes_of_other_sizes_load_over_each_other() {
    use hooke::sim::{Particle, Solver, Spring};
    let mut app = hooke::headless_app();
    let world = app.world_mut();
    for w in [120, 170, 90, 170] {
        let loaded = LoadedScene::from_scene(hooke::bench::perf::cloth(w), None).unwrap();
        load_into_world(world, &loaded);
        hooke::sim::pack(world).unwrap();
        let springs = w * (w - 1) * 2 + (w - 1) * (w - 1) * 2;
        let s = world.resource::<Solver>();
        assert_eq!(
            (s.particle_count(), s.spring_count()),
            (w * w, springs),
            "cloth{w}"
        );
        let particles = world
            .query_filtered::<(), bevy::prelude::With<Particle>>()
            .iter(world)
            .count();
        assert_eq!(particles, w * w);
        let mut q = world.query::<&Spring>();
        let joined = q
            .iter(world)
            .all(|s| world.get::<Particle>(s.a).is_some() && world.get::<Particle>(s.b).is_some());
        assert!(
            joined,
            "cloth{w}: a spring names a particle that is not there"
        );
    }
}

/// With particle pairs colliding, a radius that puts two particles without a spring closer
/// than 2r at the start is refused, naming the closest pair and the largest radius that
/// would do; that radius loads. (A 32² cloth at r = 0.05 went from 5,000 J to 150,000 J in a
/// second, pushed apart from the first step.)
#[test]
fn a_contact_radius_too_large_for_the_scene_is_refused() {
    let cloth = |r: f64| {
        format!(
            "(gravity: (0.0, -9.8), damping: 10.0, ground: Some(0.0), integrator: SymplecticEuler,
              dt: 0.0001,
              generate: [Grid(cols: 32, rows: 32, min: (0.0, 0.0), max: (1.0, 1.0), mass: 1.0,
                              stiffness: 10000.0, shear: true, pin: First)],
              contact: Some((radius: {r}, particles: true)))"
        )
    };
    let message = match parse(&cloth(0.05)) {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        other => panic!("expected an invalid scene, got {other:?}"),
    };
    // The nearest pairs without a spring are two spacings apart: 2/31 m.
    let two_spacings = 2.0 / 31.0;
    assert!(
        message.contains("contact.radius")
            && message.contains(&format!("{two_spacings:.4} m apart"))
            && message.contains(&format!("at most {:.4}", two_spacings / 2.0)),
        "{message}"
    );
    assert!(parse(&cloth(0.99 * two_spacings / 2.0)).is_ok());
    // Without particle pairs the same radius is only the obstacles' and the ground's.
    let points = cloth(0.05).replace("particles: true", "particles: false");
    assert!(parse(&points).is_ok());
}

/// A `Moving` obstacle loads with its motion and moves by it, and a save writes it where it
/// is, still moving, which loads back the same: the `paddle` after 0.3 s has turned 0.24 rad,
/// and a box sent right at 0.5 m/s has gone 0.15 m. Before, a scene file could not move an
/// obstacle at all, and a save wrote a moving one (the library's, or one dragged in the app)
/// as one standing still.
#[test]
fn a_moving_obstacle_loads_moves_and_saves_moving() {
    use hooke::scene::ObstacleDef;
    let mut scene = presets::resolve("paddle").unwrap().scene;
    scene.obstacles.push(ObstacleDef::Moving {
        shape: Box::new(ObstacleDef::Box {
            center: (0.2, 0.9),
            half: (0.05, 0.02),
            angle: 0.0,
        }),
        velocity: (0.5, 0.0),
        spin: 0.0,
    });
    let mut app = app_with(scene);
    step(&mut app, 3000);
    let saved = snapshot(app.world_mut());
    let (turned, sent) = (&saved.obstacles[0], &saved.obstacles[1]);
    let ObstacleDef::Moving {
        shape,
        velocity: (0.0, 0.0),
        spin: 0.8,
    } = turned
    else {
        panic!("the paddle saved as {turned:?}");
    };
    let ObstacleDef::Box { angle, .. } = **shape else {
        panic!("{shape:?}");
    };
    assert!((angle - 0.24).abs() < 1e-12, "turned {angle}");
    let ObstacleDef::Moving {
        shape,
        velocity: (0.5, 0.0),
        spin: 0.0,
    } = sent
    else {
        panic!("the box saved as {sent:?}");
    };
    let ObstacleDef::Box { center, .. } = **shape else {
        panic!("{shape:?}");
    };
    assert!((center.0 - 0.35).abs() < 1e-12, "at {center:?}");
    let text = to_ron(&saved).unwrap();
    let back = LoadedScene::parse(&text, Path::new("saved.ron")).unwrap();
    assert_eq!(back.scene, saved);
}

/// A moving obstacle's motion is checked as every field is: a NaN spin or velocity named by
/// its field, a `Moving` inside a `Moving` and a rigid body's `Moving` shape refused with the
/// reason, and a misspelled field named with the one it could have meant.
#[test]
fn a_bad_moving_obstacle_is_named() {
    let with = |obstacle: &str| {
        scene_text(|s| {
            s.replace(
                "    springs: [",
                &format!("    obstacles: [{obstacle}],\n    springs: ["),
            )
        })
    };
    let refused = |obstacle: &str| match parse(&with(obstacle)) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("{obstacle} loaded"),
    };
    let shape = "Box(center: (0.5, 0.4), half: (0.3, 0.02))";
    assert!(parse(&with(&format!("Moving(shape: {shape}, spin: 1.0)"))).is_ok());
    for (obstacle, named) in [
        (
            format!("Moving(shape: {shape}, spin: NaN)"),
            "obstacles[0]: spin: must be finite",
        ),
        (
            format!("Moving(shape: {shape}, velocity: (inf, 0.0))"),
            "obstacles[0]: velocity.x: must be finite",
        ),
        (
            "Moving(shape: Box(center: (0.5, 0.4), half: (0.3, -0.02)))".to_string(),
            "obstacles[0]: shape.half.y: must be finite and > 0",
        ),
        (
            format!("Moving(shape: Moving(shape: {shape}))"),
            "obstacles[0]: shape: a moving obstacle's shape is a Circle, Box, Segment or Polygon",
        ),
        (
            format!("Moving(shape: {shape}, spinn: 1.0)"),
            "did you mean `spin`",
        ),
    ] {
        let msg = refused(&obstacle);
        assert!(msg.contains(named), "{obstacle}: {msg}");
    }
    if cfg!(feature = "avian") {
        let text = scene_text(|s| {
            s.replace(
                "    springs: [",
                &format!(
                    "    bodies: [(shape: Moving(shape: {shape}, spin: 1.0))],\n    springs: ["
                ),
            )
        });
        let msg = parse(&text).unwrap_err().to_string();
        assert!(
            msg.contains("bodies[0].shape: a body moves by its own `velocity` and `spin`"),
            "{msg}"
        );
    }
}
