//! Contact between particles on the card ([`pairs.wgsl`]): the CPU's Jacobi iterations and
//! velocity pass ([`crate::solver::contact::pairs`]) over neighbours found through a spatial
//! hash rebuilt every step (count, prefix sum, fill).
//!
//! The iterations stop as the CPU's do, once the deepest overlap is under 1 % of 2r: every
//! one of the [`MAX_ITERATIONS`] is recorded, and one whose predecessor found nothing deeper
//! returns at once, so the card never waits on the host to decide. The grid is rebuilt each
//! step rather than kept with a skin: on the card a rebuild is a few passes over the particles,
//! cheaper than the reduction that would tell when it is due.

use super::context::{Gpu, Precision};
use super::kernel::{buffer, dispatch, empty, entries, pipeline, shape};
use crate::solver::contact::pairs::MAX_ITERATIONS;

/// Threads in a work group (the kernels' `@workgroup_size`).
const GROUP: u32 = 256;
/// The uniform slots' stride: wgpu's least offset alignment for uniform bindings.
const SLOT: u64 = 256;
/// The control words (`pairs.wgsl`'s `control`).
pub(super) const CONTROL_WORDS: u64 = 40;

/// The buffers of the state that the pair contact reads and writes.
pub(super) struct Bound<'a> {
    /// The contact pass's settings (`contact.wgsl`'s `Params`).
    pub params: &'a wgpu::Buffer,
    /// The positions and velocities each target pushes apart: after the explicit step that
    /// read `x[0]` (it wrote `x[1]`), after the one that read `x[1]`; under XPBD the state's,
    /// then the substeps' iterate.
    pub targets: Vec<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
    /// Inverse masses.
    pub w: &'a wgpu::Buffer,
    /// The obstacles (the iterations keep moved particles out of them).
    pub obstacles: &'a wgpu::Buffer,
    /// The step's links (each particle's start, then the other ends).
    pub links: &'a wgpu::Buffer,
    /// The control words.
    pub control: &'a wgpu::Buffer,
}

/// The bind groups of one target's positions and velocities.
#[derive(Debug)]
struct Target {
    count: wgpu::BindGroup,
    /// The k-th iteration's, then the two pushes of a substep.
    separate: Vec<wgpu::BindGroup>,
    settle: wgpu::BindGroup,
    respond: wgpu::BindGroup,
    take: wgpu::BindGroup,
    begin: wgpu::BindGroup,
    follow: wgpu::BindGroup,
}

/// The pair contact's pipelines, buffers and bind groups for one state.
#[derive(Debug)]
pub(super) struct PairPass {
    /// The hash's slots, a power of two at least twice the particles.
    pub(super) table: u32,
    clear: (wgpu::ComputePipeline, wgpu::BindGroup),
    count: wgpu::ComputePipeline,
    scan_groups: (wgpu::ComputePipeline, wgpu::BindGroup),
    scan_sums: (wgpu::ComputePipeline, wgpu::BindGroup),
    scan_add: (wgpu::ComputePipeline, wgpu::BindGroup),
    fill: (wgpu::ComputePipeline, wgpu::BindGroup),
    separate: wgpu::ComputePipeline,
    settle: wgpu::ComputePipeline,
    respond: wgpu::ComputePipeline,
    take: wgpu::ComputePipeline,
    begin: wgpu::ComputePipeline,
    follow: wgpu::ComputePipeline,
    targets: Vec<Target>,
    /// Work groups over the particles, and over the slots and their sum (a group a block of
    /// the prefix sum's first level).
    particles: (u32, u32),
    slots: (u32, u32),
}

/// Jacobi passes over the pairs after each of XPBD's substeps (the CPU's `PAIR_PASSES`).
const PUSHES: usize = 2;

impl PairPass {
    /// The table's slots for `n` particles.
    pub(super) fn table_for(n: usize) -> u32 {
        (2 * n.max(1)).next_power_of_two() as u32
    }

