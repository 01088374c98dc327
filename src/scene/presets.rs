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

/// The scene files the reports run (`hooke bench`'s scenes and hard cases), by their paths
/// from the repository's root: built in, so that an installed `hooke bench stability` or
/// `hooke run --scene assets/scenes/bench/cloth256.ron` works in any folder. A file at that path
/// is read instead ([`resolve`], [`scenes_in`]), so that an edited copy is what runs.
pub const REPORT_SCENES: &[(&str, &str)] = &[
    (
        "assets/scenes/bench/cloth256.ron",
        include_str!("../../assets/scenes/bench/cloth256.ron"),
    ),
    (
        "assets/scenes/bench/cloth256_contact.ron",
        include_str!("../../assets/scenes/bench/cloth256_contact.ron"),
    ),
    (
        "assets/scenes/bench/cloth256_free.ron",
        include_str!("../../assets/scenes/bench/cloth256_free.ron"),
    ),
    (
        "assets/scenes/bench/cloth64.ron",
        include_str!("../../assets/scenes/bench/cloth64.ron"),
    ),
    (
        "assets/scenes/bench/cloth64_implicit.ron",
        include_str!("../../assets/scenes/bench/cloth64_implicit.ron"),
    ),
    (
        "assets/scenes/bench/one_particle.ron",
        include_str!("../../assets/scenes/bench/one_particle.ron"),
    ),
    (
        "assets/scenes/hard/cloth_light.ron",
        include_str!("../../assets/scenes/hard/cloth_light.ron"),
    ),
    (
        "assets/scenes/hard/coincident.ron",
        include_str!("../../assets/scenes/hard/coincident.ron"),
    ),
    (
        "assets/scenes/hard/collinear.ron",
        include_str!("../../assets/scenes/hard/collinear.ron"),
    ),
    (
        "assets/scenes/hard/impact.ron",
        include_str!("../../assets/scenes/hard/impact.ron"),
    ),
    (
        "assets/scenes/hard/large_dt.ron",
        include_str!("../../assets/scenes/hard/large_dt.ron"),
    ),
    (
        "assets/scenes/hard/long_chain.ron",
        include_str!("../../assets/scenes/hard/long_chain.ron"),
    ),
    (
        "assets/scenes/hard/mass_ratio.ron",
        include_str!("../../assets/scenes/hard/mass_ratio.ron"),
    ),
];

/// The scene the app opens with: the assignment's empty canvas.
pub const DEFAULT_SCENE: &str = "empty";

/// The built-in scenes' names, in the order of [`BUILTIN`].
pub fn names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

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
