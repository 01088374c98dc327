//! The list of controls, shown by the help overlay (H or ?) and in the panel, and the line an
//! empty canvas shows.

use bevy::prelude::*;
use bevy_egui::{EguiContexts, egui};

/// Every control: (input, action). `docs/app.md`'s controls table says the same.
pub const CONTROLS: &[(&str, &str)] = &[
    (
        "left press on a particle",
        "grab it and drag; release throws it",
    ),
    (
        "left click on empty canvas",
        "add a particle, joined to those within the click radius (a drag adds none)",
    ),
    ("shift + left click", "add a pinned particle"),
    ("right button held", "attract particles within the circle"),
    ("P (cursor on a particle)", "pin or free it"),
    ("X or Delete (on a particle)", "delete it and its springs"),
    ("ctrl + left drag", "cut every spring the cursor crosses"),
    (
        "O + left drag",
        "build a circle obstacle: centre, then radius",
    ),
    ("B + left drag", "build a box obstacle: corner to corner"),
    ("L + left drag", "build a segment obstacle: end to end"),
    (
        "J + left drag",
        "draw a ball (a ring filled with gas): centre, then radius",
    ),
    (
        "K + left drag",
        "drop a crate (a rigid body): corner to corner",
    ),
    (
        "left press on an obstacle",
        "move it; what rests on it follows by friction",
    ),
    ("X or Delete (on an obstacle)", "delete it"),
    ("C", "clear the canvas"),
    ("ctrl+Z", "undo"),
    ("ctrl+shift+Z or ctrl+Y", "redo"),
    ("mouse wheel", "zoom about the cursor"),
    ("middle drag", "pan"),
    ("F", "fit the scene in view"),
    ("G or Space", "run or pause"),
    ("N", "one step while paused"),
    ("R", "reset the scene"),
    ("S", "save to saved/"),
    ("close the window", "quit; asks first if edits are unsaved"),
    ("H or ?", "show or hide this list"),
];

/// Whether the help overlay is shown.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub struct HelpOverlay(pub bool);

/// The controls as a two-column grid.
pub fn controls_grid(ui: &mut egui::Ui, id: &str) {
    egui::Grid::new(id)
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            for (input, action) in CONTROLS {
                ui.monospace(*input);
                ui.label(*action);
                ui.end_row();
            }
        });
}

/// The overlay, over the canvas.
pub fn help_overlay(
    mut contexts: EguiContexts,
    mut help: ResMut<HelpOverlay>,
    view: Res<super::view::CanvasView>,
) -> Result {
    if !help.0 {
        return Ok(());
    }
    let ctx = contexts.ctx_mut()?;
    let mut open = true;
    egui::Window::new("Controls")
        .open(&mut open)
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [view.canvas_offset(), 0.0])
        .show(ctx, |ui| {
            controls_grid(ui, "help-controls");
            ui.small("H or ? closes this.");
        });
    if !open {
        help.0 = false;
    }
    Ok(())
}

/// What an empty canvas says, under its middle: the first things to do, and where the rest are.
pub const EMPTY_CANVAS: &str =
    "Click to add a particle (shift: pinned) · J + drag: a ball · G: run · H: every control";

/// The line on an empty canvas (no particle, no obstacle, no body), so that the app opened with
/// no scene does not greet a newcomer with a blank box: it goes with the first particle or
/// obstacle, and while the help overlay or a file drop's line is up. It takes no input, so a
/// click under it still adds a particle.
pub fn empty_canvas_hint(
    mut contexts: EguiContexts,
    particles: Query<(), With<crate::sim::Particle>>,
    built: Query<(), With<crate::sim::Obstacle>>,
    obstacles: Res<crate::sim::Obstacles>,
    help: Res<HelpOverlay>,
    over: Res<super::drop::FilesOver>,
    view: Res<super::view::CanvasView>,
) -> Result {
    let empty = particles.is_empty() && built.is_empty() && obstacles.placed().is_empty();
    if !empty || help.0 || !over.0.is_empty() {
        return Ok(());
    }
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("empty-canvas-hint"))
        .anchor(egui::Align2::CENTER_BOTTOM, [view.canvas_offset(), -120.0])
        .order(egui::Order::Background)
        .interactable(false)
        .show(ctx, |ui| {
            let text = egui::RichText::new(EMPTY_CANVAS).color(ui.visuals().weak_text_color());
            ui.add(egui::Label::new(text).wrap_mode(egui::TextWrapMode::Extend));
        });
    Ok(())
}
