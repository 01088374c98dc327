//! The README and the guide show scene files; each must load and run as shown, so that a
//! newcomer who copies one gets what the page says. (The README's Rust code is a doc-test.)

mod common;
use common::*;
use hooke::scene::LoadedScene;
use std::path::{Path, PathBuf};

/// Every ```ron block of a Markdown file, with the line it starts on.
fn ron_blocks(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut blocks = vec![];
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start().starts_with("```");
        match (&mut current, fence) {
            (None, true) if line.trim() == "```ron" => current = Some((i + 2, String::new())),
            (Some(_), true) => blocks.push(current.take().unwrap()),
            (Some((_, body)), false) => {
                body.push_str(line);
                body.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

fn pages() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pages = vec![root.join("README.md")];
    let mut guide: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    guide.sort();
    pages.extend(guide);
    pages
}

#[test]
fn every_scene_shown_in_the_readme_and_the_guide_loads_and_runs() {
    let mut shown = 0;
    for page in pages() {
        for (line, body) in ron_blocks(&page) {
            shown += 1;
            let name = PathBuf::from(format!("{}:{line}", page.display()));
            let Some(loaded) = unless_it_needs_avian(
                LoadedScene::parse(&body, &name),
                &name.display().to_string(),
            ) else {
                continue;
            };
            let mut app = app_with(loaded.scene.clone());
            step(&mut app, 20);
            assert!(solver(&app).state_is_finite(), "{}", name.display());
        }
    }
    // The README's cloth and the scene format's every-field example at least (the latter has
    // rigid bodies: a build without them checks that it is refused for that).
    assert!(shown >= 2, "found {shown} scene blocks");
}
