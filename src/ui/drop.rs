//! Files dragged onto the window: while they hover, the canvas says what a drop will do, so
//! that a picture dragged by mistake is named before it is let go; a drop opens the scene
//! ([`actions::open_file`]).

use super::actions;
use bevy::prelude::*;
use bevy::window::FileDragAndDrop;
use bevy_egui::{EguiContexts, egui};
use std::path::{Path, PathBuf};

/// The files over the window now, in the order the system named them (none: no drag).
#[derive(Resource, Debug, Clone, Default)]
pub struct FilesOver(pub Vec<PathBuf>);

/// Follows drags over the window; a drop opens each file dropped, in order (the last one that
/// loads stays on screen, the others are in the undo history).
pub fn follow_file_drags(
    mut drags: MessageReader<FileDragAndDrop>,
    mut over: ResMut<FilesOver>,
    mut commands: Commands,
) {
    for drag in drags.read() {
        match drag {
            FileDragAndDrop::HoveredFile { path_buf, .. } => {
                if !over.0.contains(path_buf) {
                    over.0.push(path_buf.clone());
                }
            }
            FileDragAndDrop::HoveredFileCanceled { .. } => over.0.clear(),
            FileDragAndDrop::DroppedFile { path_buf, .. } => {
                over.0.clear();
                let path = path_buf.clone();
                commands.queue(move |w: &mut World| actions::open_file(w, &path));
            }
        }
    }
}

/// What letting `files` go will do, in a line: (text, whether nothing will open).
pub fn what_a_drop_does(files: &[PathBuf]) -> (String, bool) {
    let name = |p: &Path| {
        p.file_name()
            .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
    };
    let scenes: Vec<&PathBuf> = files.iter().filter(|p| actions::is_scene_file(p)).collect();
    match (files, scenes.last()) {
        ([one], Some(_)) => (format!("Drop to open {}", name(one)), false),
        ([one], None) => (
            format!(
                "{} is not a scene: {}",
                name(one),
                actions::OPENS_SCENE_FILES
            ),
            true,
        ),
        (_, Some(last)) => (
            format!(
                "Drop to open {} (the last scene of {} files)",
                name(last),
                files.len()
            ),
            false,
        ),
        (_, None) => (
            format!(
                "None of these {} files is a scene: {}",
                files.len(),
                actions::OPENS_SCENE_FILES
            ),
            true,
        ),
    }
}

