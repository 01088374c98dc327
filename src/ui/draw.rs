//! Drawing: the unit square and ground, springs as lines coloured by strain, particles as dots.
//!
//! All springs are one mesh and all dots another, rebuilt from the solver's arrays when they
//! change: two draw calls whatever the scene's size. (One entity or gizmo line per spring cost
//! ~400 ms a frame at 64×64; see `docs/app.md`.)
//! Positions are f64 in the simulation; f32 only here.

use super::pointer::Gesture;
use super::view::CanvasView;
use crate::sim::{Attraction, Obstacle, ObstaclePose, SimParams, Solver, SolverIndex};
use bevy::asset::RenderAssetUsages;
use bevy::camera::visibility::NoFrustumCulling;
use bevy::math::DVec2;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;

pub const BACKGROUND: Color = Color::srgb(0.07, 0.08, 0.10);
const FRAME: Color = Color::srgb(0.30, 0.32, 0.38);
const GROUND: Color = Color::srgb(0.55, 0.45, 0.30);
pub(super) const PARTICLE: Color = Color::srgb(0.95, 0.95, 0.95);
pub(super) const PINNED: Color = Color::srgb(1.0, 0.75, 0.2);
pub(super) const HELD: Color = Color::srgb(0.35, 0.85, 1.0);
const ATTRACTION: Color = Color::srgba(0.35, 0.85, 1.0, 0.8);
const OBSTACLE: Color = Color::srgb(0.55, 0.75, 0.45);
/// Rigid bodies that move (avian's dynamic ones); those that do not are drawn as obstacles.
const BODY: Color = Color::srgb(0.85, 0.55, 0.35);
/// An obstacle being built (the drag's preview).
const BUILDING: Color = Color::srgb(0.95, 0.8, 0.35);
/// Particle dot radius, in logical pixels.
const DOT_PX: f32 = 3.5;
/// Half the width of a spring line, in logical pixels.
pub(super) const SPRING_HALF_PX: f32 = 0.8;
/// Corners of a dot: a hexagon is round at a few pixels, in four triangles (a software
/// rasterizer's cost goes by the triangle, and a 64×64 cloth has 4,096 dots).
const DOT_SIDES: u32 = crate::solver::gpu::DOT_CORNERS;
/// Relative extension drawn in full colour (red stretched, blue compressed).
pub(super) const FULL_STRAIN: f32 = 0.05;

/// The two batched meshes.
#[derive(Resource)]
pub struct Batches {
    pub(super) springs: Handle<Mesh>,
    pub(super) dots: Handle<Mesh>,
}

/// Spawns the spring and dot meshes, empty, with a white material that the vertex colours tint.
pub fn spawn_batches(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<ColorMaterial>>,
) {
    let white = materials.add(ColorMaterial::from_color(Color::WHITE));
    let springs = meshes.add(empty_mesh());
    let dots = meshes.add(empty_mesh());
    for (mesh, z) in [(&springs, 0.5), (&dots, 1.0)] {
        commands.spawn((
            Mesh2d(mesh.clone()),
            MeshMaterial2d(white.clone()),
            Transform::from_xyz(0.0, 0.0, z),
            // The vertices move every frame; the bounds computed at spawn would be stale.
            NoFrustumCulling,
        ));
    }
    commands.insert_resource(Batches { springs, dots });
}

/// A mesh of one invisible, zero-area triangle. The renderer must never get a mesh without
/// vertices: Bevy's mesh allocator logs an error for it on every frame
/// (`slab_allocator: Use-after-free`), so an empty batch holds this placeholder instead.
fn empty_mesh() -> Mesh {
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    );
    fill(&mut mesh, 0, 3, &[0, 1, 2], |_, _| {});
    mesh
}

/// The solver index of the particle a grab holds, if one does: drawn in its own colour.
pub(super) fn held(gesture: &Gesture, indices: &Query<&SolverIndex>) -> Option<u32> {
    match *gesture {
        Gesture::Grab { particle, .. } => indices.get(particle).ok().map(|i| i.0),
        _ => None,
    }
}

