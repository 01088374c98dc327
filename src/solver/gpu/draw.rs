//! Drawing a state the card steps, on the card ([`draw.wgsl`]): the springs as quads coloured
//! by their strain and the particles as hexagons, written by two compute dispatches straight
//! into a mesh's vertex buffer, so that the picture never waits for the state to come back.
//!
//! The core knows no engine: a [`Painter`] takes a wgpu device and queue, a step's
//! [`DrawSource`] (its buffers), a [`DrawStyle`] (sizes and colours) and the vertex buffers
//! with the first vertex of each shape's run; an app finds those in its renderer's meshes.

use super::context::Precision;
use super::kernel::{empty, entries, pipeline, settings_buffer, shader, shape};
use super::step::GpuStep;

const SOURCE: &str = include_str!("draw.wgsl");
/// Threads in a work group (the kernels' `@workgroup_size`).
const GROUP: u32 = 64;
/// Vertices of a spring's quad and of a particle's hexagon.
pub const SPRING_CORNERS: u32 = 4;
/// Vertices of a particle's hexagon.
pub const DOT_CORNERS: u32 = 6;
/// Bytes of one vertex: (x, y, z) and a linear RGBA colour.
pub const VERTEX_BYTES: u64 = 28;

/// What the drawing reads of a step on the card: handles to its buffers (clones share them),
/// which stay valid while anyone holds them, the step's own copy dropped or not.
#[derive(Debug, Clone)]
pub struct DrawSource {
    x: [wgpu::Buffer; 2],
    current: usize,
    inv_mass: wgpu::Buffer,
    springs: wgpu::Buffer,
    particles: u32,
    spring_count: u32,
    precision: Precision,
}

impl DrawSource {
    /// Particles drawn: the dots' mesh holds [`DOT_CORNERS`] vertices each.
    pub fn particles(&self) -> u32 {
        self.particles
    }

    /// Springs drawn: the springs' mesh holds [`SPRING_CORNERS`] vertices each.
    pub fn springs(&self) -> u32 {
        self.spring_count
    }
}

/// How the state is drawn: sizes in metres, colours linear RGBA.
#[derive(Debug, Clone, PartialEq)]
pub struct DrawStyle {
    /// Half a spring's width.
    pub half_width: f32,
    /// A particle's radius.
    pub radius: f32,
    /// The strain drawn in the palette's end colours.
    pub full_strain: f32,
    /// The strain palette, from fully compressed through rest to fully stretched (at least one
    /// entry).
    pub palette: Vec<[f32; 4]>,
    /// A free particle's colour.
    pub free: [f32; 4],
    /// A pinned particle's (inverse mass 0) colour.
    pub pinned: [f32; 4],
    /// The held particle's colour.
    pub held_colour: [f32; 4],
    /// The particle held, if one is.
    pub held: Option<u32>,
}

/// Where a shape's vertices go: a vertex buffer (made with `STORAGE` usage), the first vertex
/// of the run and its vertices. Only the run is bound.
#[derive(Debug, Clone, Copy)]
pub struct DrawTarget<'a> {
    /// The vertex buffer.
    pub buffer: &'a wgpu::Buffer,
    /// The run's first vertex in it.
    pub first_vertex: u32,
    /// The run's vertices.
    pub vertices: u32,
}

/// Where the springs' quads and the dots go.
#[derive(Debug, Clone, Copy, Default)]
pub struct DrawTargets<'a> {
    /// The springs' mesh, or `None` to leave it.
    pub springs: Option<DrawTarget<'a>>,
    /// The dots' mesh, or `None` to leave it.
    pub dots: Option<DrawTarget<'a>>,
}

impl<'a> DrawTarget<'a> {
    /// The run's binding: its bytes from the offset alignment at or before its first vertex;
    /// and where its first vertex lies in that binding, in f32s.
    fn binding(self, alignment: u64) -> (wgpu::BufferBinding<'a>, u32) {
        let start = u64::from(self.first_vertex) * VERTEX_BYTES;
        let offset = start - start % alignment.max(1);
        let size = start + u64::from(self.vertices) * VERTEX_BYTES - offset;
        let binding = wgpu::BufferBinding {
            buffer: self.buffer,
            offset,
            size: wgpu::BufferSize::new(size.max(4)),
        };
        (binding, ((start - offset) / 4) as u32)
    }
}

/// The drawing's pipelines and buffers, made once for a device.
#[derive(Debug)]
pub struct Painter {
    /// (springs, dots) pipelines for f32 states, and for f64, made when first needed.
    pipelines: [Option<(wgpu::ComputePipeline, wgpu::ComputePipeline)>; 2],
    params: wgpu::Buffer,
    palette: wgpu::Buffer,
    palette_len: usize,
}

