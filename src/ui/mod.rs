//! The desktop app: a window onto the simulation, an egui control panel, mouse and keyboard.

mod actions;
mod automation;
mod card_draw;
mod controls;
mod draw;
mod drop;
mod edit;
mod events;
mod history;
mod input;
mod pace;
mod panel;
mod parameters;
mod pick;
mod plots;
mod pointer;
mod predict;
mod quit;
mod readouts;
mod stats;
mod title;
mod view;

use crate::scene::{LoadedScene, load_into_world};
use crate::sim::{SimParams, SimPlugin, tear};
use bevy::prelude::*;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::window::WindowResolution;
use bevy_egui::{EguiPlugin, EguiPreUpdateSet, EguiPrimaryContextPass};
use std::path::PathBuf;

pub use automation::AppOptions;

/// Everything the app adds on top of [`SimPlugin`]: view, drawing, input, panel.
pub struct AppPlugin {
    /// The scene to open.
    pub scene: LoadedScene,
    /// How to run (start running, screenshot, report, exit).
    pub options: AppOptions,
}

impl Plugin for AppPlugin {
    fn build(&self, app: &mut App) {
        let scene = self.scene.clone();
        let start_running = self.options.start_running;
        let gpu = self.options.gpu;
        app.add_plugins(card_draw::CardDrawPlugin);
        app.insert_resource(ClearColor(draw::BACKGROUND))
            .insert_resource(self.options.clone())
            .init_resource::<view::CanvasView>()
            .init_resource::<stats::LiveStats>()
            .init_resource::<parameters::PanelState>()
            .init_resource::<actions::SceneList>()
            .init_resource::<history::History>()
            .init_resource::<pick::Picking>()
            .init_resource::<pointer::Gesture>()
            .init_resource::<events::PressedAt>()
            .init_resource::<events::KeyPresses>()
            .init_resource::<controls::HelpOverlay>()
            .init_resource::<drop::FilesOver>()
            .init_resource::<quit::QuitPrompt>()
            .init_resource::<plots::Timeline>()
            .init_resource::<crate::sim::watch::EnergyWatch>()
            .init_resource::<crate::sim::Stability>()
            .add_systems(Startup, (view::spawn_camera, draw::spawn_batches))
            .add_systems(Startup, move |world: &mut World| {
                load_into_world(world, &scene);
                if start_running {
                    world.resource_mut::<SimParams>().paused = false;
                }
                world.resource_mut::<crate::sim::gpu::CardStep>().wanted = gpu;
            })
            // Before the frame's input is handled: the card's state where input wants it.
            .add_systems(
                PreUpdate,
                (
                    events::read_the_card_on_input,
                    crate::sim::gpu::catch_up_while_reading,
                )
                    .chain(),
            )
            .add_systems(
                PreUpdate,
                pace::drop_unchanged_modifiers
                    .after(EguiPreUpdateSet::ProcessInput)
                    .before(EguiPreUpdateSet::BeginPass),
            )
            .add_systems(
                EguiPrimaryContextPass,
                (
                    panel::side_panel,
                    controls::help_overlay,
                    controls::empty_canvas_hint,
                    drop::drop_hint,
                    quit::quit_prompt,
                )
                    .chain(),
            )
            // The state before a tear, for undo: after the springs are found, before they go.
            .add_systems(
                FixedUpdate,
                (|w: &mut World| history::record_burst(w, "tear", None))
                    .after(tear::find_torn_springs)
                    .before(tear::remove_torn_springs)
                    .run_if(tear::tears_pending),
            )
            // The same before the springs the card tore go (`sim::gpu`'s reads on demand).
            .add_systems(
                FixedUpdate,
                (|w: &mut World| history::record_burst(w, "tear", None))
                    .after(crate::sim::gpu::receive_from_card)
                    .before(tear::remove_springs_torn_on_card)
                    .run_if(tear::tears_pending),
            )
            .add_systems(
                Update,
                (
                    (
                        events::track_presses,
                        view::zoom_and_pan,
                        view::fit_camera,
                        // While the quit prompt is up, keys are the prompt's (Escape).
                        input::keyboard.run_if(quit::no_prompt),
                        input::particle_keys.run_if(quit::no_prompt),
                        pointer::press,
                        pointer::drag,
                        pointer::attract,
                    )
                        .chain(),
                    view::match_antialiasing.run_if(resource_added::<RenderAdapterInfo>),
                    hand_over_the_card.run_if(resource_added::<RenderAdapterInfo>),
                    stats::measure,
                    stats::estimate_stability,
                    plots::sample.after(stats::estimate_stability),
                    automation::drive,
                    drop::follow_file_drags.run_if(quit::no_prompt),
                    quit::close_requested,
                    title::window_title,
                    pace::pace_frames,
                    draw::update_batches.after(pointer::drag),
                    draw::draw_frame.after(pointer::attract),
                    draw::draw_obstacles,
                    draw::draw_bodies,
                ),
            );
        // Rigid bodies: avian's plugins, coupled. Without a body in the scene nothing of it
        // runs (`sim::avian`'s clock).
        app.add_plugins((
            avian2d::prelude::PhysicsPlugins::default(),
            crate::sim::avian::HookeAvianPlugin,
        ));
    }
}

