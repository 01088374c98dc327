//! What a tick needs of the card's state without reading the state back ([`summary.wgsl`]): its
//! energy by kind and whether springs tore, reduced on the card into 32 bytes (64 in f64). The
//! app reads the state itself only for picking, plots of particles, saving and the CPU switch;
//! every other tick it reads this.

use super::context::{Gpu, Precision};
use super::kernel::{
    buffer, dispatch, empty, entries, pipeline, settings_buffer, shader, shape, submit,
    write_settings,
};
use crate::solver::state::Energy;

/// The kernels' source, in f32.
const SOURCE: &str = include_str!("summary.wgsl");
/// Threads in a work group (the kernels' `GROUP`).
const GROUP: u32 = 256;

/// What the card reports of its state each tick.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Summary {
    /// The state's energy by kind: the card's particles, with the fixed ones (pinned, or held
    /// by a drag) that the host moves.
    pub energy: Energy,
    /// Links torn since the host last took the torn springs (a spring has a link at each end).
    pub torn_links: u64,
    /// Contacts with surfaces, and pairs of particles touching, in the last step.
    pub contacts: [usize; 2],
}

/// The two reductions and their buffers.
#[derive(Debug)]
pub(super) struct SummaryPass {
    partials: wgpu::ComputePipeline,
    total: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// One vector a work group of `partials`, then the total.
    pub(super) sums: wgpu::Buffer,
    /// Bind groups of `partials` reading `x[g]` and `v[g]`, as the state's ping-pong leaves
    /// it; and of `total` (each pipeline's layout holds only the bindings it uses).
    groups: [wgpu::BindGroup; 2],
    total_group: wgpu::BindGroup,
    /// The dispatch of `partials`, and its work groups.
    dispatch: (u32, u32),
    count: u32,
}

/// The state's buffers the reductions read.
pub(super) struct Sources<'a> {
    pub x: [&'a wgpu::Buffer; 2],
    pub v: [&'a wgpu::Buffer; 2],
    pub w: &'a wgpu::Buffer,
    pub links: &'a wgpu::Buffer,
    pub spring: &'a wgpu::Buffer,
    /// Tearing's flags, when tearing is on.
    pub torn: Option<&'a wgpu::Buffer>,
}

impl SummaryPass {
    pub(super) fn new(
        gpu: &Gpu,
        precision: Precision,
        n: u32,
        dashpots: bool,
        b: Sources,
    ) -> SummaryPass {
        let device = &gpu.device;
        let source = if dashpots {
            SOURCE.replace("alias Link = vec2<real>;", "alias Link = vec4<real>;")
        } else {
            SOURCE.to_string()
        };
        let module = shader(device, &source, "hooke summary", precision);
        let partials = pipeline(device, &module, "partials");
        let total = pipeline(device, &module, "total");
        let dispatch = shape(u64::from(n), GROUP);
        let count = dispatch.0 * dispatch.1;
        let params = settings_buffer(device, "summary settings", 64);
        let sums = empty(
            device,
            "summary sums",
            (u64::from(count) + 1) * 4 * precision.bytes() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let none = buffer(device, "no torn links", &[], wgpu::BufferUsages::STORAGE);
        let torn = b.torn.unwrap_or(&none);
        let layout = partials.get_bind_group_layout(0);
        let bind = |at: usize| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke summary"),
                layout: &layout,
                entries: &entries(&[
                    (0, &params),
                    (1, b.x[at]),
                    (2, b.v[at]),
                    (3, b.w),
                    (4, b.links),
                    (5, b.spring),
                    (6, torn),
                    (7, &sums),
                ]),
            })
        };
        let groups = [bind(0), bind(1)];
        let total_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hooke summary total"),
            layout: &total.get_bind_group_layout(0),
            entries: &entries(&[(0, &params), (7, &sums)]),
        });
        SummaryPass {
            partials,
            total,
            params,
            sums,
            groups,
            total_group,
            dispatch,
            count,
        }
    }

    /// Records the reductions of the state in `x[current]`, `v[current]` under `gravity`; the
    /// total lands at [`Self::total_at`] of `sums`.
    pub(super) fn record(
        &self,
        gpu: &Gpu,
        precision: Precision,
        (n, current): (u32, usize),
        gravity: glam::DVec2,
    ) {
        write_settings(
            &gpu.queue,
            &self.params,
            precision,
            [n, self.dispatch.0 * GROUP, self.count, 0],
            &[gravity.x, gravity.y],
        );
        submit(gpu, "hooke summary", |pass| {
            dispatch(pass, &self.partials, &self.groups[current], self.dispatch);
            dispatch(pass, &self.total, &self.total_group, (1, 1));
        });
    }

    /// Where the total starts in `sums`, and its length, in bytes.
    pub(super) fn total_at(&self, precision: Precision) -> (u64, u64) {
        let width = 4 * precision.bytes() as u64;
        (u64::from(self.count) * width, width)
    }
}
