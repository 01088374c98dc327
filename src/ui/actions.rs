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

/// Reloads the current scene (an edit: undo takes it back). A scene from a file is read from
/// the file again, so that a scene being written in an editor shows each change at R; a file
/// that no longer loads leaves what is on screen as it is and says why. A scene with no file
/// (a built-in one run outside the repository, one made in code) resets to what was loaded.
pub fn reset(world: &mut World) {
    let Some(current) = world.get_resource::<CurrentScene>().map(|s| s.0.clone()) else {
        return;
    };
    let Some(path) = current.path.clone().filter(|p| p.is_file()) else {
        replace_scene(world, "reset", &current);
        return;
    };
    match LoadedScene::read(&path) {
        Ok(fresh) => {
            let changed = fresh.scene != current.scene;
            replace_scene(world, "reset", &fresh);
            if changed {
                let text = format!("reloaded {}: the file changed", path.display());
                world.insert_resource(Notice(Some((text, false))));
            }
        }
        Err(e) => {
            let text = format!("{e}\nNothing was reset: mend the file and press R again.");
            world.insert_resource(Notice(Some((text, true))));
        }
    }
}

/// Opens a scene in place of what is on screen (an edit: undo takes it back).
pub fn open(world: &mut World, scene: &LoadedScene) {
    replace_scene(world, "load", scene);
}

/// What a refused file is told, after its name: the drop's hint and the open's notice say it
/// alike.
pub const OPENS_SCENE_FILES: &str = "hooke opens scene files (.ron)";

/// Whether `path` names a scene file by its extension, `.ron` in any case: what a drop or an
/// open looks at before reading it.
pub fn is_scene_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"))
}

/// Opens the scene file at `path` as the picker opens one (an edit: undo takes it back). A file
/// that is no scene file, or one that does not load, leaves what is on screen as it is, and the
/// panel says why.
pub fn open_file(world: &mut World, path: &Path) {
    let refused = if !is_scene_file(path) {
        Some(format!(
            "{} is not a scene: {OPENS_SCENE_FILES}",
            path.display()
        ))
    } else {
        match LoadedScene::read(path) {
            Ok(loaded) => {
                open(world, &loaded);
                None
            }
            Err(e) => Some(e.to_string()),
        }
    };
    let notice = match refused {
        Some(why) => (format!("{why}\nThe scene on screen is unchanged."), true),
        None => (format!("opened {}", path.display()), false),
    };
    world.insert_resource(Notice(Some(notice)));
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

    /// R reads a scene's file again: a change made in an editor shows, undo takes it back, and a
    /// file broken since leaves the world as it was, with the error on the panel.
    #[test]
    fn reset_reads_the_file_again() {
        let dir = std::env::temp_dir().join(format!("hooke-reset-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("two.ron");
        let scene = |x: f64| {
            format!(
                "(ground: None, particles: [(pos: (0.5, 0.5), pinned: true), (pos: ({x}, 0.5))], \
                 springs: [(a: 0, b: 1, stiffness: 100.0, rest: 0.1)])"
            )
        };
        std::fs::write(&path, scene(0.6)).unwrap();
        let mut app = crate::headless_app();
        app.init_resource::<History>();
        let world = app.world_mut();
        open(world, &LoadedScene::read(&path).unwrap());
        let second_x = |w: &mut World| {
            let mut q = w.query::<(&crate::sim::Position, Has<crate::sim::Pinned>)>();
            let free: Vec<f64> = q.iter(w).filter(|(_, p)| !p).map(|(x, _)| x.0.x).collect();
            assert_eq!(free.len(), 1);
            free[0]
        };
        assert_eq!(second_x(world), 0.6);

        std::fs::write(&path, scene(0.7)).unwrap();
        reset(world);
        assert_eq!(second_x(world), 0.7, "the file's change shows");
        let notice = world.resource::<Notice>().0.clone().unwrap();
        assert!(
            notice.0.contains("the file changed") && !notice.1,
            "{notice:?}"
        );
        history::undo(world);
        assert_eq!(second_x(world), 0.6, "undo takes the reload back");

        std::fs::write(&path, "(particles: [(pos: (0.5, oops))])").unwrap();
        reset(world);
        assert_eq!(second_x(world), 0.6, "a broken file changes nothing");
        let (text, is_error) = world.resource::<Notice>().0.clone().unwrap();
        assert!(is_error && text.contains("two.ron:1:") && text.contains("Nothing was reset"));
    }
}
