//! Tearing on the card ([`tear.wgsl`]): as the CPU's tick does, every `every` steps each link
//! stretched past (1 + strain) × rest is marked torn; the step reads the marks back and names
//! the springs.

use super::context::{Gpu, Precision};
use super::kernel::{dispatch, empty, entries, pipeline, settings_buffer, shader, write_settings};
use super::settings::TearSettings;

/// Tearing's kernel, in f32.
const TEAR: &str = include_str!("tear.wgsl");

/// Tearing's pipeline and buffers.
#[derive(Debug)]
pub(super) struct TearPass {
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// A word a link, not zero once the link tore (cleared by the step once read).
    pub(super) torn: wgpu::Buffer,
    /// Links (each spring twice, once from each end).
    pub(super) links: usize,
    /// Bind group `g` reads the positions in `x[g]`.
    groups: [wgpu::BindGroup; 2],
    /// Steps between the looks.
    pub(super) every: u32,
}

/// The step's buffers tearing reads: the positions (ping-ponged by the step), the links'
/// indices and their records, and how many links there are.
pub(super) struct LinkBuffers<'a> {
    pub x: [&'a wgpu::Buffer; 2],
    pub index: &'a wgpu::Buffer,
    pub spring: &'a wgpu::Buffer,
    pub links: usize,
    /// The records hold (k, L, c, 0), not (k, L).
    pub dashpots: bool,
}

impl TearPass {
    pub(super) fn new(
        gpu: &Gpu,
        precision: Precision,
        buffers: LinkBuffers,
        settings: TearSettings,
    ) -> TearPass {
        let LinkBuffers {
            x,
            index,
            spring,
            links,
            dashpots,
        } = buffers;
        let source = if dashpots {
            TEAR.replace("alias Link = vec2<real>;", "alias Link = vec4<real>;")
        } else {
            TEAR.to_string()
        };
        let device = &gpu.device;
        let module = shader(device, &source, "hooke tear", precision);
        let pipeline = pipeline(device, &module, "tear");
        let params = settings_buffer(device, "tear settings", 32);
        let torn = empty(
            device,
            "torn links",
            (4 * links.max(4)) as u64,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        );
        let layout = pipeline.get_bind_group_layout(0);
        let bind = |at: usize| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke tear"),
                layout: &layout,
                entries: &entries(&[
                    (0, &params),
                    (1, x[at]),
                    (2, index),
                    (3, spring),
                    (4, &torn),
                ]),
            })
        };
        let groups = [bind(0), bind(1)];
        TearPass {
            pipeline,
            params,
            torn,
            links,
            groups,
            every: settings.every.max(1),
        }
    }

    /// Writes the strain past which a link tears, for `n` particles over a dispatch `across`
    /// threads wide (how often it looks is fixed when the pass is made).
    pub(super) fn set(
        &self,
        gpu: &Gpu,
        precision: Precision,
        (n, across): (u32, u32),
        strain: f64,
    ) {
        let values = [1.0 + strain, 0.0];
        write_settings(
            &gpu.queue,
            &self.params,
            precision,
            [n, across, 0, 0],
            &values,
        );
    }

    /// Records one look at the positions in `x[current]`, over the dispatch shape `particles`.
    pub(super) fn record(
        &self,
        pass: &mut wgpu::ComputePass,
        current: usize,
        particles: (u32, u32),
    ) {
        dispatch(pass, &self.pipeline, &self.groups[current], particles);
    }

    /// Clears the marks once the step has read them.
    pub(super) fn clear(&self, gpu: &Gpu) {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("clear torn"),
            });
        encoder.clear_buffer(&self.torn, 0, None);
        gpu.queue.submit([encoder.finish()]);
    }
}
