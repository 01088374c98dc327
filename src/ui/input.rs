//! The keyboard: every key binding of the app (the table is [`super::controls::CONTROLS`]).

use super::actions::{redo, reset, save, undo};
use super::controls::HelpOverlay;
use super::edit;
use super::pick::Picking;
use super::pointer::{Cursor, modifiers};
use super::view::{CanvasView, scene_box};
use crate::scene::CurrentScene;
use crate::sim::*;
use bevy::prelude::*;
use bevy_egui::input::EguiWantsInput;

/// Particles and springs: what C clears.
type ParticleOrSpring = Or<(With<Particle>, With<Spring>)>;

/// G / Space: pause or resume. N: one step while paused. R: reset. S: save. C: clear. F: fit.
/// H / ?: help. Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y: undo, redo.
#[allow(clippy::too_many_arguments)]
pub fn keyboard(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
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
    let (shift, ctrl) = modifiers(&keys);
    let pressed = |k: KeyCode| keys.just_pressed(k);
    if ctrl {
        if pressed(KeyCode::KeyZ) && !shift {
            commands.queue(undo);
        } else if pressed(KeyCode::KeyZ) || pressed(KeyCode::KeyY) {
            commands.queue(redo);
        }
        return;
    }
    if pressed(KeyCode::KeyG) || pressed(KeyCode::Space) {
        params.paused = !params.paused;
    }
    if pressed(KeyCode::KeyN) && params.paused {
        commands.queue(|world: &mut World| {
            world.resource_mut::<SimParams>().paused = false;
            advance(world, 1);
            world.resource_mut::<SimParams>().paused = true;
        });
    }
    if pressed(KeyCode::KeyR) {
        commands.queue(reset);
    }
    if pressed(KeyCode::KeyS) {
        commands.queue(save);
    }
    if pressed(KeyCode::KeyC) && !everything.is_empty() {
        edit::clear(&mut commands, everything.iter());
    }
    if pressed(KeyCode::KeyF) {
        view.fit = Some(scene_box(&solver.x));
    }
    if pressed(KeyCode::KeyH) || (pressed(KeyCode::Slash) && shift) {
        help.0 = !help.0;
    }
}

/// P: pin or free the particle under the cursor. X / Delete: delete it and its springs.
#[allow(clippy::too_many_arguments)]
pub fn particle_keys(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    egui: Res<EguiWantsInput>,
    cursor: Cursor,
    scene: Option<Res<CurrentScene>>,
    solver: Res<Solver>,
    mut picking: ResMut<Picking>,
    pinned: Query<Has<Pinned>, With<Particle>>,
    springs: Query<(Entity, &Spring)>,
) {
    let pin = keys.just_pressed(KeyCode::KeyP);
    let delete = keys.any_just_pressed([KeyCode::KeyX, KeyCode::Delete]);
    if !(pin || delete) || egui.wants_any_keyboard_input() || modifiers(&keys).1 {
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
        return;
    };
    let Ok(is_pinned) = pinned.get(particle) else {
        return;
    };
    if pin {
        edit::toggle_pin(&mut commands, particle, is_pinned);
    } else {
        edit::delete_particle(&mut commands, particle, springs);
    }
}
