//! The window's title: the scene on screen, and a * while it has edits that are not saved, as
//! editors mark theirs. It follows the scene picker (it kept the first scene's name).

use super::history::History;
use crate::scene::CurrentScene;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

/// The title for `scene`, marked when `unsaved`.
pub fn title(scene: &str, unsaved: bool) -> String {
    let mark = if unsaved { " *" } else { "" };
    format!("hooke: {scene}{mark}")
}

/// Sets the title when it changes (a write would otherwise reach the window every frame).
pub fn window_title(
    scene: Option<Res<CurrentScene>>,
    history: Res<History>,
    mut window: Single<&mut Window, With<PrimaryWindow>>,
) {
    let name = scene.map(|s| s.0.name()).unwrap_or_default();
    let title = title(&name, history.unsaved());
    if window.title != title {
        window.title = title;
    }
}
