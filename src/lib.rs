//! hooke: an interactive 2D mass-spring simulator on Bevy.
//!
//! * [`sim`]: the headless simulation ([`sim::SimPlugin`]): particles and springs as entities,
//!   a packed solver, fixed-tick systems in ordered sets.
//! * [`scene`]: the RON scene format, generators, validation and loading.
//! * [`runner`]: headless runs of a scene (`hooke run`).
//! * [`bench`]: measured reports (`hooke bench ...`).
//! * `ui` (feature `gui`): the desktop app ([`ui::AppPlugin`]): panel, pointer gestures (grab,
//!   add, cut, attract), keyboard edits, undo history, zoom and pan.
//!
//! Outside forces enter through one input: each particle's [`sim::ExternalForce`], which the
//! solver adds wherever it evaluates forces (every stage of every integrator). The app's mouse
//! attraction writes it; so can any user system (wind, a field).

pub mod bench;
pub mod runner;
pub mod scene;
pub mod sim;
#[cfg(feature = "gui")]
pub mod ui;

pub use sim::SimPlugin;
#[cfg(feature = "gui")]
pub use ui::AppPlugin;

use bevy::prelude::*;

/// A headless Bevy app with the simulation and nothing else (no window, no GPU), stepped with
/// [`sim::advance`] or `app.update()`.
pub fn headless_app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, SimPlugin));
    app
}

/// A headless app with the scene loaded, running (not paused) and packed into the solver: ready
/// to step, and its state readable before the first step.
pub fn running_app(loaded: &scene::LoadedScene) -> Result<App, String> {
    let mut app = headless_app();
    let world = app.world_mut();
    scene::load_into_world(world, loaded);
    world.resource_mut::<sim::SimParams>().paused = false;
    sim::pack(world)?;
    Ok(app)
}