/// Opens the window and runs the app until it is closed.
pub fn run_app(scene: LoadedScene, options: AppOptions) {
    explain_a_missing_display();
    let title = title::title(&scene.name(), false);
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window {
                title,
                name: Some("hooke".into()),
                resolution: WindowResolution::new(1280, 800),
                ..default()
            }),
            // A close request asks first when there are unsaved edits (`quit`).
            close_when_requested: false,
            ..default()
        }))
        .add_plugins(EguiPlugin::default())
        .add_plugins(SimPlugin)
        .add_plugins(AppPlugin { scene, options })
        .run();
}

/// Where no window can open (no X display: `DISPLAY` unset, or a display that does not answer),
/// bevy_winit panics as it builds its event loop. That one panic becomes a line naming the
/// cause and what runs without a display, with exit code 2 (bad input, as elsewhere); every
/// other panic goes to the default hook.
fn explain_a_missing_display() {
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(why) = message.strip_prefix("Failed to build event loop") {
            // winit's error, out of the `: Os(OsError { line, file, error: … })` around it.
            let why = why
                .rsplit_once("error: ")
                .and_then(|(_, e)| e.strip_suffix(" })"))
                .unwrap_or(why.trim_start_matches(": "));
            let cause = match std::env::var("DISPLAY").unwrap_or_default().as_str() {
                "" => "DISPLAY is not set".to_string(),
                d => format!("the X display {d} does not answer ({why})"),
            };
            eprintln!(
                "hooke: no window can open here: {cause}. `hooke run --scene NAME` runs a \
                 scene without a window, and `xvfb-run hooke` runs the app on a virtual screen."
            );
            std::process::exit(2);
        }
        default_hook(info);
    }));
}

/// Where "Save scene" writes: `saved/<scene>-<n>.ron` in the working directory.
fn save_path(name: &str) -> PathBuf {
    let dir = PathBuf::from("saved");
    (1..)
        .map(|n| dir.join(format!("{name}-{n}.ron")))
        .find(|p| !p.exists())
        .unwrap_or_else(|| dir.join(format!("{name}.ron")))
}

/// Gives the simulation the renderer's device and queue, so that the panel's GPU switch steps
/// on the same card the app draws with.
fn hand_over_the_card(
    device: Res<bevy::render::renderer::RenderDevice>,
    queue: Res<bevy::render::renderer::RenderQueue>,
    info: Res<RenderAdapterInfo>,
    mut card: ResMut<crate::sim::gpu::CardStep>,
) {
    let queue: &wgpu::Queue = &queue.0;
    card.use_card(crate::solver::gpu::Gpu::from_device(
        device.wgpu_device().clone(),
        queue.clone(),
        wgpu::AdapterInfo::clone(&info.0),
    ));
    // A frame never waits for the card's state: it comes back while the frame goes on, and
    // only while input wants it; other ticks bring back the card's summary.
    card.background_reads = true;
    card.on_demand = true;
}
