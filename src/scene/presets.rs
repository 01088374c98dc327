//! The scenes that ship with hooke. They are files in `assets/scenes/`, also compiled into the
//! binary so that `--scene cloth32` works from any directory.

use super::load::{LoadedScene, SceneError};
use std::path::{Path, PathBuf};

/// Built-in scenes: (name, RON text).
pub const BUILTIN: &[(&str, &str)] = &[
    ("empty", include_str!("../../assets/scenes/empty.ron")),
    ("rope", include_str!("../../assets/scenes/rope.ron")),
    ("cloth32", include_str!("../../assets/scenes/cloth32.ron")),
    ("soft_box", include_str!("../../assets/scenes/soft_box.ron")),
    (
        "cloth_on_ball",
        include_str!("../../assets/scenes/cloth_on_ball.ron"),
    ),
    ("slope", include_str!("../../assets/scenes/slope.ron")),
    ("pile", include_str!("../../assets/scenes/pile.ron")),
    ("ropes", include_str!("../../assets/scenes/ropes.ron")),
    (
        "folding_cloth",
        include_str!("../../assets/scenes/folding_cloth.ron"),
    ),
    ("balloon", include_str!("../../assets/scenes/balloon.ron")),
    ("walker", include_str!("../../assets/scenes/walker.ron")),
    ("wire", include_str!("../../assets/scenes/wire.ron")),
    // Rigid bodies: a build without the `avian` feature refuses it, and says why.
    ("crates", include_str!("../../assets/scenes/crates.ron")),
];

/// The scene the app opens with: the assignment's empty canvas.
pub const DEFAULT_SCENE: &str = "empty";

/// The built-in scenes' names, in the order of [`BUILTIN`].
pub fn names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// Loads a scene by file path or, when no such file exists, by built-in name. A name that is
/// neither (no path separator, no `.ron`) is answered with the built-in names near it, or with
/// all of them.
pub fn resolve(name_or_path: &str) -> Result<LoadedScene, SceneError> {
    let path = Path::new(name_or_path);
    if !path.exists() {
        if let Some((name, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
            return LoadedScene::parse(text, &PathBuf::from(format!("assets/scenes/{name}.ron")));
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
