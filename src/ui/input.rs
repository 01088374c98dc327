//! The keyboard: every key binding of the app (the table is [`super::controls::CONTROLS`]).

use super::actions::{redo, reset, save, undo};
use super::controls::HelpOverlay;
use super::edit;
use super::events::KeyPresses;
use super::pick::Picking;
use super::pointer::Cursor;
use super::view::{CanvasView, scene_box};
use crate::scene::CurrentScene;
use crate::sim::*;
use bevy::prelude::*;
use bevy_egui::input::EguiWantsInput;

/// Particles and springs: what C clears.
type ParticleOrSpring = Or<(With<Particle>, With<Spring>, With<PressureBody>)>;

/// G / Space: pause or resume. N: one step while paused. R: reset. S: save. C: clear. F: fit.
/// H / ?: help. Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y: undo, redo.
///
/// Every press counts, in the order it was made ([`KeyPresses`]): a quick double ctrl+Z
/// undoes twice, G G in one frame pauses and resumes. Undo and redo follow the system's key
/// repeat while held; the others take only real presses.
#[allow(clippy::too_many_arguments)]
pub fn keyboard(
    mut commands: Commands,
    presses: Res<KeyPresses>,
    egui: Res<EguiWantsInput>,
    mut params: ResMut<SimParams>,
    mut view: ResMut<CanvasView>,
    mut help: ResMut<HelpOverlay>,
    solver: Res<Solver>,
    everything: Query<Entity, ParticleOrSpring>,
) {
    if egui.wants_any_keyboard_input() {
        return;
    }
    let mut cleared = false;
    for press in &presses.0 {
        if press.ctrl {
            match press.key {
                KeyCode::KeyZ if !press.shift => commands.queue(undo),
                KeyCode::KeyZ | KeyCode::KeyY => commands.queue(redo),
                _ => {}
            }
            continue;
        }
        if press.repeat {
            continue;
        }
        match press.key {
            KeyCode::KeyG | KeyCode::Space => params.paused = !params.paused,
            KeyCode::KeyN if params.paused => commands.queue(|world: &mut World| {
                world.resource_mut::<SimParams>().paused = false;
                advance(world, 1);
                world.resource_mut::<SimParams>().paused = true;
            }),
            KeyCode::KeyR => commands.queue(reset),
            KeyCode::KeyS => commands.queue(save),
            // Once a frame: the query still lists what the first clear removes.
            KeyCode::KeyC if !cleared && !everything.is_empty() => {
                edit::clear(&mut commands, everything.iter());
                cleared = true;
            }
            KeyCode::KeyF => view.fit = Some(scene_box(&solver.x)),
            KeyCode::KeyH => help.0 = !help.0,
            KeyCode::Slash if press.shift => help.0 = !help.0,
            _ => {}
        }
    }
}

/// P: pin or free the particle under the cursor. X / Delete: delete it and its springs, or,
/// with no particle there, the obstacle under the cursor.
#[allow(clippy::too_many_arguments)]
pub fn particle_keys(
    mut commands: Commands,
    presses: Res<KeyPresses>,
    egui: Res<EguiWantsInput>,
    cursor: Cursor,
    scene: Option<Res<CurrentScene>>,
    solver: Res<Solver>,
    mut picking: ResMut<Picking>,
    pinned: Query<Has<Pinned>, With<Particle>>,
    springs: Query<(Entity, &Spring)>,
    obstacles: super::pointer::ObstacleQuery,
) {
    // The first such press of the frame: the particle under the cursor is picked from the
    // frame's positions, which a second edit in the same frame would not see change.
    let first = presses.0.iter().find(|p| {
        !p.ctrl && !p.repeat && matches!(p.key, KeyCode::KeyP | KeyCode::KeyX | KeyCode::Delete)
    });
    let Some(press) = first else {
        return;
    };
    if egui.wants_any_keyboard_input() {
        return;
    }
    let Some(at) = cursor.on_canvas() else {
        return;
    };
    let cell = scene
        .and_then(|s| s.0.scene.click)
        .unwrap_or_default()
        .radius;
    let Some(particle) = picking.nearest(&solver, at, cursor.pick_radius(), cell) else {
        // No particle there: X or Delete on an obstacle deletes it.
        if press.key != KeyCode::KeyP
            && let Some((obstacle, _)) =
                super::pointer::obstacle_at(&obstacles, at, cursor.pick_radius())
        {
            edit::delete_obstacle(&mut commands, obstacle);
        }
        return;
    };
    let Ok(is_pinned) = pinned.get(particle) else {
        return;
    };
    if press.key == KeyCode::KeyP {
        edit::toggle_pin(&mut commands, particle, is_pinned);
    } else {
        edit::delete_particle(&mut commands, particle, springs);
    }
}
