//! The explicit step on the card: one WGSL kernel a step ([`explicit.wgsl`]), many steps a
//! submit, the state read back only when asked.
//!
//! The layout is the lean one: per particle its position, velocity and inverse mass (0 for a
//! pin, so the kick needs no flag); per particle a list of its links (a spring appears in both
//! ends' lists), each link its other end and its (k, L) read together. Each thread gathers
//! its own particle's force, so no two threads write one value and no atomics are needed: a
//! spring's length is computed twice, once per end, which costs less on a card than a scatter.

use super::context::{Gpu, GpuError, Precision};
use crate::solver::state::State;
use glam::DVec2;
use wgpu::util::DeviceExt;

/// The kernel's source, in f32.
const SOURCE: &str = include_str!("explicit.wgsl");
/// Threads in a work group (the kernel's `@workgroup_size`).
const GROUP: u32 = 256;
/// The most work groups along one side of a dispatch.
const MAX_GROUPS: u32 = 65_535;

/// Which explicit method the kernel runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExplicitMethod {
    /// Move with the velocity after the kick (and damping and ground).
    SymplecticEuler,
    /// Move with the velocity from before the kick.
    ExplicitEuler,
}

/// The step's settings: what `SimParams` says, in the core's words.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitSettings {
    /// The method.
    pub method: ExplicitMethod,
    /// Time step, s.
    pub dt: f64,
    /// Gravity, m/s².
    pub gravity: DVec2,
    /// Damping rate μ, 1/s (v *= exp(−μ dt) a step).
    pub damping: f64,
    /// The ground's height, when there is one.
    pub ground: Option<f64>,
}

/// One packed state on the card, and the pipeline that steps it.
#[derive(Debug)]
pub struct GpuStep {
    gpu: Gpu,
    precision: Precision,
    n: u32,
    springs: usize,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// Positions, ping-ponged: `x[current]` holds the state.
    x: [wgpu::Buffer; 2],
    v: wgpu::Buffer,
    /// Bind group `g` reads `x[g]` and writes `x[1 - g]`.
    groups: [wgpu::BindGroup; 2],
    current: usize,
    dispatch: (u32, u32),
    steps: u64,
}