/// A particle's drawn radius: a dot, or with contact on its collision radius (never smaller than
/// a dot), so that what touches is seen touching.
pub(super) fn dot_radius(view: &CanvasView, params: &SimParams) -> f32 {
    let contact_radius = params.contact.map_or(0.0, |c| c.radius) as f32;
    (DOT_PX / view.scale).max(contact_radius)
}

/// Rebuilds both meshes from the solver when it or the view changed. While the card draws them
/// ([`super::card_draw`]) only their sizes follow the solver: their vertices are the card's.
#[allow(clippy::too_many_arguments)] // a Bevy system: its parameters are what it reads
pub fn update_batches(
    batches: Res<Batches>,
    solver: Res<Solver>,
    view: Res<CanvasView>,
    mut meshes: ResMut<Assets<Mesh>>,
    palette: Local<StrainPalette>,
    gesture: Res<Gesture>,
    indices: Query<&SolverIndex>,
    params: Res<SimParams>,
    card: Option<Res<crate::sim::gpu::CardStep>>,
    mut sizes: Local<(usize, usize)>,
) {
    if !(solver.is_changed() || view.is_changed() || gesture.is_changed() || params.is_changed()) {
        return;
    }
    let counts = (solver.springs.len(), solver.x.len());
    let on_card = card.is_some_and(|c| c.draw_source().is_some());
    if on_card && *sizes == counts {
        return;
    }
    *sizes = counts;
    // The grabbed particle is drawn in its own colour.
    let held_index = held(&gesture, &indices).map(|i| i as usize);
    if let Some(mut mesh) = meshes.get_mut(&batches.springs) {
        let half = SPRING_HALF_PX / view.scale;
        fill(
            &mut mesh,
            solver.springs.len(),
            4,
            &[0, 1, 2, 0, 2, 3],
            |pos, col| {
                for s in &solver.springs {
                    let (a, b) = (solver.x[s.a as usize], solver.x[s.b as usize]);
                    let d = b - a;
                    let l = d.length();
                    let strain = if s.rest > 0.0 {
                        (l / s.rest - 1.0) as f32
                    } else {
                        0.0
                    };
                    let (a, b) = (a.as_vec2(), b.as_vec2());
                    let n = if l > 0.0 {
                        (d.as_vec2() / l as f32).perp() * half
                    } else {
                        Vec2::ZERO
                    };
                    pos.extend([a + n, a - n, b - n, b + n].map(|p| [p.x, p.y, 0.0]));
                    col.extend([palette.color(strain); 4]);
                }
            },
        );
    }
    if let Some(mut mesh) = meshes.get_mut(&batches.dots) {
        let radius = dot_radius(&view, &params);
        let rim: Vec<Vec2> = (0..DOT_SIDES)
            .map(|i| Vec2::from_angle(i as f32 * std::f32::consts::TAU / DOT_SIDES as f32) * radius)
            .collect();
        // A fan from the first corner: no centre vertex.
        let fan: Vec<u32> = (1..DOT_SIDES - 1).flat_map(|i| [0, i, i + 1]).collect();
        let (free, pinned, held) = (linear(PARTICLE), linear(PINNED), linear(HELD));
        fill(&mut mesh, solver.x.len(), DOT_SIDES, &fan, |pos, col| {
            for (i, x) in solver.x.iter().enumerate() {
                let c = x.as_vec2();
                pos.extend(rim.iter().map(|r| [c.x + r.x, c.y + r.y, 0.0]));
                let color = if Some(i) == held_index {
                    held
                } else if solver.is_pinned(i) {
                    pinned
                } else {
                    free
                };
                col.extend(std::iter::repeat_n(color, DOT_SIDES as usize));
            }
        });
    }
}

