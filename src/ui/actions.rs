//! What the keyboard and the panel's buttons both do: undo and redo, reset, save; the
//! notices they leave for the panel; the scene picker's list.

use super::history;
use crate::scene::{CurrentScene, load_into_world, presets, snapshot, to_ron};
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
    if let Some(mut list) = world.get_resource_mut::<SceneList>() {
        list.refresh();
    }
    world.insert_resource(Notice(Some(notice)));
}
