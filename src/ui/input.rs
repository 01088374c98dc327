//! Mouse and keyboard: a click adds a particle, G pauses, R resets, S saves, N steps once.

use super::view::CanvasView;
use crate::scene::{CurrentScene, load_into_world, snapshot, to_ron};
use crate::sim::grid::SpatialGrid;
use crate::sim::*;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy_egui::input::EguiWantsInput;

/// The particles' positions in a grid, valid while no step ran and no particle came or went.
pub struct ClickGrid {
    steps: u64,
    count: usize,
    radius: f64,
    cells: SpatialGrid<Entity>,
}

/// Left click on the canvas: a particle at the cursor, joined to every particle within the
/// click radius (rest = current distance).
#[allow(clippy::too_many_arguments)]
pub fn add_particle_on_click(
    mut commands: Commands,
    buttons: Res<ButtonInput<MouseButton>>,
    window: Single<&Window, With<PrimaryWindow>>,
    egui: Res<EguiWantsInput>,
    view: Res<CanvasView>,
    scene: Option<Res<CurrentScene>>,
    params: Res<SimParams>,
    mut serials: ResMut<Serials>,
    particles: Query<(Entity, &Position), With<Particle>>,
    clock: Res<SimClock>,
    mut grid: Local<Option<ClickGrid>>,
) {
    if !buttons.just_pressed(MouseButton::Left) || egui.wants_any_pointer_input() {
        return;
    }
    let Some(cursor) = window.cursor_position() else {
        return;
    };
    if !view.on_canvas(cursor) {
        return;
    }
    let rules = scene.and_then(|s| s.0.scene.click).unwrap_or_default();
    let at = view.window_to_world(cursor);
    // The grid is rebuilt only when particles moved or changed in number since the last click:
    // building a paused scene click by click costs O(1) per neighbour.
    let count = particles.iter().len();
    let stale = grid
        .as_ref()
        .is_none_or(|g| (g.steps, g.count, g.radius) != (clock.steps, count, rules.radius));
    if stale {
        let mut cells = SpatialGrid::new(rules.radius);
        for (e, p) in &particles {
            cells.insert(p.0, e);
        }
        *grid = Some(ClickGrid {
            steps: clock.steps,
            count,
            radius: rules.radius,
            cells,
        });
    }
    let Some(g) = grid.as_mut() else {
        return;
    };
    let neighbours = g.cells.within(at, rules.radius);
    let first = particles.is_empty();
    let mut particle = commands.spawn((
        Particle {
            serial: serials.next_serial(),
        },
        Position(at),
        Mass(rules.mass),
    ));
    if first && rules.pin_first {
        particle.insert(Pinned);
    }
    let new = particle.id();
    g.cells.insert(at, new);
    g.count += 1;
    let stiffness = params.stiffness_override.unwrap_or(rules.stiffness);
    for (other, rest) in neighbours {
        commands.spawn(Spring {
            a: new,
            b: other,
            rest,
            stiffness,
            serial: serials.next_serial(),
        });
    }
}

/// A message for the panel after a keyboard or button action.
#[derive(Resource, Debug, Clone, Default)]
pub struct Notice(pub Option<(String, bool)>);

/// G / Space: pause or resume. R: reset the scene. S: save the scene. N: one step while paused.
pub fn keyboard(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    egui: Res<EguiWantsInput>,
    mut params: ResMut<SimParams>,
) {
    if egui.wants_any_keyboard_input() {
        return;
    }
    if keys.just_pressed(KeyCode::KeyG) || keys.just_pressed(KeyCode::Space) {
        params.paused = !params.paused;
    }
    if keys.just_pressed(KeyCode::KeyR) {
        commands.queue(reset);
    }
    if keys.just_pressed(KeyCode::KeyS) {
        commands.queue(save);
    }
    if keys.just_pressed(KeyCode::KeyN) && params.paused {
        commands.queue(|world: &mut World| {
            world.resource_mut::<SimParams>().paused = false;
            advance(world, 1);
            world.resource_mut::<SimParams>().paused = true;
        });
    }
}

/// Reloads the current scene as it was loaded.
pub fn reset(world: &mut World) {
    if let Some(scene) = world.get_resource::<CurrentScene>().map(|s| s.0.clone()) {
        load_into_world(world, &scene);
    }
}

/// Saves what is on screen as an explicit scene file under `saved/`.
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
    world.insert_resource(Notice(Some(notice)));
}