/// Refills a batched mesh of `items` shapes of `corners` vertices each, reusing its buffers;
/// the index list (`pattern` repeated per shape) is rebuilt only when the count changed.
fn fill(
    mesh: &mut Mesh,
    items: usize,
    corners: u32,
    pattern: &[u32],
    write: impl FnOnce(&mut Vec<[f32; 3]>, &mut Vec<[f32; 4]>),
) {
    let mut pos = take_attribute(mesh, Mesh::ATTRIBUTE_POSITION);
    let mut col = take_attribute(mesh, Mesh::ATTRIBUTE_COLOR);
    pos.clear();
    col.clear();
    write(&mut pos, &mut col);
    // No shapes: the placeholder triangle (see `empty_mesh`).
    let placeholder = items == 0;
    if placeholder {
        pos.extend([[0.0; 3]; 3]);
        col.extend([[0.0; 4]; 3]);
    }
    mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, pos);
    mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, col);
    let (shapes, corners, pattern) = if placeholder {
        (1, 3, &[0, 1, 2][..])
    } else {
        (items, corners, pattern)
    };
    if mesh.indices().map_or(0, Indices::len) != shapes * pattern.len() {
        let indices = (0..shapes as u32)
            .flat_map(|i| pattern.iter().map(move |&k| i * corners + k))
            .collect();
        mesh.insert_indices(Indices::U32(indices));
    }
}

/// Moves a vertex attribute's buffer out of the mesh, so that its allocation is reused.
fn take_attribute<T: Attribute>(mesh: &mut Mesh, id: bevy::mesh::MeshVertexAttribute) -> Vec<T> {
    mesh.remove_attribute(id)
        .and_then(T::unwrap)
        .unwrap_or_default()
}

/// The two vertex formats used here.
trait Attribute: Sized {
    fn unwrap(values: VertexAttributeValues) -> Option<Vec<Self>>;
}

impl Attribute for [f32; 3] {
    fn unwrap(values: VertexAttributeValues) -> Option<Vec<Self>> {
        match values {
            VertexAttributeValues::Float32x3(v) => Some(v),
            _ => None,
        }
    }
}

impl Attribute for [f32; 4] {
    fn unwrap(values: VertexAttributeValues) -> Option<Vec<Self>> {
        match values {
            VertexAttributeValues::Float32x4(v) => Some(v),
            _ => None,
        }
    }
}

/// Vertex colours are linear RGBA.
pub(super) fn linear(color: Color) -> [f32; 4] {
    color.to_linear().to_f32_array()
}

/// Strain colours, converted to linear once: white at rest, red when stretched, blue when
/// compressed, full colour at ±[`FULL_STRAIN`].
pub struct StrainPalette([[f32; 4]; Self::STEPS]);

impl StrainPalette {
    const STEPS: usize = 129;

    /// The palette's colours, from fully compressed to fully stretched.
    pub(super) fn entries(&self) -> &[[f32; 4]] {
        &self.0
    }

    fn color(&self, strain: f32) -> [f32; 4] {
        let t = (strain / FULL_STRAIN).clamp(-1.0, 1.0);
        // NaN (a blown-up spring) lands on the rest colour.
        let i = ((t + 1.0) * 0.5 * (Self::STEPS - 1) as f32).round() as usize;
        self.0[i.min(Self::STEPS - 1)]
    }
}

impl Default for StrainPalette {
    fn default() -> Self {
        StrainPalette(std::array::from_fn(|i| {
            let t = 2.0 * i as f32 / (Self::STEPS - 1) as f32 - 1.0;
            linear(strain_color(t))
        }))
    }
}