impl GpuStep {
    /// The buffers the drawing reads, as the steps submitted so far leave them; `None` when a
    /// mesh of the state's springs or dots is larger than the device binds at once.
    pub fn draw_source(&self) -> Option<DrawSource> {
        let (x, current, inv_mass, springs, binds) = self.draw_buffers();
        let (particles, spring_count) = (self.particle_count() as u64, self.spring_count() as u64);
        // A run's binding starts up to an offset alignment before its first vertex.
        let widest = (particles * u64::from(DOT_CORNERS))
            .max(spring_count * u64::from(SPRING_CORNERS))
            * VERTEX_BYTES
            + 256;
        (widest <= binds).then(|| DrawSource {
            x,
            current,
            inv_mass,
            springs,
            particles: particles as u32,
            spring_count: spring_count as u32,
            precision: self.precision(),
        })
    }
}

impl Painter {
    /// A painter for `device`.
    pub fn new(device: &wgpu::Device) -> Painter {
        Painter {
            pipelines: [None, None],
            params: settings_buffer(device, "draw settings", 112),
            palette: palette_buffer(device, 1),
            palette_len: 0,
        }
    }

    /// Records the drawing of `source` into `encoder`: the springs into `targets.springs`, the
    /// dots into `targets.dots` (each skipped when `None`, or when there is nothing to draw).
    /// The targets must hold [`DrawSource::springs`] × [`SPRING_CORNERS`] and
    /// [`DrawSource::particles`] × [`DOT_CORNERS`] vertices from their first.
    pub fn record(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        encoder: &mut wgpu::CommandEncoder,
        source: &DrawSource,
        style: &DrawStyle,
        targets: DrawTargets,
    ) {
        let DrawTargets { springs, dots } = targets;
        if style.palette.is_empty() {
            return;
        }
        let slot = usize::from(source.precision == Precision::F64);
        let (spring_pipeline, dot_pipeline) = self.pipelines[slot].get_or_insert_with(|| {
            let module = shader(device, SOURCE, "hooke draw", source.precision);
            (
                pipeline(device, &module, "draw_springs"),
                pipeline(device, &module, "draw_dots"),
            )
        });
        if self.palette_len != style.palette.len() {
            self.palette = palette_buffer(device, style.palette.len());
            self.palette_len = style.palette.len();
        }
        let colours: Vec<u8> = style
            .palette
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        queue.write_buffer(&self.palette, 0, &colours);
        let alignment = u64::from(device.limits().min_storage_buffer_offset_alignment);
        let springs = springs
            .filter(|_| source.spring_count > 0)
            .map(|t| t.binding(alignment));
        let dots = dots
            .filter(|_| source.particles > 0)
            .map(|t| t.binding(alignment));
        let words = [
            source.particles,
            source.spring_count,
            style.held.unwrap_or(u32::MAX),
            springs.as_ref().map_or(0, |t| t.1),
            dots.as_ref().map_or(0, |t| t.1),
            style.palette.len() as u32,
            0,
            0,
        ];
        let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let reals = [style.half_width, style.radius, style.full_strain, 0.0];
        bytes.extend(reals.iter().flat_map(|v| v.to_le_bytes()));
        for colour in [style.free, style.pinned, style.held_colour] {
            bytes.extend(colour.iter().flat_map(|v| v.to_le_bytes()));
        }
        queue.write_buffer(&self.params, 0, &bytes);
        let x = &source.x[source.current];
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hooke draw"),
            timestamp_writes: None,
        });
        let mut run = |pipeline: &wgpu::ComputePipeline,
                       list: &[(u32, &wgpu::Buffer)],
                       target: wgpu::BufferBinding,
                       items: u32| {
            let mut e = entries(list);
            e.push(wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::Buffer(target),
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke draw"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &e,
            });
            let (across, down) = shape(u64::from(items), GROUP);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(across, down, 1);
        };
        if let Some((target, _)) = springs {
            let list = [
                (0, &self.params),
                (1, x),
                (3, &source.springs),
                (4, &self.palette),
            ];
            run(spring_pipeline, &list, target, source.spring_count);
        }
        if let Some((target, _)) = dots {
            let list = [(0, &self.params), (1, x), (2, &source.inv_mass)];
            run(dot_pipeline, &list, target, source.particles);
        }
    }
}

fn palette_buffer(device: &wgpu::Device, entries: usize) -> wgpu::Buffer {
    empty(
        device,
        "strain palette",
        (16 * entries.max(1)) as u64,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    )
}
