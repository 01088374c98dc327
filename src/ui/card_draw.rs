//! Drawing the card's state on the card: while the ticks step there, the springs' and the
//! dots' meshes are written by a compute pass from the card's own buffers
//! ([`crate::solver::gpu::Painter`]), in the render world before the cameras draw, as Bevy's
//! `compute_mesh` example fills a mesh. The meshes keep their sizes from the CPU's drawing
//! ([`super::draw::update_batches`], which then leaves their vertices alone), so the picture is
//! the card's latest state, never waiting for it to come back.

use super::draw::{self, Batches};
use super::pointer::Gesture;
use super::view::CanvasView;
use crate::sim::gpu::CardStep;
use crate::sim::{SimParams, SolverIndex};
use crate::solver::gpu::{
    DOT_CORNERS, DrawSource, DrawStyle, DrawTarget, DrawTargets, Painter, SPRING_CORNERS,
};
use bevy::core_pipeline::schedule::camera_driver;
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::mesh::allocator::{MeshAllocator, MeshAllocatorSettings};
use bevy::render::render_resource::BufferUsages;
use bevy::render::renderer::{RenderContext, RenderDevice, RenderGraph, RenderQueue};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// What the render world draws from the card this frame: the card's buffers, the meshes and
/// the style; `None` while the ticks step on the CPU.
#[derive(Resource, Clone, Default)]
pub struct CardPicture {
    picture: Option<Picture>,
    /// Frames the render world drew from the card (shared with it).
    pub drawn: Arc<AtomicU64>,
}

#[derive(Clone)]
struct Picture {
    source: DrawSource,
    springs: AssetId<Mesh>,
    dots: AssetId<Mesh>,
    style: DrawStyle,
}

impl ExtractResource for CardPicture {
    type Source = CardPicture;
    fn extract_resource(source: &Self::Source) -> Self {
        source.clone()
    }
}

impl CardPicture {
    /// Whether the meshes are drawn from the card this frame.
    pub fn active(&self) -> bool {
        self.picture.is_some()
    }

    /// Frames drawn from the card so far.
    pub fn frames_drawn(&self) -> u64 {
        self.drawn.load(Ordering::Relaxed)
    }
}

/// The card's drawing: the picture chosen in the main world, drawn in the render world.
pub struct CardDrawPlugin;

impl Plugin for CardDrawPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<CardPicture>()
            .add_plugins(ExtractResourcePlugin::<CardPicture>::default())
            .add_systems(PostUpdate, choose_picture);
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app.add_systems(RenderGraph, paint.before(camera_driver));
        }
    }

    fn finish(&self, app: &mut App) {
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        // The meshes' vertex buffers are written by the compute pass.
        if let Some(mut settings) = render_app
            .world_mut()
            .get_resource_mut::<MeshAllocatorSettings>()
        {
            settings.extra_buffer_usages |= BufferUsages::STORAGE;
        }
    }
}

/// The picture for this frame: the card's buffers while the ticks step there.
#[allow(clippy::too_many_arguments)] // a Bevy system: its parameters are what it reads
fn choose_picture(
    card: Option<Res<CardStep>>,
    batches: Option<Res<Batches>>,
    view: Res<CanvasView>,
    params: Res<SimParams>,
    gesture: Res<Gesture>,
    indices: Query<&SolverIndex>,
    mut picture: ResMut<CardPicture>,
    palette: Local<draw::StrainPalette>,
) {
    let source = card.and_then(|c| c.draw_source());
    let (Some(source), Some(batches)) = (source, batches) else {
        if picture.picture.is_some() {
            picture.picture = None;
        }
        return;
    };
    let held = draw::held(&gesture, &indices);
    let style = DrawStyle {
        half_width: draw::SPRING_HALF_PX / view.scale,
        radius: draw::dot_radius(&view, &params),
        full_strain: draw::FULL_STRAIN,
        palette: palette.entries().to_vec(),
        free: draw::linear(draw::PARTICLE),
        pinned: draw::linear(draw::PINNED),
        held_colour: draw::linear(draw::HELD),
        held,
    };
    picture.picture = Some(Picture {
        source,
        springs: batches.springs.id(),
        dots: batches.dots.id(),
        style,
    });
}

/// Render world: the meshes' vertices written from the card, before the cameras draw. A mesh
/// whose allocation does not yet hold the card's count (it was resized this frame and not yet
/// uploaded) is left as the CPU drew it.
fn paint(
    mut context: RenderContext,
    picture: Option<Res<CardPicture>>,
    allocator: Res<MeshAllocator>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut painter: Local<Option<Painter>>,
) {
    let Some(shared) = picture else { return };
    let Some(p) = &shared.picture else { return };
    let fits = |id: &AssetId<Mesh>, items: u32, corners: u32| {
        allocator
            .mesh_vertex_slice(id)
            .filter(|s| items > 0 && s.range.len() as u32 == items * corners)
    };
    let springs = fits(&p.springs, p.source.springs(), SPRING_CORNERS);
    let dots = fits(&p.dots, p.source.particles(), DOT_CORNERS);
    if springs.is_none() && dots.is_none() {
        return;
    }
    let device = device.wgpu_device();
    let painter = painter.get_or_insert_with(|| Painter::new(device));
    let queue: &wgpu::Queue = &queue.0;
    let springs = springs.as_ref().map(|s| DrawTarget {
        buffer: s.buffer,
        first_vertex: s.range.start,
        vertices: s.range.len() as u32,
    });
    let dots = dots.as_ref().map(|s| DrawTarget {
        buffer: s.buffer,
        first_vertex: s.range.start,
        vertices: s.range.len() as u32,
    });
    let encoder = context.command_encoder();
    let targets = DrawTargets { springs, dots };
    painter.record((device, queue), encoder, &p.source, &p.style, targets);
    shared.drawn.fetch_add(1, Ordering::Relaxed);
}
