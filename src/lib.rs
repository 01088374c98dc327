//! hooke: an interactive 2D mass-spring simulator on Bevy.
//!
//! * [`sim`]: the headless simulation ([`sim::SimPlugin`]): particles and springs as entities,
//!   a packed solver, fixed-tick systems in ordered sets.
//! * [`scene`]: the RON scene format, generators, validation and loading.
//! * [`runner`]: headless runs of a scene (`hooke run`).
//! * [`bench`]: measured reports (`hooke bench ...`).
//! * `ui` (feature `gui`): the desktop app ([`ui::AppPlugin`]).

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
