//! What the keyboard and the panel's buttons both do: undo and redo, reset, open, save; the
//! notices they leave for the panel; the scene picker's list.

use super::history::{self, History};
use crate::scene::{CurrentScene, LoadedScene, load_into_world, presets, snapshot, to_ron};
use bevy::prelude::*;
use std::path::Path;

/// A message for the panel after a keyboard or button action: (text, is an error).
#[derive(Resource, Debug, Clone, Default)]
pub struct Notice(pub Option<(String, bool)>);

/// The scene picker's entries: (label, what to pass to `presets::resolve`).
#[derive(Resource, Debug, Clone)]
pub struct SceneList(pub Vec<(String, String)>);

impl Default for SceneList {
    fn default() -> Self {
        let mut list = SceneList(vec![]);
        list.refresh();
        list
    }
}

impl SceneList {
    /// Lists the scene files in `assets/scenes/` and `saved/`, then the built-in scenes.
    pub fn refresh(&mut self) {
        let mut scenes: Vec<(String, String)> = vec![];
        for dir in ["assets/scenes", "saved"] {
            for p in presets::scene_files(Path::new(dir)) {
                let label = p
                    .strip_prefix("assets/scenes")
                    .unwrap_or(&p)
                    .with_extension("")
                    .display()
                    .to_string();
                scenes.push((label, p.display().to_string()));
            }
        }
        for (name, _) in presets::BUILTIN {
            if !scenes.iter().any(|(label, _)| label == name) {
                scenes.push((name.to_string(), name.to_string()));
            }
        }
        self.0 = scenes;
    }
}

/// Undoes the newest edit, and says so.
pub fn undo(world: &mut World) {
    let text = match history::undo(world) {
        Some(label) => format!("undid {label}"),
        None => "nothing to undo".into(),
    };
    world.insert_resource(Notice(Some((text, false))));
}

/// Redoes the newest undone edit, and says so.
pub fn redo(world: &mut World) {
    let text = match history::redo(world) {
        Some(label) => format!("redid {label}"),
        None => "nothing to redo".into(),
    };
    world.insert_resource(Notice(Some((text, false))));
}

/// Reloads the current scene as it was loaded (an edit: undo takes it back).
pub fn reset(world: &mut World) {
    if let Some(scene) = world.get_resource::<CurrentScene>().map(|s| s.0.clone()) {
        replace_scene(world, "reset", &scene);
    }
}

/// Opens a scene in place of what is on screen (an edit: undo takes it back).
pub fn open(world: &mut World, scene: &LoadedScene) {
    replace_scene(world, "load", scene);
}

/// Loads `scene` as an edit labelled `label`. What is on screen is then a file's, and nothing
/// is unsaved, unless something was before: those edits are only in the undo history now,
/// and quitting still asks first.
fn replace_scene(world: &mut World, label: &'static str, scene: &LoadedScene) {
    let unsaved_before = world.resource::<History>().unsaved();
    history::record(world, label);
    load_into_world(world, scene);
    if !unsaved_before {
        world.resource_mut::<History>().mark_saved();
    }
}

/// Saves what is on screen as an explicit scene file under `saved/`, and lists it in the
/// scene picker (S, and the panel's Save).
pub fn save(world: &mut World) {
    try_save(world);
}

/// [`save`], returning whether the scene was saved (the panel's notice says why not).
pub fn try_save(world: &mut World) -> bool {
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
    let saved = result.is_ok();
    let notice = match result {
        Ok(()) => (format!("saved {}", path.display()), false),
        Err(e) => (format!("could not save {}: {e}", path.display()), true),
    };
    if saved {
        world.resource_mut::<History>().mark_saved();
    }
    if let Some(mut list) = world.get_resource_mut::<SceneList>() {
        list.refresh();
    }
    world.insert_resource(Notice(Some(notice)));
    saved
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Opening a scene over nothing unsaved leaves nothing unsaved; over unsaved edits (now
    /// only in the undo history) quitting must still ask.
    #[test]
    fn opening_a_scene_keeps_unsaved_edits_unsaved() {
        let mut app = crate::headless_app();
        app.init_resource::<History>();
        let world = app.world_mut();
        let rope = presets::resolve("rope").unwrap();
        let unsaved = |w: &World| w.resource::<History>().unsaved();
        open(world, &rope);
        assert!(!unsaved(world), "a file opened over nothing");
        history::record(world, "add");
        open(world, &rope);
        assert!(unsaved(world), "the add is behind the load");
        history::undo(world);
        assert!(unsaved(world), "the add is back on screen");
        history::undo(world);
        assert!(!unsaved(world), "back at the first load");
        reset(world);
        assert!(!unsaved(world), "a reset over nothing unsaved");
    }
}
