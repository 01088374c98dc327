//! Scripted runs of the app (used by the GUI test and to make the screenshots in `docs/images/`):
//! a screenshot after a delay, a status file, quitting after a delay.

use super::controls::HelpOverlay;
use super::history::History;
use super::quit::QuitPrompt;
use super::stats::LiveStats;
use super::view::CanvasView;
use crate::sim::{Attraction, Particle, Pinned, SimClock, SimParams, Solver, Tearing};
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, save_to_disk};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Resource, Debug, Clone, Default)]
/// Options of a scripted run of the app (hidden command-line flags).
pub struct AppOptions {
    /// Run even if the scene starts paused.
    pub start_running: bool,
    /// Save a PNG of the window to this path after this many seconds.
    pub screenshot: Option<(PathBuf, f64)>,
    /// Quit after this many seconds.
    pub exit_after: Option<f64>,
    /// Write a JSON status line to this file twice a second.
    pub report: Option<PathBuf>,
    /// Start with the panel's GPU switch on.
    pub gpu: bool,
}

#[derive(Default)]
pub struct DriveState {
    started: Option<Instant>,
    screenshot_taken: bool,
    last_report: Option<Instant>,
}

/// What the status report reads besides the simulation.
#[derive(SystemParam)]
pub struct AppState<'w, 's> {
    history: Res<'w, History>,
    help: Res<'w, HelpOverlay>,
    quit: Res<'w, QuitPrompt>,
    tearing: Res<'w, Tearing>,
    attraction: Res<'w, Attraction>,
    pinned: Query<'w, 's, (), (With<Particle>, With<Pinned>)>,
    obstacles: Query<'w, 's, &'static crate::sim::ObstaclePose, With<crate::sim::Obstacle>>,
    card: Res<'w, crate::sim::gpu::CardStep>,
    picture: Res<'w, super::card_draw::CardPicture>,
    threads: Res<'w, crate::sim::SolverThreads>,
}

/// Scenes up to this many particles list their positions in the status report.
const REPORT_POSITIONS: usize = 2000;

#[allow(clippy::too_many_arguments)]
pub fn drive(
    mut commands: Commands,
    view: Res<CanvasView>,
    options: Res<AppOptions>,
    mut state: Local<DriveState>,
    mut exit: MessageWriter<AppExit>,
    solver: Res<Solver>,
    clock: Res<SimClock>,
    params: Res<SimParams>,
    stats: Res<LiveStats>,
    app: AppState,
) {
    let started = *state.started.get_or_insert_with(Instant::now);
    let elapsed = started.elapsed().as_secs_f64();
    if let Some((path, after)) = &options.screenshot
        && !state.screenshot_taken
        && elapsed >= *after
    {
        state.screenshot_taken = true;
        commands
            .spawn(Screenshot::primary_window())
            .observe(save_to_disk(path.clone()));
    }
    if let Some(path) = &options.report
        && state
            .last_report
            .is_none_or(|t| t.elapsed() > Duration::from_millis(500))
    {
        state.last_report = Some(Instant::now());
        let line = serde_json::json!({
            "particles": solver.particle_count(),
            "springs": solver.spring_count(),
            "steps": clock.steps,
            "sim_time": clock.time,
            "paused": params.paused,
            "fps": stats.fps,
            "real_time_factor": stats.real_time_factor,
            "elapsed": elapsed,
            "pinned": app.pinned.iter().len(),
            // Each obstacle's centre (in no particular order).
            "obstacles": app.obstacles.iter().map(|p| [p.center.x, p.center.y]).collect::<Vec<_>>(),
            // Their rotations, rad, in the same order.
            "obstacle_angles": app.obstacles.iter().map(|p| p.angle).collect::<Vec<_>>(),
            "held": solver.kinematic,
            "springs_torn": app.tearing.torn,
            "tear": params.tear,
            "attracting": app.attraction.active_at.is_some(),
            "external_force": solver.external_active,
            "undo": app.history.undo.len(),
            "redo": app.history.redo.len(),
            "unsaved": app.history.unsaved(),
            "quit_prompt": app.quit.0,
            "help": app.help.0,
            "stiffness_override": params.stiffness_override,
            "damping": params.damping,
            "dt": params.dt,
            "integrator": params.integrator.cli_name(),
            "iterations": params.iterations,
            // Where the steps run: "gpu" while the panel's switch has them on the card.
            "device": if app.card.active() { "gpu" } else { "cpu" },
            "adapter": app.card.adapter(),
            "gpu_wanted": app.card.wanted,
            "gpu_why_not": app.card.why_not,
            // Whether the solver's state (and `positions`) lag the card's: with the state read
            // on demand, while nothing in the window wants it.
            "state_lags_card": app.card.behind(),
            "energy": solver.energy_now(params.gravity, &app.threads).total(),
            // Whether the meshes are drawn from the card's buffers, and frames drawn so.
            "drawn_on_card": app.picture.active(),
            "frames_drawn_on_card": app.picture.frames_drawn(),
            // In scene order (creation order), for scenes up to REPORT_POSITIONS particles.
            "positions": (solver.particle_count() <= REPORT_POSITIONS)
                .then(|| solver.x.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>()),
            // The window-to-world mapping, so scripts can click at world coordinates:
            // window = center + (world - world_center) * scale, with y flipped.
            "view": { "scale": view.scale, "center": [view.center.x, view.center.y],
                      "world_center": [view.world_center.x, view.world_center.y],
                      "panel_width": view.panel_width },
        });
        // A status file that cannot be written only loses the status, never the app. Written
        // beside it and renamed over it, so that a reader never sees half a line (the GUI test
        // once read a report mid-write and found no JSON).
        let mut partial = path.clone().into_os_string();
        partial.push(".partial");
        if std::fs::write(&partial, format!("{line}\n")).is_ok() {
            let _ = std::fs::rename(&partial, path);
        }
    }
    if options.exit_after.is_some_and(|t| elapsed >= t) {
        exit.write(AppExit::Success);
    }
}