/// Colour for t = strain / full strain in [-1, 1].
fn strain_color(t: f32) -> Color {
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

/// The obstacles' outlines, at their poses (a few gizmo lines each), and the one a build drag
/// would make.
pub fn draw_obstacles(
    mut gizmos: Gizmos,
    obstacles: Query<(&Obstacle, &ObstaclePose)>,
    gesture: Res<Gesture>,
    view: Res<CanvasView>,
) {
    for (o, pose) in &obstacles {
        outline(&mut gizmos, o.0, pose.center, pose.angle, OBSTACLE);
    }
    if let Gesture::Build { kind, from, to } = *gesture {
        let least = super::pointer::CLICK_SLOP_PX as f64 * view.pixel();
        if let Some((shape, center)) = kind.shape(from, to, least) {
            outline(&mut gizmos, shape, center, 0.0, BUILDING);
        }
    }
}

/// avian's rigid bodies' colliders at their poses, in the obstacles' outlines: a dynamic body
/// in its own colour, the others as obstacles (they do not move either). A shape the particles
/// cannot touch (`sim::avian::obstacle_shapes` says which) is not drawn.
pub fn draw_bodies(
    mut gizmos: Gizmos,
    bodies: Query<(
        &avian2d::prelude::Collider,
        &avian2d::prelude::Position,
        &avian2d::prelude::Rotation,
        Option<&avian2d::prelude::RigidBody>,
    )>,
) {
    for (collider, at, turn, kind) in &bodies {
        let Ok(shapes) = crate::sim::avian::obstacle_shapes(collider) else {
            continue;
        };
        let color = if kind.is_some_and(|k| k.is_dynamic()) {
            BODY
        } else {
            OBSTACLE
        };
        let (center, angle) = (at.0.as_dvec2(), turn.as_radians() as f64);
        for (shape, offset, spin) in shapes {
            let c = center + DVec2::from_angle(angle).rotate(offset);
            outline(&mut gizmos, shape, c, angle + spin, color);
        }
    }
}

/// One obstacle's outline.
fn outline(
    gizmos: &mut Gizmos,
    shape: crate::solver::Shape,
    center: DVec2,
    angle: f64,
    color: Color,
) {
    use crate::solver::Shape;
    let (c, angle) = (center.as_vec2(), angle as f32);
    match shape {
        Shape::Circle { radius } => {
            gizmos.circle_2d(Isometry2d::from_translation(c), radius as f32, color);
        }
        Shape::Box { half } => {
            gizmos.rect_2d(
                Isometry2d::new(c, Rot2::radians(angle)),
                2.0 * half.as_vec2(),
                color,
            );
        }
        Shape::Segment { a, b, thickness } => {
            let turn = Rot2::radians(angle);
            let (a, b) = (c + turn * a.as_vec2(), c + turn * b.as_vec2());
            if thickness > 0.0 {
                let r = thickness as f32;
                let side = (b - a).normalize_or_zero().perp() * r;
                gizmos.line_2d(a + side, b + side, color);
                gizmos.line_2d(a - side, b - side, color);
                gizmos.circle_2d(Isometry2d::from_translation(a), r, color);
                gizmos.circle_2d(Isometry2d::from_translation(b), r, color);
            } else {
                gizmos.line_2d(a, b, color);
            }
        }
        Shape::Polygon(p) => {
            let turn = Rot2::radians(angle);
            let corners = p.corners().iter().map(|q| c + turn * q.as_vec2());
            gizmos.linestrip_2d(corners.clone().chain(corners.take(1)), color);
        }
    }
}

/// The unit square, the ground line across the window, and the attraction's circle.
pub fn draw_frame(
    mut gizmos: Gizmos,
    params: Res<SimParams>,
    view: Res<CanvasView>,
    attraction: Res<Attraction>,
) {
    gizmos.rect_2d(
        Isometry2d::from_translation(Vec2::splat(0.5)),
        Vec2::ONE,
        FRAME,
    );
    if let Some(g) = params.ground {
        let (min, max) = view.visible();
        let y = g as f32;
        gizmos.line_2d(
            Vec2::new(min.x as f32, y),
            Vec2::new(max.x as f32, y),
            GROUND,
        );
    }
    if let Some(at) = attraction.active_at {
        gizmos.circle_2d(
            Isometry2d::from_translation(at.as_vec2()),
            attraction.radius as f32,
            ATTRACTION,
        );
    }
}
