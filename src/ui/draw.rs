//! Drawing: the unit square and ground, springs as lines coloured by strain, particles as dots.
//! Positions are f64 in the simulation; f32 only here.

use super::view::CanvasView;
use crate::sim::{Particle, Pinned, Position, SimParams, Solver};
use bevy::prelude::*;

pub const BACKGROUND: Color = Color::srgb(0.07, 0.08, 0.10);
const FRAME: Color = Color::srgb(0.30, 0.32, 0.38);
const GROUND: Color = Color::srgb(0.55, 0.45, 0.30);
const PARTICLE: Color = Color::srgb(0.95, 0.95, 0.95);
const PINNED: Color = Color::srgb(1.0, 0.75, 0.2);
/// Particle dot radius, in logical pixels.
const DOT_PX: f32 = 3.5;

/// The dot's mesh and materials, shared by every particle.
pub struct ParticleLook {
    mesh: Handle<Mesh>,
    free: Handle<ColorMaterial>,
    pinned: Handle<ColorMaterial>,
}

/// Particles that are new or newly pinned.
type NewDots<'w, 's> = Query<'w, 's, (Entity, Has<Pinned>), Or<(Added<Particle>, Added<Pinned>)>>;

/// Gives new particles (and re-pinned ones) a dot.
pub fn attach_particle_meshes(
    mut commands: Commands,
    mut look: Local<Option<ParticleLook>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<ColorMaterial>>,
    new: NewDots,
    mut unpinned: RemovedComponents<Pinned>,
    particles: Query<(), With<Particle>>,
) {
    // Made on the first run, in the same run: returning early would miss the particles a scene
    // spawned at startup (their `Added` is seen only once).
    let look = look.get_or_insert_with(|| ParticleLook {
        mesh: meshes.add(Circle::new(1.0)),
        free: materials.add(ColorMaterial::from_color(PARTICLE)),
        pinned: materials.add(ColorMaterial::from_color(PINNED)),
    });
    let unpinned: Vec<Entity> = unpinned.read().filter(|e| particles.contains(*e)).collect();
    let all = new.iter().chain(unpinned.into_iter().map(|e| (e, false)));
    for (e, pinned) in all {
        let material = if pinned { &look.pinned } else { &look.free };
        commands.entity(e).insert((
            Mesh2d(look.mesh.clone()),
            MeshMaterial2d(material.clone()),
            Transform::default(),
        ));
    }
}

/// Moves each dot to its particle, sized in pixels.
pub fn place_particles(
    view: Res<CanvasView>,
    mut q: Query<(&Position, &mut Transform), With<Particle>>,
) {
    let radius = DOT_PX / view.scale;
    for (p, mut t) in &mut q {
        t.translation = Vec3::new(p.0.x as f32, p.0.y as f32, 1.0);
        t.scale = Vec3::splat(radius);
    }
}

/// Springs as lines: white at rest, red when stretched, blue when compressed.
pub fn draw_springs(mut gizmos: Gizmos, solver: Res<Solver>) {
    for s in &solver.springs {
        let (a, b) = (solver.x[s.a as usize], solver.x[s.b as usize]);
        let strain = if s.rest > 0.0 {
            ((a - b).length() / s.rest - 1.0) as f32
        } else {
            0.0
        };
        gizmos.line_2d(a.as_vec2(), b.as_vec2(), strain_color(strain));
    }
}

/// Colour for a relative extension: ±5 % is full colour.
fn strain_color(strain: f32) -> Color {
    let t = (strain / 0.05).clamp(-1.0, 1.0);
    if t >= 0.0 {
        Color::srgb(0.85, 0.85 * (1.0 - t) + 0.2 * t, 0.85 * (1.0 - t) + 0.2 * t)
    } else {
        let t = -t;
        Color::srgb(
            0.85 * (1.0 - t) + 0.25 * t,
            0.85 * (1.0 - t) + 0.55 * t,
            0.85,
        )
    }
}

/// The unit square and the ground line.
pub fn draw_frame(mut gizmos: Gizmos, params: Res<SimParams>, view: Res<CanvasView>) {
    gizmos.rect_2d(
        Isometry2d::from_translation(Vec2::splat(0.5)),
        Vec2::ONE,
        FRAME,
    );
    if let Some(g) = params.ground {
        let reach = 2.0 * view.center.x / view.scale;
        let y = g as f32;
        gizmos.line_2d(Vec2::new(-reach, y), Vec2::new(1.0 + reach, y), GROUND);
    }
}
