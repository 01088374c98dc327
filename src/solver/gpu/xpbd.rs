//! XPBD on the card ([`xpbd.wgsl`]): the CPU's colouring and coefficients
//! ([`crate::solver::methods::xpbd`]), one dispatch a colour a sweep, so that the sweeps are
//! the CPU's Gauss-Seidel sweeps in the CPU's order; with contact, the CPU's contact inside
//! the substeps (`contact/inside.rs`): the iterate held out of the surfaces before the first
//! prediction and after each substep's sweeps, and particle pairs pushed apart there.

use super::contact::{ContactPass, Iterate};
use super::context::{Gpu, Precision};
use super::kernel::{
    buffer, dispatch, entries, pipeline, reals, settings_buffer, shader, write_settings,
};
use super::settings::ExplicitSettings;
use crate::solver::methods::xpbd::coloured;
use crate::solver::state::State;

const SOURCE: &str = include_str!("xpbd.wgsl");
/// The uniform slots' stride: wgpu's least offset alignment for uniform bindings.
const SLOT: u64 = 256;
/// Threads in a work group (the kernel's `@workgroup_size`).
const GROUP: u32 = 256;

/// XPBD's pipelines, buffers and bind groups for one state.
#[derive(Debug)]
pub(super) struct XpbdPass {
    begin: (wgpu::ComputePipeline, wgpu::BindGroup),
    predict: (wgpu::ComputePipeline, [wgpu::BindGroup; 2]),
    project: (wgpu::ComputePipeline, Vec<wgpu::BindGroup>),
    finish: (wgpu::ComputePipeline, wgpu::BindGroup),
    /// The settings (`xpbd.wgsl`'s `Params`), written by [`Self::set`].
    params: wgpu::Buffer,
    /// The iterate, each substep's start, and each particle's heading before contact: what
    /// the contact inside the substeps reads and writes.
    pos: wgpu::Buffer,
    prev: wgpu::Buffer,
    heading: wgpu::Buffer,
    /// Constraints in each colour.
    colours: Vec<u32>,
    substeps: u32,
    sweeps: u32,
}

/// The state's buffers XPBD works on.
pub(super) struct StateBuffers<'a> {
    pub x: &'a wgpu::Buffer,
    pub v: &'a wgpu::Buffer,
    pub w: &'a wgpu::Buffer,
    pub external: &'a wgpu::Buffer,
}

