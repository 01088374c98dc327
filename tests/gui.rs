//! The desktop app starts, draws and accepts clicks, under a real X server (Xvfb).
//!
//! Skips with a printed reason only where no display can be had: no `$DISPLAY` and no Xvfb
//! installed. Under CI (`CI` set) a missing display is a failure, not a skip.
#![cfg(feature = "gui")]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Kills the process when dropped, so a failing assertion leaves nothing behind.
struct Killed(Child);
impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A private X server, stopped with SIGTERM when dropped: a killed (SIGKILL) Xvfb leaves
/// its socket and lock file behind in `/tmp`, and those pile up across runs.
struct Xvfb(Child);
impl Drop for Xvfb {
    fn drop(&mut self) {
        let terminated = Command::new("kill")
            .args(["-TERM", &self.0.id().to_string()])
            .status()
            .is_ok_and(|s| s.success());
        let deadline = Instant::now() + Duration::from_secs(5);
        while terminated && Instant::now() < deadline {
            if let Ok(Some(_)) = self.0.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The GUI tests run one at a time: each takes a display and the cores, and keyboard focus
/// belongs to one window.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// A display to use: `$DISPLAY`, or a private Xvfb started here.
///
/// Xvfb picks the display number itself (`-displayfd`): it skips displays in use and clears
/// stale lock files, which a scan of `/tmp/.X11-unix` by hand cannot tell apart from live ones.
fn display() -> Option<(String, Option<Xvfb>)> {
    if let Ok(d) = std::env::var("DISPLAY")
        && !d.is_empty()
    {
        return Some((d, None));
    }
    if !have("Xvfb") {
        return None;
    }
    let mut child = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1280x800x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let stdout = child.stdout.take()?;
    let server = Xvfb(child);
    // Xvfb writes the number once it listens, or exits (end of file) if it cannot start.
    let mut line = String::new();
    std::io::BufRead::read_line(&mut std::io::BufReader::new(stdout), &mut line).ok()?;
    let n: u32 = line.trim().parse().ok()?;
    Some((format!(":{n}"), Some(server)))
}

fn status(path: &Path) -> Option<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

fn wait_for(what: &str, timeout: Duration, mut ok: impl FnMut() -> bool) {
    let deadline = Instant::now() + timeout;
    while !ok() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

fn xdotool(display: &str, args: &[&str]) -> String {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", display)
        .output()
        .expect("xdotool runs");
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// The id of the app's window.
fn hooke_window(display: &str) -> String {
    let found = xdotool(display, &["search", "--name", "^hooke"]);
    found
        .lines()
        .next()
        .expect("a window named hooke")
        .to_string()
}

fn pixel(png: &Path, x: i64, y: i64) -> (u8, u8, u8) {
    let out = Command::new("convert")
        .arg(png)
        .args(["-format", &format!("%[fx:int(255*p{{{x},{y}}}.r)],%[fx:int(255*p{{{x},{y}}}.g)],%[fx:int(255*p{{{x},{y}}}.b)]"), "info:"])
        .output()
        .expect("ImageMagick's convert runs");
    let s = String::from_utf8_lossy(&out.stdout);
    let v: Vec<u8> = s
        .trim()
        .split(',')
        .map(|c| c.parse().unwrap_or(0))
        .collect();
    assert_eq!(
        v.len(),
        3,
        "convert said {s:?} {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (v[0], v[1], v[2])
}

/// Starts the app on `scene` with a status file, on software Vulkan, in the project's folder.
fn launch(display: &str, scene: &str, report: &Path, log: &Path) -> Killed {
    launch_in(
        display,
        scene,
        report,
        log,
        Path::new(env!("CARGO_MANIFEST_DIR")),
    )
}

/// [`launch`] in the folder `cwd` (where Save writes `saved/`).
fn launch_in(display: &str, scene: &str, report: &Path, log: &Path, cwd: &Path) -> Killed {
    let app = Command::new(env!("CARGO_BIN_EXE_hooke"))
        .args(["--scene", scene, "--exit-after", "300", "--report"])
        .arg(report)
        .current_dir(cwd)
        .env("DISPLAY", display)
        .env("WGPU_BACKEND", "vulkan")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(log).unwrap())
        .spawn()
        .expect("the app starts");
    Killed(app)
}

/// The pixels of the (2r+1)² square around (x, y), in one ImageMagick call.
fn pixels_around(png: &Path, x: i64, y: i64, r: i64) -> Vec<(u8, u8, u8)> {
    let out = Command::new("convert")
        .arg(png)
        .args([
            "-crop",
            &format!("{0}x{0}+{1}+{2}", 2 * r + 1, x - r, y - r),
            "-depth",
            "8",
            "txt:-",
        ])
        .output()
        .expect("ImageMagick's convert runs");
    // Lines look like `0,0: (255,191,51)  #FFBF33  srgb(255,191,51)`.
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let inner = l.split_once(": (")?.1.split_once(')')?.0;
            let v: Vec<u8> = inner
                .split(',')
                .filter_map(|c| c.trim().parse().ok())
                .collect();
            (v.len() >= 3).then(|| (v[0], v[1], v[2]))
        })
        .collect()
}

/// A display and the tools, or `None` with the reason printed (under CI: a failure).
fn gui_display(tools: &[&str]) -> Option<(String, Option<Xvfb>)> {
    let in_ci = std::env::var_os("CI").is_some();
    let Some(found) = display() else {
        assert!(
            !in_ci,
            "CI must provide a display: no $DISPLAY, and Xvfb is missing or did not start"
        );
        println!("skipped: no DISPLAY and no Xvfb on this machine");
        return None;
    };
    for tool in tools {
        if !have(tool) {
            assert!(!in_ci, "CI must install {tool}");
            println!("skipped: {tool} is not installed");
            return None;
        }
    }
    Some(found)
}

#[test]
fn app_starts_draws_and_accepts_clicks() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some((display, _xvfb)) = gui_display(&["xdotool", "import", "convert"]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("hooke-gui-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let report = dir.join("status.json");
    let mut app = launch(&display, "empty", &report, &dir.join("app.log"));
    let log = || std::fs::read_to_string(dir.join("app.log")).unwrap_or_default();

    // It opens a window and renders frames.
    wait_for("the app's first frames", Duration::from_secs(180), || {
        if let Ok(Some(code)) = app.0.try_wait() {
            panic!("the app exited early ({code}):\n{}", log());
        }
        status(&report).is_some_and(|s| s["fps"].as_f64().unwrap_or(0.0) > 0.0)
    });
    let window = hooke_window(&display);
    let s = status(&report).unwrap();
    assert_eq!(s["particles"], 0, "the empty scene starts empty");
    assert_eq!(s["paused"], true, "the assignment's scene starts paused");
    // Paused and untouched, it waits for input instead of drawing the same picture sixty
    // times a second (it did, and kept most of two cores busy): a few frames a second, for
    // the report's clock. The clicks below are input, and wake it at once.
    wait_for("a paused app to idle", Duration::from_secs(30), || {
        status(&report).is_some_and(|s| s["fps"].as_f64().is_some_and(|f| f < 8.0))
    });

    // Three clicks on the canvas, within 0.15 of each other: 3 particles, 3 springs, the
    // first pinned. A click on the panel adds nothing.
    let view = s["view"].clone();
    let clicks = [(0.5, 0.8), (0.6, 0.8), (0.55, 0.7)];
    for (i, &(x, y)) in clicks.iter().enumerate() {
        let (wx, wy) = world_to_window(&view, x, y);
        xdotool(
            &display,
            &[
                "mousemove",
                "--window",
                &window,
                &wx.to_string(),
                &wy.to_string(),
            ],
        );
        std::thread::sleep(Duration::from_millis(300));
        xdotool(&display, &["click", "1"]);
        wait_for(
            &format!("particle {}", i + 1),
            Duration::from_secs(60),
            || status(&report).is_some_and(|s| s["particles"] == i + 1),
        );
    }
    xdotool(&display, &["mousemove", "--window", &window, "100", "600"]);
    std::thread::sleep(Duration::from_millis(300));
    xdotool(&display, &["click", "1"]);
    std::thread::sleep(Duration::from_secs(2));
    let s = status(&report).unwrap();
    assert_eq!(
        (
            s["particles"].as_u64(),
            s["springs"].as_u64(),
            s["pinned"].as_u64()
        ),
        (Some(3), Some(3), Some(1)),
        "{s}"
    );

    // What is on screen: the particles are drawn where they were clicked, and the panel is there.
    let shot: PathBuf = dir.join("screen.png");
    let ok = Command::new("import")
        .args(["-window", "root"])
        .arg(&shot)
        .env("DISPLAY", &display)
        .status()
        .unwrap();
    assert!(ok.success());
    let origin = xdotool(&display, &["getwindowgeometry", &window]);
    let (ox, oy) = origin
        .lines()
        .find_map(|l| l.trim().strip_prefix("Position: "))
        .and_then(|p| p.split_whitespace().next())
        .and_then(|p| p.split_once(','))
        .map(|(x, y)| (x.parse::<i64>().unwrap(), y.parse::<i64>().unwrap()))
        .unwrap_or((0, 0));
    for &(x, y) in &clicks[1..] {
        let (wx, wy) = world_to_window(&view, x, y);
        let (r, g, b) = pixel(&shot, ox + wx, oy + wy);
        assert!(
            r > 180 && g > 180 && b > 180,
            "no particle drawn at ({x}, {y}): {r},{g},{b}"
        );
    }
    let (r, g, b) = pixel(&shot, ox + 640, oy + 400);
    assert!((r, g, b) != (0, 0, 0), "the window shows something");
    drop(app);

    // A scene loaded at start-up gets its dots too: the rope's pinned end is drawn, in orange.
    let report = dir.join("rope.json");
    let _app = launch(&display, "rope", &report, &dir.join("rope.log"));
    wait_for("the rope's first frames", Duration::from_secs(180), || {
        status(&report).is_some_and(|s| s["fps"].as_f64().unwrap_or(0.0) > 0.0)
    });
    std::thread::sleep(Duration::from_secs(1));
    let window = hooke_window(&display);
    let view = status(&report).unwrap()["view"].clone();
    let shot = dir.join("rope.png");
    assert!(
        Command::new("import")
            .args(["-window", &window])
            .arg(&shot)
            .env("DISPLAY", &display)
            .status()
            .unwrap()
            .success()
    );
    // Orange (255,191,51) around the pinned end, partly under the spring's red line (217,51,51);
    // without the dot only red and the near-black background are there.
    let (wx, wy) = world_to_window(&view, 0.3, 0.9);
    let around = pixels_around(&shot, wx, wy, 4);
    let orange = around
        .iter()
        .filter(|&&(r, g, b)| r > 220 && g > 150 && b < 100)
        .count();
    assert!(orange > 0, "no pinned dot at the rope's end: {around:?}");
}

/// One running app under Xvfb, driven by real input (xdotool) and checked through its status
/// report.
struct Session {
    display: String,
    window: String,
    report: PathBuf,
    log: PathBuf,
    app: Killed,
}

impl Session {
    fn start(display: &str, scene: &str, dir: &Path) -> Session {
        Session::start_in(display, scene, dir, Path::new(env!("CARGO_MANIFEST_DIR")))
    }

    /// [`Session::start`] with the app working in `cwd`.
    fn start_in(display: &str, scene: &str, dir: &Path, cwd: &Path) -> Session {
        let report = dir.join(format!("{scene}-session.json"));
        let log = dir.join(format!("{scene}-session.log"));
        // A report left by an earlier session in `dir` is not this app's.
        let _ = std::fs::remove_file(&report);
        let mut app = launch_in(display, scene, &report, &log, cwd);
        wait_for("the app's first frames", Duration::from_secs(180), || {
            if let Ok(Some(code)) = app.0.try_wait() {
                panic!("the app exited early ({code})");
            }
            status(&report).is_some_and(|s| s["fps"].as_f64().unwrap_or(0.0) > 0.0)
        });
        let window = hooke_window(display);
        let s = Session {
            display: display.to_string(),
            window,
            report,
            log,
            app,
        };
        s.x(&["windowfocus", "--sync", &s.window]);
        s
    }

    fn x(&self, args: &[&str]) -> String {
        xdotool(&self.display, args)
    }

    fn status(&self) -> serde_json::Value {
        let mut last = None;
        wait_for("a status report", Duration::from_secs(30), || {
            last = status(&self.report);
            last.is_some()
        });
        last.unwrap()
    }

    /// Waits for the next report written after now, then for `ok` to hold.
    fn expect(&self, what: &str, ok: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let mut last = serde_json::Value::Null;
        let deadline = Instant::now() + Duration::from_secs(60);
        std::thread::sleep(Duration::from_millis(700));
        loop {
            if let Some(s) = status(&self.report) {
                if ok(&s) {
                    return s;
                }
                last = s;
            }
            assert!(
                Instant::now() < deadline,
                "timed out waiting for {what}: {last}"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// Moves the pointer to a world point, through the mapping the app reports now.
    fn move_to(&self, x: f64, y: f64) {
        let view = self.status()["view"].clone();
        let (wx, wy) = world_to_window(&view, x, y);
        self.move_px(wx, wy);
    }

    /// Moves the pointer to a window point.
    fn move_px(&self, wx: i64, wy: i64) {
        self.x(&[
            "mousemove",
            "--window",
            &self.window,
            &wx.to_string(),
            &wy.to_string(),
        ]);
        std::thread::sleep(Duration::from_millis(150));
    }

    fn key(&self, key: &str) {
        self.keys(&[key]);
    }

    /// Types `keys` with no delay between them: they reach the app within one frame.
    fn keys(&self, keys: &[&str]) {
        self.x(&["windowfocus", "--sync", &self.window]);
        self.x(&[&["key", "--delay", "0"][..], keys].concat());
    }

    /// Drags with `button` from world point a to world point b in `steps` moves.
    fn drag(&self, button: &str, a: (f64, f64), b: (f64, f64), steps: usize) {
        self.move_to(a.0, a.1);
        self.x(&["mousedown", button]);
        std::thread::sleep(Duration::from_millis(200));
        for i in 1..=steps {
            let t = i as f64 / steps as f64;
            self.move_to(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        }
        std::thread::sleep(Duration::from_millis(300));
        self.x(&["mouseup", button]);
    }

    fn log(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }
}

/// The window-to-world mapping the app reports: (scale, center, world_center).
fn mapping(view: &serde_json::Value) -> (f64, (f64, f64), (f64, f64)) {
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    let pair = |v: &serde_json::Value| (f(&v[0]), f(&v[1]));
    (
        f(&view["scale"]),
        pair(&view["center"]),
        pair(&view["world_center"]),
    )
}

/// Window coordinates of a world point: center + (world − world_center) · scale, y flipped.
fn world_to_window(view: &serde_json::Value, x: f64, y: f64) -> (i64, i64) {
    let (scale, (cx, cy), (wx, wy)) = mapping(view);
    (
        (cx + (x - wx) * scale).round() as i64,
        (cy - (y - wy) * scale).round() as i64,
    )
}

/// The world point of a window point (the inverse of [`world_to_window`], unrounded).
fn window_to_world(view: &serde_json::Value, px: f64, py: f64) -> (f64, f64) {
    let (scale, (cx, cy), (wx, wy)) = mapping(view);
    (wx + (px - cx) / scale, wy - (py - cy) / scale)
}

fn positions(s: &serde_json::Value) -> Vec<(f64, f64)> {
    s["positions"]
        .as_array()
        .expect("positions in the report")
        .iter()
        .map(|p| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect()
}

fn counts(s: &serde_json::Value) -> (u64, u64, u64) {
    (
        s["particles"].as_u64().unwrap(),
        s["springs"].as_u64().unwrap(),
        s["pinned"].as_u64().unwrap(),
    )
}

/// The ERROR lines, and the WARN lines that name hooke, in a log.
fn bad_lines(log: &str) -> Vec<&str> {
    log.lines()
        .filter(|l| l.contains("ERROR") || (l.contains("WARN") && l.contains("hooke")))
        .collect()
}

/// Every control, with real input, checked by the state the app reports; and a quiet log.
#[test]
fn every_control_works_under_real_input_and_the_log_stays_quiet() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some((display, _xvfb)) = gui_display(&["xdotool"]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("hooke-controls-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = Session::start(&display, "empty", &dir);
    // The empty canvas renders a while with nothing in it.
    std::thread::sleep(Duration::from_secs(2));
    assert!(bad_lines(&s.log()).is_empty(), "empty canvas:\n{}", s.log());

    // The panel's tearing field takes a typed percentage: 30 is a strain of 0.3 (it was read
    // as 30, 3000 %, and clamped to 200 %). The row's place is the empty scene's panel
    // layout, under the contact rows (and the Device row above them).
    s.move_px(95, 368);
    s.x(&["click", "1"]);
    s.expect("tearing on", |st| st["tear"] == 0.6);
    s.move_px(242, 368);
    s.x(&["click", "1"]);
    std::thread::sleep(Duration::from_millis(300));
    s.x(&["windowfocus", "--sync", &s.window]);
    s.x(&["type", "--delay", "80", "30"]);
    s.key("Return");
    s.expect("30 % typed", |st| st["tear"] == 0.3);
    s.move_px(95, 368);
    s.x(&["click", "1"]);
    s.expect("tearing off", |st| st["tear"].is_null());

    // The dt field takes a typed fraction: 1/60 is a frame's step, to the bit of 1.0 / 60.0.
    // A click on the value box opens it with its text selected, so typing replaces it.
    let type_dt = |text: &str| {
        s.move_px(225, 284);
        s.x(&["click", "1"]);
        std::thread::sleep(Duration::from_millis(300));
        s.x(&["windowfocus", "--sync", &s.window]);
        s.x(&["type", "--delay", "80", text]);
        s.key("Return");
    };
    type_dt("1/60");
    s.expect("dt 1/60 typed", |st| st["dt"] == 1.0 / 60.0);
    type_dt("1e-4");
    s.expect("dt back to 1e-4", |st| st["dt"] == 1e-4);

    // The Device row's GPU switch: the renderer's card is handed over, and the empty scene's
    // steps go to it (it runs symplectic Euler), then back.
    s.expect("a card handed over", |st| st["adapter"].is_string());
    s.move_px(95, 179);
    s.x(&["click", "1"]);
    s.expect("stepping on the card", |st| st["device"] == "gpu");
    s.move_px(95, 179);
    s.x(&["click", "1"]);
    s.expect("back on the CPU", |st| {
        st["device"] == "cpu" && st["gpu_wanted"] == false
    });

    // The empty canvas's line under its middle takes no input: a click on its words adds a
    // particle (it is then gone), and undo takes the particle back.
    s.move_px(780, 673);
    s.x(&["click", "1"]);
    s.expect("a particle added under the line", |st| st["particles"] == 1);
    s.key("ctrl+z");
    s.expect("and taken back", |st| st["particles"] == 0);

    // Left click on empty canvas: three particles joined within 0.15, the first pinned.
    for (i, &(x, y)) in [(0.5, 0.8), (0.6, 0.8), (0.55, 0.7)].iter().enumerate() {
        s.move_to(x, y);
        s.x(&["click", "1"]);
        s.expect(&format!("particle {}", i + 1), |st| {
            st["particles"] == i + 1
        });
    }
    assert_eq!(counts(&s.status()), (3, 3, 1));

    // Shift + click: a pinned particle, too far from the others to be joined.
    s.move_to(0.3, 0.45);
    s.x(&["keydown", "shift", "click", "1", "keyup", "shift"]);
    s.expect("a pinned particle", |st| counts(st) == (4, 3, 2));

    // A press on empty canvas that turns into a drag is no click: it adds nothing.
    s.drag("1", (0.85, 0.85), (0.95, 0.6), 6);
    let st = s.expect("a drag from empty canvas over", |st| st["held"] == 0);
    assert_eq!(
        counts(&st),
        (4, 3, 2),
        "a drag from empty canvas adds nothing"
    );

    // A press on a particle grabs it (adds nothing); the drag ends at the cursor (paused).
    s.drag("1", (0.6, 0.8), (0.7, 0.6), 8);
    let st = s.expect("the dragged particle at the cursor", |st| {
        let p = positions(st)[1];
        (p.0 - 0.7).abs() < 0.01 && (p.1 - 0.6).abs() < 0.01
    });
    assert_eq!(counts(&st), (4, 3, 2), "a grab adds nothing");
    let px = 1.0 / st["view"]["scale"].as_f64().unwrap();
    let p = positions(&st)[1];
    assert!(
        (p.0 - 0.7).abs() < 1.5 * px && (p.1 - 0.6).abs() < 1.5 * px,
        "{p:?}"
    );

    // P pins, and P again frees, the particle under the cursor.
    s.move_to(0.55, 0.7);
    s.key("p");
    s.expect("P pins", |st| counts(st).2 == 3);
    s.key("p");
    s.expect("P frees", |st| counts(st).2 == 2);

    // X deletes the particle under the cursor (the lone pinned one: no springs).
    let before_delete = positions(&s.status());
    s.move_to(0.3, 0.45);
    s.key("x");
    s.expect("X deletes", |st| counts(st) == (3, 3, 1));

    // Ctrl + drag cuts exactly the springs the path crosses: at y = 0.75 from x = 0.45 to
    // 0.54 it crosses (0.5, 0.8)-(0.55, 0.7) only; (0.5, 0.8)-(0.7, 0.6) passes y = 0.75 at
    // x = 0.55.
    s.x(&["keydown", "ctrl"]);
    s.drag("1", (0.45, 0.75), (0.54, 0.75), 6);
    s.x(&["keyup", "ctrl"]);
    s.expect("one spring cut", |st| counts(st) == (3, 2, 1));

    // Undo and redo: the cut, then the delete, back exactly.
    s.key("ctrl+z");
    s.expect("undo the cut", |st| counts(st) == (3, 3, 1));
    s.key("ctrl+shift+z");
    s.expect("redo the cut", |st| counts(st) == (3, 2, 1));
    s.key("ctrl+z");
    s.expect("undo the cut again", |st| counts(st) == (3, 3, 1));
    s.key("ctrl+y");
    s.expect("ctrl+y redoes", |st| counts(st) == (3, 2, 1));
    // Two chords in one frame are two undos.
    s.keys(&["ctrl+z", "ctrl+z"]);
    let st = s.expect("undo the delete", |st| counts(st) == (4, 3, 2));
    assert_eq!(
        positions(&st),
        before_delete,
        "the delete undone to the bit"
    );
    s.keys(&["ctrl+shift+z", "ctrl+shift+z"]);
    s.expect("both redone", |st| counts(st) == (3, 2, 1));

    // The wheel zooms about the cursor: the world point under it stays put, and a click after
    // zooming lands where it points.
    let view0 = s.status()["view"].clone();
    let (cx, cy) = world_to_window(&view0, 0.8, 0.4);
    s.move_px(cx, cy);
    s.x(&["click", "--repeat", "3", "--delay", "80", "4"]);
    let st = s.expect("zoomed in", |st| {
        st["view"]["scale"].as_f64().unwrap() > 1.5 * view0["scale"].as_f64().unwrap()
    });
    let (ux, uy) = window_to_world(&st["view"], cx as f64, cy as f64);
    let px = 1.0 / st["view"]["scale"].as_f64().unwrap();
    assert!(
        (ux - 0.8).abs() < 2.0 * px && (uy - 0.4).abs() < 2.0 * px,
        "({ux}, {uy}) under the cursor after zooming"
    );
    s.move_to(0.8, 0.45);
    s.x(&["click", "1"]);
    let st = s.expect("a particle added at the zoomed view", |st| {
        counts(st).0 == 4
    });
    let p = *positions(&st).last().unwrap();
    assert!(
        (p.0 - 0.8).abs() < 1.5 * px && (p.1 - 0.45).abs() < 1.5 * px,
        "clicked (0.8, 0.45), got {p:?}"
    );

    // Middle drag pans: the world moves with the cursor.
    let view1 = s.status()["view"].clone();
    let (ax, ay) = world_to_window(&view1, 0.9, 0.3);
    s.move_px(ax, ay);
    s.x(&["mousedown", "2"]);
    for i in 1..=5 {
        s.move_px(ax - 16 * i, ay + 8 * i);
    }
    s.x(&["mouseup", "2"]);
    let st = s.expect("panned", |st| {
        st["view"]["world_center"] != view1["world_center"]
    });
    let scale = st["view"]["scale"].as_f64().unwrap();
    let moved = (
        st["view"]["world_center"][0].as_f64().unwrap()
            - view1["world_center"][0].as_f64().unwrap(),
        st["view"]["world_center"][1].as_f64().unwrap()
            - view1["world_center"][1].as_f64().unwrap(),
    );
    assert!(
        (moved.0 - 80.0 / scale).abs() < 2.0 / scale
            && (moved.1 - 40.0 / scale).abs() < 2.0 / scale,
        "pan moved the view by {moved:?}"
    );

    // F fits the scene: the unit square fills the canvas again.
    s.key("f");
    let st = s.expect("fitted", |st| {
        let v = &st["view"];
        (v["world_center"][0].as_f64().unwrap() - 0.5).abs() < 1e-6
            && (v["scale"].as_f64().unwrap() - view0["scale"].as_f64().unwrap()).abs() < 1e-3
    });
    assert_eq!(counts(&st).0, 4);

    // H and ? show and hide the list of controls.
    s.key("h");
    s.expect("help shown", |st| st["help"] == true);
    s.key("question");
    s.expect("help hidden", |st| st["help"] == false);

    // The right button attracts: run, let the free particles fall to the ground, then hold
    // the button just above the one added last; it rises toward the cursor.
    s.key("g");
    s.expect("running and settled", |st| {
        st["paused"] == false && positions(st).last().unwrap().1 < 0.01
    });
    let x_last = positions(&s.status()).last().unwrap().0;
    s.move_to(x_last, 0.08);
    s.x(&["mousedown", "3"]);
    // (The status may be written between the press and the solver's sync of that frame, so
    // the external force is waited for with the rise, not asserted after it.)
    s.expect("pulled up by the attraction", |st| {
        st["attracting"] == true
            && st["external_force"] == true
            && positions(st).last().unwrap().1 > 0.03
    });
    s.x(&["mouseup", "3"]);
    s.expect("attraction released", |st| {
        st["attracting"] == false && st["external_force"] == false
    });

    // Obstacles: B + drag builds a box, O + drag a circle, L + drag a segment (while paused).
    s.key("g");
    s.expect("paused", |st| st["paused"] == true);
    let built = |st: &serde_json::Value| st["obstacles"].as_array().map_or(0, |a| a.len());
    for (i, (key, a, b)) in [
        ("b", (0.15, 0.3), (0.3, 0.2)),
        ("o", (0.8, 0.3), (0.85, 0.3)),
        ("l", (0.1, 0.6), (0.3, 0.5)),
    ]
    .into_iter()
    .enumerate()
    {
        s.x(&["windowfocus", "--sync", &s.window]);
        s.x(&["keydown", key]);
        s.drag("1", a, b, 5);
        s.x(&["keyup", key]);
        s.expect(&format!("obstacle {} built", i + 1), |st| {
            built(st) == i + 1
        });
    }
    // A press on the box moves it; undo puts it back.
    let box_at = |st: &serde_json::Value| {
        let o = st["obstacles"].as_array().unwrap();
        o.iter()
            .map(|c| (c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
            .find(|c| (c.1 - 0.25).abs() < 0.2 && c.0 < 0.5 && c.1 < 0.45)
    };
    let before = box_at(&s.status()).expect("the box's centre");
    assert!(
        (before.0 - 0.225).abs() < 0.01 && (before.1 - 0.25).abs() < 0.01,
        "{before:?}"
    );
    s.drag("1", (0.2, 0.25), (0.3, 0.35), 5);
    s.expect("the box moved", |st| {
        box_at(st).is_some_and(|c| (c.0 - 0.325).abs() < 0.01 && (c.1 - 0.35).abs() < 0.01)
    });
    s.key("ctrl+z");
    s.expect("the move undone", |st| {
        box_at(st).is_some_and(|c| (c.0 - before.0).abs() < 1e-6 && (c.1 - before.1).abs() < 1e-6)
    });
    // X on the circle deletes it; undo brings it back; redo deletes it again.
    s.move_to(0.8, 0.3);
    s.key("x");
    s.expect("the circle deleted", |st| built(st) == 2);
    s.key("ctrl+z");
    s.expect("the delete undone", |st| built(st) == 3);
    s.key("ctrl+shift+z");
    s.expect("the delete redone", |st| built(st) == 2);
    // J + drag draws a ball: a ring of particles, one spring per edge, filled with gas; undo
    // takes it away whole.
    let (n0, m0, _) = counts(&s.status());
    s.x(&["windowfocus", "--sync", &s.window]);
    s.x(&["keydown", "j"]);
    s.drag("1", (0.6, 0.7), (0.68, 0.7), 5);
    s.x(&["keyup", "j"]);
    let ball = s.expect("a ball drawn", |st| counts(st).0 > n0);
    let (n1, m1, _) = counts(&ball);
    assert!(n1 - n0 >= 8 && m1 - m0 == n1 - n0, "{:?}", counts(&ball));
    s.key("ctrl+z");
    s.expect("the ball undone", |st| {
        counts(st).0 == n0 && counts(st).1 == m0
    });
    s.key("g");
    s.expect("running again", |st| st["paused"] == false);

    // C clears; undo brings it all back.
    s.key("c");
    s.expect("cleared", |st| counts(st) == (0, 0, 0));
    s.key("ctrl+z");
    s.expect("the clear undone", |st| counts(st).0 == 4);

    // A resize keeps the mapping consistent and the log quiet.
    s.x(&["windowsize", &s.window, "1000", "700"]);
    s.expect("resized", |st| {
        st["view"]["center"][1].as_f64().unwrap() < 360.0
    });
    std::thread::sleep(Duration::from_secs(1));
    let bad = bad_lines(&s.log()).join("\n");
    assert!(
        bad.is_empty(),
        "the log has errors or warnings of ours:\n{bad}"
    );
    drop(s.app);

    // cloth32: grab and cut a cloth while it runs; still a quiet log.
    let s = Session::start(&display, "cloth32", &dir);
    s.drag("1", (0.5, 0.5), (0.8, 0.3), 6);
    let springs0 = s.expect("the grab over", |st| st["held"] == 0)["springs"]
        .as_u64()
        .unwrap();
    s.x(&["keydown", "ctrl"]);
    s.drag("1", (0.3, 0.95), (0.3, 0.6), 6);
    s.x(&["keyup", "ctrl"]);
    let cut = counts(&s.expect("the cloth cut", |st| counts(st).1 < springs0)).1;
    // On the card the cloth is drawn from its buffers (a compute pass writes the meshes), and
    // a grab there still lets go.
    s.move_px(95, 179);
    s.x(&["click", "1"]);
    s.expect("drawn from the card", |st| {
        st["device"] == "gpu"
            && st["drawn_on_card"] == true
            && st["frames_drawn_on_card"].as_u64().is_some_and(|n| n > 0)
    });
    s.drag("1", (0.5, 0.5), (0.7, 0.4), 6);
    s.expect("the grab on the card over", |st| {
        st["held"] == 0 && st["device"] == "gpu" && counts(st).1 == cut
    });
    // Untouched, the card's state stays on the card: the steps go on, the positions the
    // report shows (the solver's) stay, the energy is the card's summary; the pointer moving
    // brings the state back.
    std::thread::sleep(Duration::from_secs(2));
    let quiet = s.status();
    std::thread::sleep(Duration::from_millis(1500));
    let later = s.status();
    assert_eq!(later["state_lags_card"], true, "{later}");
    assert!(later["steps"].as_u64() > quiet["steps"].as_u64());
    assert!(
        positions(&quiet) == positions(&later),
        "the state came back untouched"
    );
    assert!(later["energy"].as_f64().is_some_and(f64::is_finite));
    s.move_to(0.2, 0.2);
    s.expect("the state back for the pointer", |st| {
        positions(st) != positions(&later)
    });
    s.move_px(95, 179);
    s.x(&["click", "1"]);
    s.expect("drawn on the CPU again", |st| {
        st["device"] == "cpu" && st["drawn_on_card"] == false
    });
    let bad = bad_lines(&s.log()).join("\n");
    assert!(
        bad.is_empty(),
        "cloth32's log has errors or warnings of ours:\n{bad}"
    );
}

/// A scene's parameters outside the panel's slider ranges (all valid: damping of 250 1/s, a dt
/// of 2e-7 s, 80 Newton steps, a tearing strain of 500 %) stay as the scene set them while the
/// panel shows them, and no edit is recorded: egui's sliders clamp what they show by default,
/// which changed the scene's physics in the app, not in `hooke run`, and added an undo entry
/// nobody made.
#[test]
fn the_panel_keeps_a_scenes_values_outside_its_ranges() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some((display, _xvfb)) = gui_display(&[]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("hooke-gui-keep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("outside.ron");
    std::fs::write(
        &scene,
        "(gravity: (0.0, -9.8), damping: 250.0, ground: Some(0.0), integrator: ImplicitEuler,
          dt: 2e-7, particles: [(pos: (0.5, 0.9), pinned: true), (pos: (0.6, 0.9))],
          springs: [(a: 0, b: 1, stiffness: 1e7, rest: 0.1)], tear: Some(5.0),
          iterations: (newton: 80), start_paused: false)",
    )
    .unwrap();
    let report = dir.join("status.json");
    let log = dir.join("app.log");
    let mut app = launch(&display, scene.to_str().unwrap(), &report, &log);
    let read_log = || std::fs::read_to_string(&log).unwrap_or_default();
    // Frames drawn, and a report written after them (every 0.5 s): the panel has been shown.
    let mut first_steps = None;
    wait_for("the panel's frames", Duration::from_secs(180), || {
        if let Ok(Some(code)) = app.0.try_wait() {
            panic!("the app exited early ({code}):\n{}", read_log());
        }
        let Some(s) = status(&report) else {
            return false;
        };
        let steps = s["steps"].as_u64().unwrap_or(0);
        if s["fps"].as_f64().unwrap_or(0.0) == 0.0 || steps == 0 {
            return false;
        }
        *first_steps.get_or_insert(steps) < steps
    });
    let s = status(&report).unwrap();
    assert_eq!(s["damping"], 250.0, "damping: {s}");
    assert_eq!(s["dt"], 2e-7, "dt: {s}");
    assert_eq!(s["integrator"], "implicit-euler");
    assert_eq!(s["iterations"]["newton"], 80, "Newton steps: {s}");
    assert_eq!(s["tear"], 5.0, "tearing strain: {s}");
    assert_eq!(s["undo"], 0, "no edit was made: {s}");
    let bad = bad_lines(&read_log()).join("\n");
    assert!(bad.is_empty(), "the app's log:\n{bad}");
}

/// A moving obstacle dragged in the app keeps its own spin while held and gets its own motion
/// back when let go: a box turning at 0.8 rad/s (a scene file's `Moving`), dragged 0.1 m right
/// and 0.1 m up while the steps run, follows the cursor turning, then stays where it was let go
/// and turns on.
#[test]
fn a_dragged_moving_obstacle_keeps_its_own_motion() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some((display, _xvfb)) = gui_display(&["xdotool"]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("hooke-spinner-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("spinner.ron"),
        "(ground: Some(0.0), obstacles: [
            Moving(shape: Box(center: (0.5, 0.4), half: (0.15, 0.03)), spin: 0.8)])",
    )
    .unwrap();
    let s = Session::start_in(&display, "spinner.ron", &dir, &dir);
    if s.status()["paused"] == true {
        s.key("g");
    }
    let pose = |st: &serde_json::Value| {
        let f = |v: &serde_json::Value| v.as_f64().unwrap();
        let c = &st["obstacles"][0];
        (f(&c[0]), f(&c[1]), f(&st["obstacle_angles"][0]))
    };
    let start = pose(&s.expect("running", |st| st["paused"] == false));
    s.expect("turning", |st| pose(st).2 > start.2 + 0.1);
    // Pressed at its centre, dragged and held there.
    s.move_to(0.5, 0.4);
    s.x(&["mousedown", "1"]);
    std::thread::sleep(Duration::from_millis(200));
    for i in 1..=5 {
        let t = i as f64 / 5.0;
        s.move_to(0.5 + 0.1 * t, 0.4 + 0.1 * t);
    }
    let held = s.expect("the box at the cursor", |st| {
        let (x, y, _) = pose(st);
        (x - 0.6).abs() < 0.01 && (y - 0.5).abs() < 0.01
    });
    s.expect("turning while held", |st| pose(st).2 > pose(&held).2 + 0.1);
    s.x(&["mouseup", "1"]);
    let let_go = s.expect("let go", |st| st["paused"] == false);
    s.expect("turning where it was let go", |st| {
        let ((x, y, a), (x0, y0, a0)) = (pose(st), pose(&let_go));
        (x - x0).abs() < 1e-9 && (y - y0).abs() < 1e-9 && a > a0 + 0.1
    });
    assert!(bad_lines(&s.log()).is_empty(), "{}", s.log());
}

/// Sends `window` a close request as a window manager does (a `WM_DELETE_WINDOW` client
/// message), through libX11 from Python's ctypes: this xdotool's `windowclose` destroys the
/// window instead of asking it to close.
fn request_close(display: &str, window: &str) {
    const SCRIPT: &str = r#"
import ctypes, sys
x = ctypes.cdll.LoadLibrary("libX11.so.6")
x.XOpenDisplay.restype = ctypes.c_void_p
x.XOpenDisplay.argtypes = [ctypes.c_char_p]
x.XInternAtom.restype = ctypes.c_ulong
x.XInternAtom.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
x.XSendEvent.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_long, ctypes.c_void_p]
x.XFlush.argtypes = [ctypes.c_void_p]
class ClientMessage(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("window", ctypes.c_ulong),
                ("message_type", ctypes.c_ulong), ("format", ctypes.c_int),
                ("data", ctypes.c_long * 5)]
class Event(ctypes.Union):
    _fields_ = [("xclient", ClientMessage), ("pad", ctypes.c_long * 24)]
d = x.XOpenDisplay(None)
if not d:
    sys.exit("cannot open the display")
window = int(sys.argv[1])
e = Event()
e.xclient.type = 33  # ClientMessage
e.xclient.window = window
e.xclient.message_type = x.XInternAtom(d, b"WM_PROTOCOLS", 0)
e.xclient.format = 32
e.xclient.data[0] = x.XInternAtom(d, b"WM_DELETE_WINDOW", 0)
x.XSendEvent(d, window, 0, 0, ctypes.byref(e))
x.XFlush(d)
"#;
    let out = Command::new("python3")
        .args(["-c", SCRIPT, window])
        .env("DISPLAY", display)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "the close request was not sent: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Waits for the app to exit by itself, and returns whether it exited cleanly.
fn exits(app: &mut Killed, what: &str) -> bool {
    let mut code = None;
    wait_for(what, Duration::from_secs(30), || {
        code = app.0.try_wait().ok().flatten();
        code.is_some()
    });
    code.is_some_and(|c| c.success())
}

/// Closing the window with nothing unsaved quits at once; with an edit it asks, the keys
/// wait, Escape goes back, and "Save and quit" writes the scene under `saved/` and quits. A
/// structure built click by click was lost to the close button.
#[test]
fn closing_with_unsaved_edits_asks_first() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let Some((display, _xvfb)) = gui_display(&["xdotool", "python3"]) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("hooke-gui-quit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();

    // Nothing unsaved: the close request quits.
    let mut s = Session::start_in(&display, "empty", &dir, &dir);
    assert_eq!(s.status()["unsaved"], false);
    assert_eq!(s.x(&["getwindowname", &s.window]), "hooke: empty");
    request_close(&display, &s.window);
    assert!(exits(&mut s.app, "the app to quit"), "{}", s.log());

    // One particle added: the close request asks first.
    let mut s = Session::start_in(&display, "empty", &dir, &dir);
    s.move_to(0.5, 0.8);
    s.x(&["click", "1"]);
    s.expect("a particle, unsaved", |st| {
        st["particles"] == 1 && st["unsaved"] == true
    });
    // The title marks it, as editors do.
    wait_for("the title's mark", Duration::from_secs(10), || {
        s.x(&["getwindowname", &s.window]) == "hooke: empty *"
    });
    request_close(&display, &s.window);
    s.expect("the prompt", |st| st["quit_prompt"] == true);
    // The canvas's keys wait while it is up: C does not clear.
    s.key("c");
    std::thread::sleep(Duration::from_millis(500));
    let st = s.expect("a report after the key", |_| true);
    assert_eq!(st["particles"], 1, "C cleared behind the prompt: {st}");
    assert!(s.app.0.try_wait().unwrap().is_none(), "the app quit");
    s.key("Escape");
    s.expect("back from the prompt", |st| st["quit_prompt"] == false);

    // Save and quit: its button, where the modal sits (centred in the window).
    request_close(&display, &s.window);
    let st = s.expect("the prompt again", |st| st["quit_prompt"] == true);
    let view = &st["view"];
    let (center, panel) = (&view["center"], view["panel_width"].as_f64().unwrap());
    let width = panel + 2.0 * (center[0].as_f64().unwrap() - panel);
    let height = 2.0 * center[1].as_f64().unwrap();
    s.move_px((width / 2.0) as i64 - 148, (height / 2.0) as i64 + 32);
    s.x(&["click", "1"]);
    assert!(exits(&mut s.app, "the app to save and quit"), "{}", s.log());
    let saved = dir.join("saved/empty-1.ron");
    let scene =
        hooke::scene::LoadedScene::read(&saved).unwrap_or_else(|e| panic!("the saved scene: {e}"));
    assert_eq!(scene.expanded().particles.len(), 1);
    let bad = bad_lines(&s.log()).join("\n");
    assert!(bad.is_empty(), "the app's log:\n{bad}");
    let _ = std::fs::remove_dir_all(&dir);
}
