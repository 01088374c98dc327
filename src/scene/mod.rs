//! Scenes: the RON file format, parametric generators, validation and loading.

pub mod bodies;
mod builtin;
mod despawn;
pub mod format;
pub mod generate;
pub mod load;
pub mod presets;
mod reserve;
mod start_apart;
mod typo;
pub mod validate;

pub use format::*;
pub use generate::Expanded;
pub use load::{
    CurrentScene, LoadedScene, SceneError, explicit_state, load_into_world, obstacle_defs,
    replace_contents, replace_obstacles, snapshot, spawn_expanded, to_ron,
};
pub use validate::validate;

/// How scene files are read: RON with `implicit_some`, so that an optional field takes a plain
/// value (`damping: 5.0`, `ground: 0.0`, `contact: (radius: 0.01)`) as well as `Some(..)` and
/// `None`, as every other number of the format is written.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}