impl XpbdPass {
    pub(super) fn new(
        gpu: &Gpu,
        precision: Precision,
        state: &State,
        (dt, substeps, sweeps): (f64, u32, u32),
        buffers: StateBuffers,
    ) -> XpbdPass {
        let device = &gpu.device;
        let substeps = substeps.max(1);
        let sweeps = sweeps.max(1);
        let hs = dt / substeps as f64;
        let c = coloured(state, hs);
        let module = shader(device, SOURCE, "hooke xpbd", precision);
        let pipeline = |entry: &str| pipeline(device, &module, entry);
        let storage = wgpu::BufferUsages::STORAGE;
        let init = |label: &str, contents: Vec<u8>, usage| buffer(device, label, &contents, usage);
        let n = state.particle_count();
        let zeros = vec![0u8; n * 2 * precision.bytes()];
        let pos = init("xpbd positions", zeros.clone(), storage);
        let prev = init("xpbd substep starts", zeros.clone(), storage);
        let heading = init("xpbd headings", zeros, storage);
        let ends: Vec<u8> = c
            .ends
            .iter()
            .flat_map(|&(a, b)| [a.to_le_bytes(), b.to_le_bytes()].concat())
            .collect();
        let ends = init("xpbd ends", ends, storage);
        let flat: Vec<f64> = c
            .coefficients
            .iter()
            .flat_map(|k| k.iter().copied().chain([0.0]))
            .collect();
        let coef = init("xpbd coefficients", reals(&flat, precision), storage);
        let params = settings_buffer(device, "xpbd settings", 96);
        // The slots: colour c's first sweep at 2c, its later sweeps at 2c + 1; the first
        // substep's prediction, then the others'.
        let colours: Vec<u32> = c
            .colour_starts
            .windows(2)
            .map(|w| (w[1] - w[0]) as u32)
            .collect();
        let count = colours.len();
        let mut slots = vec![0u8; (2 * count + 2) * SLOT as usize];
        let mut put = |at: usize, values: [u32; 4]| {
            let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            slots[at * SLOT as usize..at * SLOT as usize + 16].copy_from_slice(&bytes);
        };
        for (k, w) in c.colour_starts.windows(2).enumerate() {
            put(2 * k, [w[0] as u32, w[1] as u32, 1, 0]);
            put(2 * k + 1, [w[0] as u32, w[1] as u32, 0, 0]);
        }
        put(2 * count, [0, 0, 1, 0]);
        put(2 * count + 1, [0, 0, 0, 0]);
        let slots = init("xpbd slots", slots, wgpu::BufferUsages::UNIFORM);
        let slot = |k: usize| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &slots,
                offset: k as u64 * SLOT,
                size: wgpu::BufferSize::new(16),
            })
        };
        let group = |pipeline: &wgpu::ComputePipeline, list: &[(u32, &wgpu::Buffer)], s| {
            let mut e = entries(list);
            if let Some(k) = s {
                e.push(wgpu::BindGroupEntry {
                    binding: 1,
                    resource: slot(k),
                });
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke xpbd"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &e,
            })
        };
        let StateBuffers { x, v, w, external } = buffers;
        let begin = pipeline("begin");
        let beginning = [
            (0, &params),
            (2, &pos),
            (4, v),
            (5, x),
            (6, w),
            (7, external),
            (10, &heading),
        ];
        let begin_group = group(&begin, &beginning, None);
        let predict = pipeline("predict");
        let predicting = [
            (0, &params),
            (2, &pos),
            (3, &prev),
            (4, v),
            (6, w),
            (7, external),
        ];
        let predict_groups = [
            group(&predict, &predicting, Some(2 * count)),
            group(&predict, &predicting, Some(2 * count + 1)),
        ];
        let project = pipeline("project");
        let projecting = [(0, &params), (2, &pos), (3, &prev), (8, &ends), (9, &coef)];
        let project_groups = (0..2 * count)
            .map(|k| group(&project, &projecting, Some(k)))
            .collect();
        let finish = pipeline("finish");
        let finish_group = group(
            &finish,
            &[(0, &params), (2, &pos), (3, &prev), (4, v), (5, x), (6, w)],
            None,
        );
        XpbdPass {
            begin: (begin, begin_group),
            predict: (predict, predict_groups),
            project: (project, project_groups),
            finish: (finish, finish_group),
            params,
            pos,
            prev,
            heading,
            colours,
            substeps,
            sweeps,
        }
    }

    /// Writes the settings for `n` particles over a dispatch `across` threads wide: with
    /// `external` forces on, and `dashpots` in the constraints; `decay` is the step's
    /// exp(−μ dt).
    pub(super) fn set(
        &self,
        gpu: &Gpu,
        precision: Precision,
        (n, across): (u32, u32),
        settings: &ExplicitSettings,
        (external, dashpots): (bool, bool),
        decay: f64,
    ) {
        let hs = self.substep(settings.dt);
        // With contact set, the ground is the contact pass's.
        let floor = settings.ground.filter(|_| settings.contact.is_none());
        let flags =
            u32::from(floor.is_some()) | (u32::from(external) << 1) | (u32::from(dashpots) << 2);
        let values = [
            settings.gravity.x,
            settings.gravity.y,
            hs,
            1.0 / hs,
            floor.unwrap_or(0.0),
            settings.dt,
            1.0 / settings.dt,
            decay,
        ];
        write_settings(
            &gpu.queue,
            &self.params,
            precision,
            [n, across, flags, 0],
            &values,
        );
    }

    /// A substep of a step of `dt`.
    pub(super) fn substep(&self, dt: f64) -> f64 {
        dt / f64::from(self.substeps)
    }

    /// The buffers the contact inside the substeps reads and writes.
    pub(super) fn iterate(&self) -> Iterate<'_> {
        Iterate {
            pos: &self.pos,
            prev: &self.prev,
            heading: &self.heading,
        }
    }

    /// Records one step, with `contact` inside the substeps when the scene has it.
    pub(super) fn record(
        &self,
        pass: &mut wgpu::ComputePass,
        particles: (u32, u32),
        contact: Option<&ContactPass>,
    ) {
        let run = dispatch;
        run(pass, &self.begin.0, &self.begin.1, particles);
        for substep in 0..self.substeps {
            if let Some(c) = contact.filter(|_| substep == 0) {
                c.record_entry(pass, particles);
            }
            let first = usize::from(substep != 0);
            run(pass, &self.predict.0, &self.predict.1[first], particles);
            for sweep in 0..self.sweeps {
                for (c, &size) in self.colours.iter().enumerate() {
                    let group = &self.project.1[2 * c + usize::from(sweep != 0)];
                    let groups = size.div_ceil(GROUP).max(1);
                    run(pass, &self.project.0, group, (groups, 1));
                }
            }
            if let Some(c) = contact {
                c.record_substep_end(pass, particles);
            }
        }
        run(pass, &self.finish.0, &self.finish.1, particles);
    }
}