    pub(super) fn new(
        gpu: &Gpu,
        module: &wgpu::ShaderModule,
        precision: Precision,
        n: usize,
        b: Bound,
    ) -> PairPass {
        let device = &gpu.device;
        let table = Self::table_for(n);
        let blocks = (u64::from(table) + 1).div_ceil(u64::from(GROUP));
        let storage = wgpu::BufferUsages::STORAGE;
        let empty = |label: &str, bytes: u64| {
            empty(device, label, bytes.max(16).next_multiple_of(16), storage)
        };
        let n64 = n as u64;
        let vectors = n64 * 2 * precision.bytes() as u64;
        let scratch = empty("pair scratch", vectors);
        let before = empty("pair start", vectors);
        let grid = empty("pair grid", (u64::from(table) + 1 + n64) * 4);
        let sums = empty("pair block sums", blocks * 4);
        let homes = empty("pair cells", n64 * 8);
        let ranks = empty("pair ranks", n64 * 4);
        // The rounds: the iterations', then the substeps' pushes.
        let rounds: Vec<[u32; 2]> = (0..MAX_ITERATIONS as u32)
            .map(|k| [k, 0])
            .chain((0..PUSHES as u32).map(|k| [k, 1]))
            .collect();
        let mut slots = vec![0u8; rounds.len() * SLOT as usize];
        for (at, round) in rounds.iter().enumerate() {
            let bytes: Vec<u8> = round.iter().flat_map(|v| v.to_le_bytes()).collect();
            slots[at * SLOT as usize..at * SLOT as usize + 8].copy_from_slice(&bytes);
        }
        let slots = buffer(device, "pair rounds", &slots, wgpu::BufferUsages::UNIFORM);
        let pipe = |entry: &str| pipeline(device, module, entry);
        let group = |pipeline: &wgpu::ComputePipeline, list: &[(u32, &wgpu::Buffer)], round| {
            let mut e = entries(list);
            if let Some(k) = round {
                e.push(wgpu::BindGroupEntry {
                    binding: 20,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &slots,
                        offset: k as u64 * SLOT,
                        size: wgpu::BufferSize::new(16),
                    }),
                });
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke pairs"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &e,
            })
        };
        let p = b.params;
        let clear = pipe("pair_clear");
        let clear_group = group(&clear, &[(0, p), (13, &grid), (19, b.control)], None);
        let count = pipe("pair_count");
        let scan_groups = pipe("scan_groups");
        let scan_groups_group = group(&scan_groups, &[(0, p), (13, &grid), (14, &sums)], None);
        let scan_sums = pipe("scan_sums");
        let scan_sums_group = group(&scan_sums, &[(0, p), (14, &sums)], None);
        let scan_add = pipe("scan_add");
        let scan_add_group = group(&scan_add, &[(0, p), (13, &grid), (14, &sums)], None);
        let fill = pipe("pair_fill");
        let fill_group = group(
            &fill,
            &[(0, p), (13, &grid), (16, &homes), (17, &ranks)],
            None,
        );
        let (separate, settle, respond) = (
            pipe("pair_separate"),
            pipe("pair_settle"),
            pipe("pair_respond"),
        );
        let (take, begin, follow) = (pipe("pair_take"), pipe("pair_begin"), pipe("pair_follow"));
        let targets = b
            .targets
            .iter()
            .map(|&(x, v)| {
                let pushing = |k: usize, round: usize| {
                    // Even rounds from the target into the scratch, odd ones back.
                    let (from, to) = if k.is_multiple_of(2) {
                        (x, &scratch)
                    } else {
                        (&scratch, x)
                    };
                    let list = [
                        (0, p),
                        (10, from),
                        (11, to),
                        (4, b.w),
                        (5, b.obstacles),
                        (13, &grid),
                        (16, &homes),
                        (18, b.links),
                        (19, b.control),
                    ];
                    group(&separate, &list, Some(round))
                };
                let iterations = (0..MAX_ITERATIONS).map(|k| pushing(k, k));
                let pushes = (0..PUSHES).map(|k| pushing(k, MAX_ITERATIONS + k));
                let responding = [
                    (0, p),
                    (10, x),
                    (21, v),
                    (22, &scratch),
                    (4, b.w),
                    (13, &grid),
                    (16, &homes),
                    (18, b.links),
                    (19, b.control),
                ];
                let counting = [(0, p), (10, x), (12, &grid), (16, &homes), (17, &ranks)];
                Target {
                    count: group(&count, &counting, None),
                    separate: iterations.chain(pushes).collect(),
                    settle: group(
                        &settle,
                        &[(0, p), (10, &scratch), (11, x), (19, b.control)],
                        None,
                    ),
                    respond: group(&respond, &responding, None),
                    take: group(&take, &[(0, p), (10, &scratch), (3, v)], None),
                    begin: group(&begin, &[(0, p), (10, x), (26, &before)], None),
                    follow: group(&follow, &[(0, p), (10, x), (26, &before), (3, v)], None),
                }
            })
            .collect();
        PairPass {
            table,
            clear: (clear, clear_group),
            count,
            scan_groups: (scan_groups, scan_groups_group),
            scan_sums: (scan_sums, scan_sums_group),
            scan_add: (scan_add, scan_add_group),
            fill: (fill, fill_group),
            separate,
            settle,
            respond,
            take,
            begin,
            follow,
            targets,
            particles: shape(n64, GROUP),
            slots: shape(u64::from(table) + 1, GROUP),
        }
    }

    /// Records the grid of `target`'s positions.
    fn build(&self, pass: &mut wgpu::ComputePass, target: &Target) {
        let run = dispatch;
        run(pass, &self.clear.0, &self.clear.1, self.slots);
        run(pass, &self.count, &target.count, self.particles);
        run(pass, &self.scan_groups.0, &self.scan_groups.1, self.slots);
        run(pass, &self.scan_sums.0, &self.scan_sums.1, (1, 1));
        run(pass, &self.scan_add.0, &self.scan_add.1, self.slots);
        run(pass, &self.fill.0, &self.fill.1, self.particles);
    }

    /// Records the pair contact after a step, on target `target`'s positions and velocities:
    /// the iterations, then (with `follows`, for the methods whose velocity is where the step
    /// went) the push into the velocity, then the velocity pass.
    pub(super) fn record(&self, pass: &mut wgpu::ComputePass, target: usize, follows: bool) {
        let run = dispatch;
        let t = &self.targets[target];
        self.build(pass, t);
        if follows {
            run(pass, &self.begin, &t.begin, self.particles);
        }
        for group in &t.separate[..MAX_ITERATIONS] {
            run(pass, &self.separate, group, self.particles);
        }
        run(pass, &self.settle, &t.settle, self.particles);
        if follows {
            run(pass, &self.follow, &t.follow, self.particles);
        }
        run(pass, &self.respond, &t.respond, self.particles);
        run(pass, &self.take, &t.take, self.particles);
    }

    /// Records the pushes after one of XPBD's substeps on target `target`'s positions.
    pub(super) fn record_pushes(&self, pass: &mut wgpu::ComputePass, target: usize) {
        let t = &self.targets[target];
        self.build(pass, t);
        for group in &t.separate[MAX_ITERATIONS..] {
            dispatch(pass, &self.separate, group, self.particles);
        }
    }
}
