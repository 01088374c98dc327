//! The scenes that ship with hooke. They are files in `assets/scenes/`, also compiled into the
//! binary so that `--scene cloth32` works from any directory.

use super::load::{LoadedScene, SceneError};
use std::path::{Path, PathBuf};

pub use super::builtin::{BUILTIN, DEFAULT_SCENE, REPORT_SCENES, names};

/// Loads a scene by file path or, when no such file exists, by built-in name or by a shipped
/// scene's path (`assets/scenes/rope.ron` in any folder). A name that is neither (no path
/// separator, no `.ron`) is answered with the built-in names near it, or with all of them.
pub fn resolve(name_or_path: &str) -> Result<LoadedScene, SceneError> {
    let path = Path::new(name_or_path);
    if !path.exists() {
        let shipped = |name: &str| PathBuf::from(format!("assets/scenes/{name}.ron"));
        let builtin = BUILTIN
            .iter()
            .find(|(n, _)| *n == name_or_path || path == shipped(n));
        if let Some((name, text)) = builtin {
            return LoadedScene::parse(text, &shipped(name));
        }
        if let Some((shipped, text)) = REPORT_SCENES.iter().find(|(p, _)| Path::new(p) == path) {
            return LoadedScene::parse(text, Path::new(shipped));
        }
        let looks_like_a_path =
            name_or_path.contains(['/', '\\']) || name_or_path.ends_with(".ron");
        if !looks_like_a_path {
            return Err(SceneError::Unknown {
                name: name_or_path.to_string(),
                near: super::typo::near_names(name_or_path, &names()),
            });
        }
    }
    LoadedScene::read(path)
}

/// The scenes in a folder, sorted by path: its files, or, where no such folder exists, the
/// [`REPORT_SCENES`] built in under that path (`hooke bench stability`'s hard cases in any
/// folder).
pub fn scenes_in(dir: &Path) -> Result<Vec<LoadedScene>, SceneError> {
    if dir.is_dir() {
        return scene_files(dir)
            .iter()
            .map(|p| LoadedScene::read(p))
            .collect();
    }
    REPORT_SCENES
        .iter()
        .filter(|(p, _)| Path::new(p).starts_with(dir))
        .map(|(p, text)| LoadedScene::parse(text, Path::new(p)))
        .collect()
}

/// Scene files found in a directory (sorted), for the scene picker.
pub fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(scene_files(&p));
        } else if p.extension().is_some_and(|x| x == "ron") {
            out.push(p);
        }
    }
    out.sort();
    out
}