/// The line, over the canvas's middle, while files hover.
pub fn drop_hint(
    mut contexts: EguiContexts,
    over: Res<FilesOver>,
    view: Res<super::view::CanvasView>,
) -> Result {
    if over.0.is_empty() {
        return Ok(());
    }
    let (text, refused) = what_a_drop_does(&over.0);
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("file-drop-hint"))
        .anchor(egui::Align2::CENTER_CENTER, [view.canvas_offset(), 0.0])
        .order(egui::Order::Foreground)
        .interactable(false)
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                let text = egui::RichText::new(text).heading();
                let text = if refused {
                    text.color(ui.visuals().error_fg_color)
                } else {
                    text
                };
                // One line, however narrow the area's first guess at its width.
                ui.add(egui::Label::new(text).wrap_mode(egui::TextWrapMode::Extend));
            });
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hint_says_what_a_drop_opens() {
        let p = |s: &str| PathBuf::from(s);
        let cases = [
            (
                vec![p("/home/a/my_cloth.ron")],
                "Drop to open my_cloth.ron",
                false,
            ),
            (
                vec![p("/tmp/cat.png")],
                "cat.png is not a scene: hooke opens scene files (.ron)",
                true,
            ),
            (
                vec![p("a.ron"), p("b.RON"), p("c.txt")],
                "Drop to open b.RON (the last scene of 3 files)",
                false,
            ),
            (
                vec![p("a.txt"), p("b")],
                "None of these 2 files is a scene: hooke opens scene files (.ron)",
                true,
            ),
        ];
        for (files, text, refused) in cases {
            assert_eq!(what_a_drop_does(&files), (text.to_string(), refused));
        }
    }

    /// A headless app that follows drags and opens what is dropped, with an undo history.
    fn following_drags() -> App {
        let mut app = crate::headless_app();
        app.init_resource::<super::super::history::History>()
            .init_resource::<FilesOver>()
            .add_message::<FileDragAndDrop>()
            .add_systems(Update, follow_file_drags);
        app
    }

    /// The particles in `app`'s world.
    fn particles(app: &mut App) -> usize {
        let w = app.world_mut();
        w.query::<&crate::sim::Particle>().iter(w).count()
    }

    /// Hovering fills the list, a cancel or a drop empties it, and a drop opens the file.
    #[test]
    fn a_drag_is_followed_and_a_drop_opens() {
        let dir = std::env::temp_dir().join(format!("hooke-drag-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("two.ron");
        std::fs::write(
            &scene,
            "(particles: [(pos: (0.4, 0.5)), (pos: (0.6, 0.5))])",
        )
        .unwrap();

        let mut app = following_drags();
        let window = Entity::PLACEHOLDER;
        let send = |app: &mut App, m: FileDragAndDrop| {
            app.world_mut().write_message(m);
            app.update();
            app.world().resource::<FilesOver>().0.clone()
        };
        let hover = FileDragAndDrop::HoveredFile {
            window,
            path_buf: scene.clone(),
        };
        assert_eq!(send(&mut app, hover.clone()), vec![scene.clone()]);
        assert_eq!(send(&mut app, hover.clone()), vec![scene.clone()]);
        assert!(send(&mut app, FileDragAndDrop::HoveredFileCanceled { window }).is_empty());
        send(&mut app, hover);
        let dropped = FileDragAndDrop::DroppedFile {
            window,
            path_buf: scene,
        };
        assert!(send(&mut app, dropped).is_empty());
        assert_eq!(particles(&mut app), 2);
    }

    /// A scene file dropped on the window opens (undo takes it back); a file of another kind, or
    /// a broken scene, changes nothing and the panel says why.
    #[test]
    fn a_dropped_scene_file_opens() {
        let dir = std::env::temp_dir().join(format!("hooke-drop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("three.ron");
        std::fs::write(
            &good,
            "(particles: [(pos: (0.2, 0.5)), (pos: (0.4, 0.5)), (pos: (0.6, 0.5))])",
        )
        .unwrap();
        let picture = dir.join("cloth.png");
        std::fs::write(&picture, [0x89, b'P', b'N', b'G']).unwrap();
        let broken = dir.join("broken.ron");
        std::fs::write(&broken, "(particles: [(pos: (0.5, 0.5)),").unwrap();

        let mut app = following_drags();
        actions::open(
            app.world_mut(),
            &crate::scene::presets::resolve("rope").unwrap(),
        );
        let rope = particles(&mut app);
        let drop = |app: &mut App, path: &Path| {
            app.world_mut().write_message(FileDragAndDrop::DroppedFile {
                window: Entity::PLACEHOLDER,
                path_buf: path.to_owned(),
            });
            app.update();
            app.world().resource::<actions::Notice>().0.clone().unwrap()
        };
        for (path, needle) in [
            (&picture, "is not a scene: hooke opens scene files (.ron)"),
            (&broken, "broken.ron:1:"),
        ] {
            let (text, is_error) = drop(&mut app, path);
            assert!(is_error && text.contains(needle), "{text}");
            assert!(text.ends_with("The scene on screen is unchanged."));
            assert_eq!(particles(&mut app), rope);
        }
        let (text, is_error) = drop(&mut app, &good);
        assert!(!is_error && text.contains("opened"), "{text}");
        assert_eq!(particles(&mut app), 3);
        super::super::history::undo(app.world_mut());
        assert_eq!(particles(&mut app), rope, "undo takes the drop back");
    }
}
