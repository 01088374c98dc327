//! The shipped scenes' table: each name with its RON text, compiled into the binary from
//! `assets/scenes/` so that `--scene cloth32` works from any directory. What loads them is
//! [`super::presets`]; what names them in an error is [`super::load`].

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
    ("paddle", include_str!("../../assets/scenes/paddle.ron")),
    // Rigid bodies: a build without the `avian` feature refuses it, and says why.
    ("crates", include_str!("../../assets/scenes/crates.ron")),
];

/// The scene files the reports run (`hooke bench`'s scenes and hard cases), by their paths
/// from the repository's root: built in, so that an installed `hooke bench stability` or
/// `hooke run --scene assets/scenes/bench/cloth256.ron` works in any folder. A file at that path
/// is read instead ([`super::presets::resolve`], [`super::presets::scenes_in`]), so that an
/// edited copy is what runs.
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
