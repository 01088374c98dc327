//! The keyboard: every key binding of the app (the table is [`super::controls::CONTROLS`]).

use super::controls::HelpOverlay;
use super::edit;
use super::history;
use super::pick::Picking;
use super::pointer::{Cursor, modifiers};
use super::view::{CanvasView, scene_box};
use crate::scene::{CurrentScene, load_into_world, snapshot, to_ron};
use crate::sim::*;
use bevy::prelude::*;
use bevy_egui::input::EguiWantsInput;

/// Particles and springs: what C clears.
type ParticleOrSpring = Or<(With<Particle>, With<Spring>)>;

/// A message for the panel after a keyboard or button action: (text, is an error).
#[derive(Resource, Debug, Clone, Default)]
pub struct Notice(pub Option<(String, bool)>);

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

fn undo(world: &mut World) {
    let text = match history::undo(world) {
        Some(label) => format!("undid {label}"),
        None => "nothing to undo".into(),
    };
    world.insert_resource(Notice(Some((text, false))));
}

fn redo(world: &mut World) {
    let text = match history::redo(world) {
        Some(label) => format!("redid {label}"),
        None => "nothing to redo".into(),
    };
    world.insert_resource(Notice(Some((text, false))));
}

/// Reloads the current scene as it was loaded (an edit: undo takes it back).
pub fn reset(world: &mut World) {
    if let Some(scene) = world.get_resource::<CurrentScene>().map(|s| s.0.clone()) {
        history::record(world, "reset");
        load_into_world(world, &scene);
    }
}

/// Saves what is on screen as an explicit scene file under `saved/`, and lists it in the
/// scene picker.
pub fn save(world: &mut World) {
    let name = world
        .get_resource::<CurrentScene>()
        .map(|s| s.0.name())
        .unwrap_or_else(|| "scene".into());
    let scene = snapshot(world);
    let path = super::save_path(&name);
    let result = to_ron(&scene).map_err(|e| e.to_string()).and_then(|text| {
        std::fs::create_dir_all(path.parent().unwrap_or(&path)).map_err(|e| e.to_string())?;
        std::fs::write(&path, text).map_err(|e| e.to_string())
    });
    let notice = match result {
        Ok(()) => (format!("saved {}", path.display()), false),
        Err(e) => (format!("could not save {}: {e}", path.display()), true),
    };
    if let Some(mut panel) = world.get_resource_mut::<super::panel::PanelState>() {
        panel.refresh_scenes();
    }
    world.insert_resource(Notice(Some(notice)));
}
