//! Scenes: the RON file format, parametric generators, validation and loading.

pub mod format;
pub mod generate;
pub mod load;
pub mod presets;
mod reserve;
mod typo;
pub mod validate;

pub use format::*;
pub use generate::Expanded;
pub use load::{
    CurrentScene, LoadedScene, SceneError, explicit_state, load_into_world, obstacle_defs,
    replace_contents, replace_obstacles, snapshot, spawn_expanded, to_ron,
};
pub use validate::validate;