impl GpuStep {
    /// Uploads `state` to the card in `precision`, with the step's settings. The state's
    /// materials, if any, are not run here: the caller checks [`GpuStep::unsupported`] first.
    pub fn new(
        gpu: &Gpu,
        state: &State,
        settings: &ExplicitSettings,
        precision: Precision,
    ) -> Result<GpuStep, GpuError> {
        if precision == Precision::F64 && !gpu.has_f64() {
            return Err(GpuError::NoDevice(format!(
                "{} does not compute in f64",
                gpu.adapter()
            )));
        }
        let n = state.particle_count();
        let (starts, others, ks) = links(state);
        let limits = gpu.device.limits();
        let widest = (others.len().max(n) * 2 * precision.bytes()) as u64;
        if widest > limits.max_storage_buffer_binding_size
            || widest > limits.max_buffer_size
            || n >= u32::MAX as usize / 2
        {
            return Err(GpuError::TooLarge(format!(
                "{n} particles and {} springs need a buffer of {widest} bytes; the adapter allows {}",
                state.spring_count(),
                limits.max_storage_buffer_binding_size
            )));
        }
        let device = &gpu.device;
        let source = match precision {
            Precision::F32 => SOURCE.to_string(),
            Precision::F64 => SOURCE.replace("alias real = f32;", "alias real = f64;"),
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("hooke explicit step"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("hooke explicit step"),
            layout: None,
            module: &module,
            entry_point: Some("step"),
            compilation_options: Default::default(),
            cache: None,
        });
        let storage = wgpu::BufferUsages::STORAGE;
        let moving = storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let x0 = init("x", &vectors(&state.x, precision), moving);
        let x1 = init("x'", &vectors(&state.x, precision), moving);
        let v = init("v", &vectors(&state.v, precision), moving);
        let w = init("1/m", &reals(&state.inv_mass, precision), storage);
        let mut index = starts;
        index.extend_from_slice(&others);
        let link_bytes: Vec<u8> = index.iter().flat_map(|i| i.to_le_bytes()).collect();
        let links = init("links", &link_bytes, storage);
        let spring = init("springs", &pairs(&ks, precision), storage);
        let external = if state.external_active {
            vectors(&state.external, precision)
        } else {
            vec![0; 2 * precision.bytes()]
        };
        let external = init("external", &external, storage);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("step settings"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let groups_needed = (n as u32).div_ceil(GROUP).max(1);
        let across = groups_needed.min(MAX_GROUPS);
        let dispatch = (across, groups_needed.div_ceil(across));
        let layout = pipeline.get_bind_group_layout(0);
        let bind = |from: &wgpu::Buffer, to: &wgpu::Buffer| {
            let entries = [&params, from, to, &v, &w, &links, &spring, &external];
            let entries: Vec<wgpu::BindGroupEntry> = entries
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke explicit step"),
                layout: &layout,
                entries: &entries,
            })
        };
        let groups = [bind(&x0, &x1), bind(&x1, &x0)];
        let mut step = GpuStep {
            gpu: gpu.clone(),
            precision,
            n: n as u32,
            springs: state.spring_count(),
            pipeline,
            params,
            x: [x0, x1],
            v,
            groups,
            current: 0,
            dispatch,
            steps: 0,
        };
        step.set(settings, state.external_active);
        Ok(step)
    }

    /// What in `state` the card's explicit step does not run, in words; `None` when it runs
    /// all of it.
    pub fn unsupported(state: &State) -> Option<String> {
        let m = &state.materials;
        if m.has_dashpots() {
            return Some("dashpots".into());
        }
        if !m.gas.is_empty() {
            return Some("pressure bodies".into());
        }
        if !m.muscles.is_empty() {
            return Some("muscles".into());
        }
        if !m.plastic.is_empty() {
            return Some("plastic springs".into());
        }
        None
    }

    /// Writes the step's settings (and whether external forces are on) to the card.
    pub fn set(&mut self, settings: &ExplicitSettings, external: bool) {
        let across = self.dispatch.0 * GROUP;
        let flags = u32::from(settings.method == ExplicitMethod::ExplicitEuler)
            | (u32::from(settings.ground.is_some()) << 1)
            | (u32::from(external) << 2);
        let mut bytes: Vec<u8> = [self.n, across, flags, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let decay = if settings.damping != 0.0 {
            (-settings.damping * settings.dt).exp()
        } else {
            1.0
        };
        let values = [
            settings.gravity.x,
            settings.gravity.y,
            settings.dt,
            decay,
            settings.ground.unwrap_or(0.0),
            0.0,
        ];
        bytes.extend(reals(&values, self.precision));
        bytes.resize(64, 0);
        self.gpu.queue.write_buffer(&self.params, 0, &bytes);
    }

    /// Records `steps` steps in one submit, and submits it (it does not wait for the card).
    pub fn run(&mut self, steps: u32) {
        if steps == 0 {
            return;
        }
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("hooke steps"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hooke steps"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            for _ in 0..steps {
                pass.set_bind_group(0, &self.groups[self.current], &[]);
                pass.dispatch_workgroups(self.dispatch.0, self.dispatch.1, 1);
                self.current = 1 - self.current;
            }
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.steps += u64::from(steps);
    }

    /// Waits until every submitted step has run.
    pub fn finish(&self) -> Result<(), GpuError> {
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::ReadBack(e.to_string()))
    }

    /// Reads the positions and velocities back into `state` (which must be the state this was
    /// made from: the same particles), waiting for the card. Pinned particles keep their
    /// positions.
    pub fn read_into(&self, state: &mut State) -> Result<(), GpuError> {
        let bytes = (self.n as u64) * 2 * self.precision.bytes() as u64;
        let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read back"),
            size: 2 * bytes.max(8),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("read back"),
            });
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&self.x[self.current], 0, &staging, 0, bytes);
            encoder.copy_buffer_to_buffer(&self.v, 0, &staging, bytes, bytes);
        }
        self.gpu.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.finish()?;
        rx.recv()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        {
            let view = slice.get_mapped_range();
            let values = from_bytes(&view, self.precision);
            let n = self.n as usize;
            // A pinned particle does not move on the card: it keeps its f64 position, which
            // the f32 copy would round.
            for (i, (x, &w)) in state.x.iter_mut().zip(&state.inv_mass).enumerate().take(n) {
                if w != 0.0 {
                    *x = DVec2::new(values[2 * i], values[2 * i + 1]);
                }
            }
            for (i, v) in state.v.iter_mut().enumerate().take(n) {
                *v = DVec2::new(values[2 * (n + i)], values[2 * (n + i) + 1]);
            }
        }
        staging.unmap();
        state.non_finite = !state.state_is_finite();
        Ok(())
    }

    /// Steps taken on the card since it was made.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The precision the kernel computes in.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Springs in the uploaded state.
    pub fn spring_count(&self) -> usize {
        self.springs
    }

    /// The card's name.
    pub fn adapter(&self) -> String {
        self.gpu.adapter()
    }
}

/// Each particle's links: where each particle's list starts (n + 1 values), each link's other
/// end, and each link's (k, L), from the packed springs by a counting sort.
fn links(state: &State) -> (Vec<u32>, Vec<u32>, Vec<(f64, f64)>) {
    let n = state.particle_count();
    let mut starts = vec![0u32; n + 1];
    for s in &state.springs {
        starts[s.a as usize + 1] += 1;
        starts[s.b as usize + 1] += 1;
    }
    for i in 0..n {
        starts[i + 1] += starts[i];
    }
    let total = starts[n] as usize;
    let mut fill = starts.clone();
    let mut others = vec![0u32; total];
    let mut ks = vec![(0.0, 0.0); total];
    for s in &state.springs {
        for (from, to) in [(s.a, s.b), (s.b, s.a)] {
            let at = fill[from as usize] as usize;
            others[at] = to;
            ks[at] = (s.k, s.rest);
            fill[from as usize] += 1;
        }
    }
    (starts, others, ks)
}

fn reals(values: &[f64], precision: Precision) -> Vec<u8> {
    match precision {
        Precision::F32 => values
            .iter()
            .flat_map(|&v| (v as f32).to_le_bytes())
            .collect(),
        Precision::F64 => values.iter().flat_map(|&v| v.to_le_bytes()).collect(),
    }
}

fn vectors(values: &[DVec2], precision: Precision) -> Vec<u8> {
    let flat: Vec<f64> = values.iter().flat_map(|v| [v.x, v.y]).collect();
    reals(&flat, precision)
}

fn pairs(values: &[(f64, f64)], precision: Precision) -> Vec<u8> {
    let flat: Vec<f64> = values.iter().flat_map(|&(a, b)| [a, b]).collect();
    reals(&flat, precision)
}

fn from_bytes(bytes: &[u8], precision: Precision) -> Vec<f64> {
    match precision {
        Precision::F32 => bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect(),
        Precision::F64 => bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect(),
    }
}
