//! SimPlugin inside your own Bevy app, with your own minimal drawing and no hooke UI.
//!
//! `cargo run --release --example embed` (needs a display; the default `gui` feature)

use bevy::math::DVec2;
use bevy::prelude::*;
use hooke::sim::{Particle, Pinned, Position, SimParams, SimPlugin, Spring};

fn main() {
    App::new()
        .add_plugins(DefaultPlugins)
        .add_plugins(SimPlugin)
        .add_systems(Startup, (camera, build))
        .add_systems(Update, draw)
        .run();
}

/// A camera that shows the unit square.
fn camera(mut commands: Commands) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scale: 1.0 / 500.0,
            ..OrthographicProjection::default_2d()
        }),
        Transform::from_xyz(0.5, 0.5, 0.0),
    ));
}

/// A 10×10 cloth pinned at its top corners, built from entities.
fn build(mut commands: Commands, mut params: ResMut<SimParams>) {
    params.paused = false;
    let n = 10;
    let at = |r: usize, c: usize| DVec2::new(0.25 + 0.05 * c as f64, 0.95 - 0.05 * r as f64);
    let mut ids = vec![];
    for r in 0..n {
        for c in 0..n {
            let mut e = commands.spawn((Particle, Position(at(r, c))));
            if r == 0 && (c == 0 || c == n - 1) {
                e.insert(Pinned);
            }
            ids.push(e.id());
        }
    }
    for r in 0..n {
        for c in 0..n {
            let here = ids[r * n + c];
            if c + 1 < n {
                commands.spawn(Spring::new(here, ids[r * n + c + 1], 0.05, 1e4));
            }
            if r + 1 < n {
                commands.spawn(Spring::new(here, ids[(r + 1) * n + c], 0.05, 1e4));
            }
        }
    }
}

/// Gizmo lines for the springs, read straight from the components.
fn draw(
    mut gizmos: Gizmos,
    springs: Query<&Spring>,
    positions: Query<(&Position, Has<Pinned>), With<Particle>>,
) {
    for s in &springs {
        if let (Ok((a, _)), Ok((b, _))) = (positions.get(s.a), positions.get(s.b)) {
            gizmos.line_2d(a.0.as_vec2(), b.0.as_vec2(), Color::WHITE);
        }
    }
    for (p, pinned) in &positions {
        let color = if pinned {
            Color::srgb(1.0, 0.75, 0.2)
        } else {
            Color::WHITE
        };
        gizmos.circle_2d(Isometry2d::from_translation(p.0.as_vec2()), 0.006, color);
    }
}
