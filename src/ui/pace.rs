//! Frames only while something moves. While the simulation runs the app draws continuously;
//! paused, it waits for input (or [`IDLE_WAIT`]) instead of drawing an unchanging picture
//! sixty times a second. Measured under Xvfb with software rendering, the paused empty canvas
//! took 1.5 of the machine's two cores at 61–64 frames/s, and takes 0.13 at 4 (`docs/app.md` has
//! the figures).
//!
//! Waiting takes two things: the window's update mode ([`pace_frames`]), and an egui that does
//! not ask for a frame every frame. bevy_egui hands egui the modifier keys' state as an event
//! on every frame, changed or not, and egui repaints at once for any event
//! ([`drop_unchanged_modifiers`]).

use crate::sim::SimParams;
use bevy::prelude::*;
use bevy::winit::{UpdateMode, WinitSettings};
use bevy_egui::{EguiInput, egui};
use std::time::Duration;

/// How long a paused app waits for input before it updates anyway: the status report (every
/// 0.5 s), a stability estimate still due and the scripted timers run at least this often.
pub const IDLE_WAIT: Duration = Duration::from_millis(250);

/// The update modes for a running or a paused simulation.
fn modes(paused: bool) -> (UpdateMode, UpdateMode) {
    match paused {
        // Input wakes the app at once (a key, the mouse); nothing else needs a frame.
        true => (
            UpdateMode::reactive(IDLE_WAIT),
            UpdateMode::reactive_low_power(IDLE_WAIT),
        ),
        false => {
            let game = WinitSettings::game();
            (game.focused_mode, game.unfocused_mode)
        }
    }
}

/// Sets the window's update mode from the run state (written only when it changes).
pub fn pace_frames(params: Res<SimParams>, mut winit: ResMut<WinitSettings>) {
    let (focused, unfocused) = modes(params.paused);
    if winit.focused_mode != focused || winit.unfocused_mode != unfocused {
        winit.focused_mode = focused;
        winit.unfocused_mode = unfocused;
    }
}

/// Drops the modifier keys' state from a frame's egui input when it is all the input and
/// unchanged since it was last handed on. egui keeps the modifiers from pass to pass, so it
/// loses nothing; with any other event in the frame (a key, the pointer, the window losing
/// focus, which clears egui's modifiers) the state goes through as bevy_egui wrote it.
pub fn drop_unchanged_modifiers(
    mut inputs: Query<&mut EguiInput>,
    mut last: Local<Option<egui::Modifiers>>,
) {
    for mut input in &mut inputs {
        let only_modifiers = input
            .events
            .iter()
            .all(|e| matches!(e, egui::Event::ModifiersChanged(_)));
        let newest = input.events.iter().rev().find_map(|e| match e {
            egui::Event::ModifiersChanged(m) => Some(*m),
            _ => None,
        });
        if only_modifiers && newest.is_some() && newest == *last {
            input.events.clear();
        }
        if newest.is_some() {
            *last = newest;
        }
    }
}
