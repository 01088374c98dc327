//! Closing the window with edits that are not saved asks first: save and quit, quit without
//! saving, or go back. A structure built click by click is not lost to a stray click on the
//! window's close button. With nothing unsaved the window closes at once, as it always did.

use super::actions;
use super::history::History;
use bevy::prelude::*;
use bevy::window::WindowCloseRequested;
use bevy_egui::{EguiContexts, egui};

/// Whether the quit prompt is shown (the keyboard's bindings wait while it is).
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub struct QuitPrompt(pub bool);

/// Run condition: the quit prompt is not shown.
pub fn no_prompt(prompt: Res<QuitPrompt>) -> bool {
    !prompt.0
}

/// A request to close the window (its close button, the window manager) quits at once when
/// nothing is unsaved, and otherwise shows the prompt. (The app's `WindowPlugin` leaves these
/// requests to this system.)
pub fn close_requested(
    mut requests: MessageReader<WindowCloseRequested>,
    history: Res<History>,
    mut prompt: ResMut<QuitPrompt>,
    mut exit: MessageWriter<AppExit>,
) {
    if requests.read().count() == 0 {
        return;
    }
    if history.unsaved() {
        prompt.0 = true;
    } else {
        exit.write(AppExit::Success);
    }
}

/// What the user chose in the prompt.
enum Choice {
    SaveAndQuit,
    Quit,
    Back,
}

/// The prompt: a modal over the whole window. Escape or a click beside it goes back.
pub fn quit_prompt(
    mut contexts: EguiContexts,
    mut commands: Commands,
    mut prompt: ResMut<QuitPrompt>,
    history: Res<History>,
    mut exit: MessageWriter<AppExit>,
) -> Result {
    if !prompt.0 {
        return Ok(());
    }
    let ctx = contexts.ctx_mut()?;
    let mut choice = None;
    let modal = egui::Modal::new(egui::Id::new("quit prompt")).show(ctx, |ui| {
        ui.set_width(380.0);
        ui.heading("Quit hooke?");
        ui.label("The scene has edits that are not saved.");
        if matches!(history.undo.back().map(|e| e.label), Some("load" | "reset")) {
            ui.small(
                "Edits from before the last load or reset are in the undo history: \
                 go back, then ctrl+Z.",
            );
        }
        ui.small("Save writes what is on screen to saved/, as S does.");
        ui.add_space(8.0);
        ui.horizontal(|ui| {
            if ui.button("Save and quit").clicked() {
                choice = Some(Choice::SaveAndQuit);
            }
            if ui.button("Quit without saving").clicked() {
                choice = Some(Choice::Quit);
            }
            if ui.button("Back").clicked() {
                choice = Some(Choice::Back);
            }
        });
    });
    if choice.is_none() && modal.should_close() {
        choice = Some(Choice::Back);
    }
    match choice {
        Some(Choice::SaveAndQuit) => {
            prompt.0 = false;
            // A failed save stays open, with the panel saying why.
            commands.queue(|world: &mut World| {
                if actions::try_save(world) {
                    world.write_message(AppExit::Success);
                }
            });
        }
        Some(Choice::Quit) => {
            exit.write(AppExit::Success);
        }
        Some(Choice::Back) => prompt.0 = false,
        None => {}
    }
    Ok(())
}
