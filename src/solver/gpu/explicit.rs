//! The explicit step on the card: one WGSL kernel a step ([`explicit.wgsl`]), many steps a
//! submit, the state read back only when asked.
//!
//! The layout is the lean one: per particle its position, velocity and inverse mass (0 for a
//! pin, so the kick needs no flag); per particle a list of its links (a spring appears in both
//! ends' lists), each link its other end and its (k, L) read together. Each thread gathers
//! its own particle's force, so no two threads write one value and no atomics are needed: a
//! spring's length is computed twice, once per end, which costs less on a card than a scatter.

use super::context::{Gpu, GpuError, Precision, ready};
use super::summary::{Sources, Summary, SummaryPass};
use crate::solver::contact::ContactSettings;
use crate::solver::contact::obstacle::{MIN_THICKNESS, Placed, SLOP, Shape};
use crate::solver::contact::pairs::Pairs;
use crate::solver::state::{Energy, State};
use glam::DVec2;
use wgpu::util::DeviceExt;

/// The step kernel's source, in f32.
const SOURCE: &str = include_str!("explicit.wgsl");
/// The contact pass's kernels (`collide`, and `advance` for the obstacles), in f32.
const CONTACT: &str = include_str!("contact.wgsl");
/// The pair contact's kernels, appended to the contact pass's (whose functions they use).
const PAIRS: &str = include_str!("pairs.wgsl");
/// Tearing's kernel, in f32.
const TEAR: &str = include_str!("tear.wgsl");
/// Threads in a work group (the kernel's `@workgroup_size`).
const GROUP: u32 = 256;
/// The overlap, as a share of 2r, under which the pair iterations stop (the CPU's).
const PAIR_TOLERANCE: f64 = crate::solver::contact::pairs::TOLERANCE;
/// Numbers in one obstacle's record (`Obstacle` in `contact.wgsl`).
const OBSTACLE_REALS: usize = 16;
/// The most work groups along one side of a dispatch.
const MAX_GROUPS: u32 = 65_535;

/// Which method the card runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExplicitMethod {
    /// Move with the velocity after the kick (and damping and ground).
    SymplecticEuler,
    /// Move with the velocity from before the kick.
    ExplicitEuler,
    /// XPBD with these substeps a step and Gauss-Seidel sweeps a substep (`xpbd.wgsl`).
    Xpbd {
        /// Substeps a step.
        substeps: u32,
        /// Sweeps a substep.
        sweeps: u32,
    },
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
    /// The contact settings: with them the ground is the contact pass's (at the particles'
    /// radius, with friction and restitution), not the step's clamp.
    pub contact: Option<ContactSettings>,
    /// Tearing, when on.
    pub tear: Option<TearSettings>,
}

/// When springs tear: as the CPU's tick does ([`crate::sim::tear`]), a spring stretched past
/// (1 + strain) × rest breaks at the end of every `every` steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TearSettings {
    /// The strain past which a spring breaks.
    pub strain: f64,
    /// Steps between the checks: the CPU's steps a tick.
    pub every: u32,
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
    /// Velocities, ping-ponged with the positions.
    v: [wgpu::Buffer; 2],
    /// External forces (one zero vector when none was set at upload).
    external: wgpu::Buffer,
    /// Particles with an external force uploaded (0: none).
    external_len: usize,
    /// Bind group `g` reads `x[g]` and writes `x[1 - g]`.
    groups: [wgpu::BindGroup; 2],
    current: usize,
    dispatch: (u32, u32),
    steps: u64,
    /// The step, s (the obstacles' turn a step is written from it).
    dt: f64,
    /// Some spring has a dashpot.
    dashpots: bool,
    /// The last step's contacts with surfaces and between particles, as the last read brought
    /// them.
    contacts: [std::sync::atomic::AtomicUsize; 2],
    /// The read-back's staging buffers, kept between reads: the state's, and the summary's.
    staging: [std::sync::Mutex<Option<wgpu::Buffer>>; 2],
    /// A read of the state started and not yet taken ([`Self::begin_read`]).
    pending: std::sync::Mutex<Option<Read>>,
    /// The summary's reductions, made at the first summary asked for, and the buffers they
    /// read besides the state's (the links and their records).
    summary: std::sync::OnceLock<SummaryPass>,
    summary_sources: (wgpu::Buffer, wgpu::Buffer),
    /// A summary started and not yet taken ([`Self::begin_summary`]), with the host's share
    /// of the energy (the fixed particles') as they stood when it was asked for.
    summary_pending: std::sync::Mutex<Option<(Read, Energy)>>,
    /// The contact pass, when the scene has obstacles, or a ground with contact set.
    contact: Option<ContactPass>,
    /// Tearing's pass, when tearing is on.
    tear: Option<TearPass>,
    /// XPBD's passes, when the method is XPBD.
    xpbd: Option<super::xpbd::XpbdPass>,
    /// Steps since tearing last looked.
    since_tear: u32,
    /// Each link's spring, in the state's spring order.
    link_spring: Vec<u32>,
    /// The particles the step does not move (inverse mass 0: pinned, or held by a drag), with
    /// the position and velocity the card has for each, and its mass (for the summary's
    /// energy).
    fixed: Vec<(usize, DVec2, DVec2, f64)>,
    /// Inverse masses, and each spring's ends and rest length for the drawing (`draw.rs`).
    inv_mass: wgpu::Buffer,
    drawn_springs: wgpu::Buffer,
}

/// A read under way: the staging buffer the copy went to, the bytes it holds, and the map's
/// answer.
#[derive(Debug)]
struct Read {
    staging: wgpu::Buffer,
    /// Which of [`GpuStep`]'s staging buffers it is (0: the state's, 1: the summary's).
    slot: usize,
    total: u64,
    mapped: std::sync::mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
}

/// Tearing's pipeline and buffers.
#[derive(Debug)]
struct TearPass {
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    torn: wgpu::Buffer,
    links: usize,
    /// Bind group `g` reads the positions in `x[g]`.
    groups: [wgpu::BindGroup; 2],
    every: u32,
}

/// The contact pass's pipelines and buffers.
#[derive(Debug)]
pub(super) struct ContactPass {
    collide: wgpu::ComputePipeline,
    advance: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    obstacles: wgpu::Buffer,
    count: usize,
    counter: wgpu::Buffer,
    /// Bind group `g` follows the step that read `x[g]`, `v[g]`: it places `x[1 - g]`.
    groups: [wgpu::BindGroup; 2],
    advance_group: wgpu::BindGroup,
    /// The contact between particles, when on.
    pairs: Option<super::pairs::PairPass>,
    /// Whether the ground is this pass's (contact is set and the scene has one): with no
    /// obstacles either, only the pairs' passes run.
    ground: bool,
    /// Under XPBD, the contact inside its substeps.
    inside: Option<InSolvePass>,
}

/// The contact inside XPBD's substeps (`contact.wgsl`'s `enter`, `hold_out` and `settle`).
#[derive(Debug)]
struct InSolvePass {
    enter: (wgpu::ComputePipeline, wgpu::BindGroup),
    hold_out: (wgpu::ComputePipeline, wgpu::BindGroup),
    settle: (wgpu::ComputePipeline, wgpu::BindGroup),
}

impl GpuStep {
    /// Uploads `state` to the card in `precision`, with the step's settings. The state's
    /// materials, if any, are not run here: the caller checks [`GpuStep::unsupported`] first.
    pub fn new(
        gpu: &Gpu,
        state: &State,
        settings: &ExplicitSettings,
        obstacles: &[Placed],
        precision: Precision,
    ) -> Result<GpuStep, GpuError> {
        if precision == Precision::F64 && !gpu.has_f64() {
            return Err(GpuError::NoDevice(format!(
                "{} does not compute in f64",
                gpu.adapter()
            )));
        }
        if obstacles
            .iter()
            .any(|o| matches!(o.shape, Shape::Polygon(_)))
        {
            return Err(GpuError::Refused(
                "the card's contact has circles, boxes and segments, not convex polygons".into(),
            ));
        }
        let n = state.particle_count();
        let dashpots = state.materials.has_dashpots();
        let (starts, others, records, link_spring) = links(state);
        let limits = gpu.device.limits();
        // The largest buffer: the link records, their indices, or the particles' vectors.
        let width = if dashpots { 4 } else { 2 };
        // XPBD's constraints: ten numbers each (`xpbd.wgsl`'s `Coefficients`).
        let xpbd = match settings.method {
            ExplicitMethod::Xpbd { .. } => state.spring_count() * 10 * precision.bytes(),
            _ => 0,
        };
        let widest = [
            others.len() * width * precision.bytes(),
            (n + 1 + others.len()) * 4,
            n * 2 * precision.bytes(),
            xpbd,
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u64;
        let allowed = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if widest > allowed || n >= u32::MAX as usize / 2 {
            return Err(GpuError::TooLarge(format!(
                "{n} particles and {} springs need a buffer of {} MB in {}; the adapter binds at most {} MB",
                state.spring_count(),
                widest.div_ceil(1 << 20),
                precision.name(),
                allowed >> 20
            )));
        }
        let device = &gpu.device;
        // What the device refuses (out of memory, a kernel its driver cannot build) comes
        // back as an error, not as wgpu's panic.
        let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let invalid = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let source = if dashpots {
            SOURCE
                .replace("alias Link = vec2<real>;", "alias Link = vec4<real>;")
                .replace("const DASHPOTS: bool = false;", "const DASHPOTS: bool = true;")
                .replace(
                    "fn dashpot(s: Link, dv: vec2<real>, n: vec2<real>) -> real {\n    return real(0.0);",
                    "fn dashpot(s: Link, dv: vec2<real>, n: vec2<real>) -> real {\n    return s.z * dot(dv, n);",
                )
        } else {
            SOURCE.to_string()
        };
        let module = shader(device, &source, "hooke explicit step", precision);
        let pipeline = pipeline(device, &module, "step");
        let storage = wgpu::BufferUsages::STORAGE;
        let moving = storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let init = |label: &str, contents: &[u8], usage| buffer(device, label, contents, usage);
        let x0 = init("x", &vectors(&state.x, precision), moving);
        let x1 = init("x'", &vectors(&state.x, precision), moving);
        let v0 = init("v", &vectors(&state.v, precision), moving);
        let v1 = init("v'", &vectors(&state.v, precision), moving);
        let w = init("1/m", &reals(&state.inv_mass, precision), storage);
        let mut index = starts;
        index.extend_from_slice(&others);
        let link_bytes: Vec<u8> = index.iter().flat_map(|i| i.to_le_bytes()).collect();
        let links = init("links", &link_bytes, storage);
        // (k, L) a link, or (k, L, c, 0) with dashpots.
        let flat: Vec<f64> = records.iter().flat_map(|r| r[..width].to_vec()).collect();
        let spring = init("springs", &reals(&flat, precision), storage);
        let external = if state.external_active {
            vectors(&state.external, precision)
        } else {
            vec![0; 2 * precision.bytes()]
        };
        let external = init(
            "external",
            &external,
            storage | wgpu::BufferUsages::COPY_DST,
        );
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("step settings"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let dispatch = shape(n as u64, GROUP);
        let layout = pipeline.get_bind_group_layout(0);
        let bind = |from: usize| {
            let (x, v) = ([&x0, &x1], [&v0, &v1]);
            let to = 1 - from;
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke explicit step"),
                layout: &layout,
                entries: &entries(&[
                    (0, &params),
                    (1, x[from]),
                    (2, x[to]),
                    (3, v[from]),
                    (4, v[to]),
                    (5, &w),
                    (6, &links),
                    (7, &spring),
                    (8, &external),
                ]),
            })
        };
        let groups = [bind(0), bind(1)];
        // Each spring's ends and rest length (f32), for the drawing.
        let drawn: Vec<u8> = (state.springs.iter())
            .flat_map(|s| [s.a, s.b, (s.rest as f32).to_bits(), 0])
            .flat_map(u32::to_le_bytes)
            .collect();
        let drawn_springs = init("drawn springs", &drawn, storage);
        let pairs = settings
            .contact
            .is_some_and(|c| c.particles && c.radius > 0.0)
            && n >= 2;
        let xpbd = match settings.method {
            ExplicitMethod::Xpbd { substeps, sweeps } => Some(super::xpbd::XpbdPass::new(
                gpu,
                precision,
                state,
                (settings.dt, substeps, sweeps),
                super::xpbd::StateBuffers {
                    x: &x0,
                    v: &v0,
                    w: &w,
                    external: &external,
                },
            )),
            _ => None,
        };
        let needs_contact = !obstacles.is_empty()
            || (settings.contact.is_some() && settings.ground.is_some())
            || pairs;
        let contact = needs_contact.then(|| {
            let state = ContactBuffers {
                x: [&x0, &x1],
                v: [&v0, &v1],
                w: &w,
                links: &links,
                xpbd: xpbd.as_ref(),
            };
            ContactPass::new(gpu, precision, obstacles.len(), state, pairs.then_some(n))
        });
        let tear = settings.tear.map(|t| {
            let source = if dashpots {
                TEAR.replace("alias Link = vec2<real>;", "alias Link = vec4<real>;")
            } else {
                TEAR.to_string()
            };
            TearPass::new(
                gpu,
                precision,
                &source,
                others.len(),
                [&x0, &x1],
                &links,
                &spring,
                t,
            )
        });
        let mut step = GpuStep {
            gpu: gpu.clone(),
            precision,
            n: n as u32,
            springs: state.spring_count(),
            pipeline,
            params,
            x: [x0, x1],
            v: [v0, v1],
            external_len: if state.external_active {
                state.external.len()
            } else {
                0
            },
            external,
            groups,
            current: 0,
            dispatch,
            steps: 0,
            dt: settings.dt,
            dashpots,
            contacts: Default::default(),
            staging: Default::default(),
            pending: Default::default(),
            summary: Default::default(),
            summary_sources: (links.clone(), spring.clone()),
            summary_pending: Default::default(),
            contact,
            tear,
            xpbd,
            since_tear: 0,
            link_spring,
            fixed: fixed(state),
            inv_mass: w,
            drawn_springs,
        };
        step.set(settings, state.external_active);
        step.set_tear(settings);
        step.place(obstacles);
        for scope in [invalid, out_of_memory] {
            if let Some(e) = ready(scope.pop()) {
                return Err(GpuError::Refused(e.to_string()));
            }
        }
        Ok(step)
    }

    /// What in `state` the card's explicit step does not run, in words; `None` when it runs
    /// all of it.
    pub fn unsupported(state: &State) -> Option<String> {
        let m = &state.materials;
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
        self.dt = settings.dt;
        let across = self.dispatch.0 * GROUP;
        // With contact set, the ground is the contact pass's.
        let clamp = settings.ground.is_some() && settings.contact.is_none();
        let flags = u32::from(settings.method == ExplicitMethod::ExplicitEuler)
            | (u32::from(clamp) << 1)
            | (u32::from(external) << 2);
        // exp(−μ dt), exactly 1 at μ = 0.
        let decay = crate::solver::forces::kernels::decay(settings.damping, settings.dt);
        let values = [
            settings.gravity.x,
            settings.gravity.y,
            settings.dt,
            decay,
            settings.ground.unwrap_or(0.0),
            0.0,
        ];
        let q = &self.gpu.queue;
        write_settings(
            q,
            &self.params,
            self.precision,
            [self.n, across, flags, 0],
            &values,
        );
        if let Some(x) = &self.xpbd {
            let hs = settings.dt / f64::from(x.substeps());
            let floor = settings.ground.filter(|_| settings.contact.is_none());
            let flags = u32::from(floor.is_some())
                | (u32::from(external) << 1)
                | (u32::from(self.dashpots) << 2);
            write_settings(
                q,
                &x.params,
                self.precision,
                [self.n, across, flags, 0],
                &[
                    settings.gravity.x,
                    settings.gravity.y,
                    hs,
                    1.0 / hs,
                    floor.unwrap_or(0.0),
                    settings.dt,
                    1.0 / settings.dt,
                    decay,
                ],
            );
        }
        if let Some(c) = &mut self.contact {
            let contact = settings.contact.unwrap_or_default();
            let ground = settings.contact.and(settings.ground);
            c.ground = ground.is_some();
            let flags = u32::from(ground.is_some())
                | (u32::from(settings.method == ExplicitMethod::ExplicitEuler) << 1);
            let table = c.pairs.as_ref().map_or(0, |p| p.table);
            let header = [self.n, c.count as u32, flags, table];
            let contact_distance = 2.0 * contact.radius;
            let values = [
                settings.dt,
                contact.radius,
                contact.friction,
                contact.restitution,
                // A resting particle approaches at one step of gravity; twice that keeps it at
                // rest (as `Surroundings::surface`).
                2.0 * settings.gravity.length() * settings.dt,
                ground.unwrap_or(0.0),
                // The pair grid's cells: 2r and the CPU's skin.
                contact_distance + Pairs::skin(contact.radius),
                PAIR_TOLERANCE * contact_distance,
            ];
            write_settings(q, &c.params, self.precision, header, &values);
        }
    }

    /// Writes tearing's settings to the card (its strain; how often it looks is fixed when the
    /// step is made).
    fn set_tear(&mut self, settings: &ExplicitSettings) {
        let (Some(t), Some(strain)) = (&self.tear, settings.tear.map(|t| t.strain)) else {
            return;
        };
        let header = [self.n, self.dispatch.0 * GROUP, 0, 0];
        let values = [1.0 + strain, 0.0];
        write_settings(&self.gpu.queue, &t.params, self.precision, header, &values);
    }

    /// Writes the obstacles' shapes and poses to the card (as many as it was made with): the
    /// caller's poses, in f64, are the truth, and the card moves its copy within a submit.
    pub fn place(&mut self, obstacles: &[Placed]) {
        let Some(c) = &self.contact else { return };
        if c.count == 0 || obstacles.len() != c.count {
            return;
        }
        let mut values = Vec::with_capacity(OBSTACLE_REALS * obstacles.len());
        for o in obstacles {
            let (kind, a, b, size) = match o.shape {
                Shape::Circle { radius } => (0.0, DVec2::ZERO, DVec2::ZERO, radius),
                Shape::Box { half } => (1.0, half, DVec2::ZERO, 0.0),
                Shape::Segment { a, b, thickness } => {
                    (2.0, a, b, thickness.max(min_thickness(self.precision)))
                }
                // Refused when the step was made; the obstacles changed since: the caller's
                // check (`sim::gpu::unsupported`) takes the scene back to the CPU.
                Shape::Polygon(_) => return,
            };
            let p = &o.pose;
            let (sin, cos) = p.angle.sin_cos();
            let (turn_sin, turn_cos) = (p.angular_velocity * self.dt).sin_cos();
            values.extend([
                p.center.x,
                p.center.y,
                p.velocity.x,
                p.velocity.y,
                a.x,
                a.y,
                b.x,
                b.y,
                cos,
                sin,
                turn_cos,
                turn_sin,
                p.angular_velocity,
                size,
                kind,
                0.0,
            ]);
        }
        self.gpu
            .queue
            .write_buffer(&c.obstacles, 0, &reals(&values, self.precision));
    }

    /// Contacts with surfaces resolved in the last step run (0 without a contact pass), as the
    /// last [`Self::read_into`] read them with the state.
    pub fn contacts(&self) -> usize {
        self.contacts[0].load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Pairs of particles touching in the last step run (each pair once), as the last
    /// [`Self::read_into`] read them.
    pub fn pair_contacts(&self) -> usize {
        self.contacts[1].load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Uploads `state`'s positions, velocities and external forces (the state this was made
    /// from, edited on the CPU since: a drag, an undo; the same particles).
    pub fn write_state(&mut self, state: &State) {
        let q = &self.gpu.queue;
        q.write_buffer(&self.x[self.current], 0, &vectors(&state.x, self.precision));
        q.write_buffer(&self.v[self.current], 0, &vectors(&state.v, self.precision));
        if state.external_active && self.external_len == state.external.len() {
            q.write_buffer(&self.external, 0, &vectors(&state.external, self.precision));
        }
        self.fixed = fixed(state);
    }

    /// Uploads the position and velocity of each particle the step does not move (pinned, or
    /// held) that the CPU moved since the card last had it: a drag moves its held particle
    /// every frame without touching the rest of the state.
    pub fn write_fixed(&mut self, state: &State) {
        let width = 2 * self.precision.bytes() as u64;
        for (i, x, v, _) in &mut self.fixed {
            let (now_x, now_v) = match (state.x.get(*i), state.v.get(*i)) {
                (Some(x), Some(v)) => (*x, *v),
                _ => continue,
            };
            if now_x == *x && now_v == *v {
                continue;
            }
            (*x, *v) = (now_x, now_v);
            let q = &self.gpu.queue;
            let at = *i as u64 * width;
            q.write_buffer(
                &self.x[self.current],
                at,
                &vectors(&[now_x], self.precision),
            );
            q.write_buffer(
                &self.v[self.current],
                at,
                &vectors(&[now_v], self.precision),
            );
        }
    }

    /// Records `steps` steps in one submit, and submits it (it does not wait for the card).
    pub fn run(&mut self, steps: u32) {
        if steps == 0 {
            return;
        }
        let gpu = self.gpu.clone();
        submit(&gpu, "hooke steps", |pass| {
            for _ in 0..steps {
                if let Some(x) = &self.xpbd {
                    // XPBD works in place on the state's buffers (`x[0]`, `v[0]`).
                    x.record(pass, self.dispatch, self.contact.as_ref());
                    if let Some(c) = &self.contact {
                        c.record_after_solve(pass, self.dispatch);
                    }
                } else {
                    dispatch(
                        pass,
                        &self.pipeline,
                        &self.groups[self.current],
                        self.dispatch,
                    );
                    if let Some(c) = &self.contact {
                        c.record_after_step(pass, self.current, self.dispatch);
                    }
                    self.current = 1 - self.current;
                }
                if let Some(t) = &self.tear {
                    self.since_tear += 1;
                    if self.since_tear == t.every {
                        dispatch(pass, &t.pipeline, &t.groups[self.current], self.dispatch);
                        self.since_tear = 0;
                    }
                }
            }
        });
        self.steps += u64::from(steps);
    }

    /// Tearing's look now, if steps ran since the last (the end of the CPU's last, shorter tick
    /// of a run: the CPU tears at the end of every tick).
    pub fn tear_now(&mut self) {
        let Some(t) = &self.tear else { return };
        if self.since_tear == 0 {
            return;
        }
        submit(&self.gpu, "hooke tear", |pass| {
            dispatch(pass, &t.pipeline, &t.groups[self.current], self.dispatch);
        });
        self.since_tear = 0;
    }

    /// The springs (their indices in the state's spring order) that tore since the last call,
    /// read from the card.
    pub fn torn_springs(&self) -> Result<Vec<usize>, GpuError> {
        let Some(t) = &self.tear else {
            return Ok(vec![]);
        };
        let bytes = self.read(&[(&t.torn, 0, 4 * t.links as u64)])?;
        let mut torn: Vec<usize> = bytes
            .chunks_exact(4)
            .enumerate()
            .filter(|(_, b)| b.iter().any(|&x| x != 0))
            .map(|(link, _)| self.link_spring[link] as usize)
            .collect();
        torn.sort_unstable();
        torn.dedup();
        if !torn.is_empty() {
            let mut encoder =
                self.gpu
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("clear torn"),
                    });
            encoder.clear_buffer(&t.torn, 0, None);
            self.gpu.queue.submit([encoder.finish()]);
        }
        Ok(torn)
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
        self.begin_read()?;
        self.finish_read_into(state)
    }

    /// Starts reading the state back, as the steps submitted so far leave it, without waiting:
    /// [`Self::finish_read_into`] takes it. A read already under way is kept.
    pub fn begin_read(&self) -> Result<(), GpuError> {
        let mut pending = self.lock_pending()?;
        if pending.is_some() {
            return Ok(());
        }
        let bytes = (self.n as u64) * 2 * self.precision.bytes() as u64;
        // The last step's contact count comes back in the same copy.
        let mut ranges = vec![
            (&self.x[self.current], 0, bytes),
            (&self.v[self.current], 0, bytes),
        ];
        if let Some(c) = &self.contact {
            ranges.push((&c.counter, 0, 16));
        }
        *pending = Some(self.start_read(0, &ranges)?);
        Ok(())
    }

    /// Whether a read was started and not yet taken.
    pub fn reading(&self) -> bool {
        self.pending.lock().is_ok_and(|p| p.is_some())
    }

    /// Takes the read [`Self::begin_read`] started into `state` (the state this was made from),
    /// waiting for the card only if it has not finished it; without one under way, reads now.
    /// Pinned particles keep their positions.
    pub fn finish_read_into(&self, state: &mut State) -> Result<(), GpuError> {
        let taken = self.lock_pending()?.take();
        let read = match taken {
            Some(read) => read,
            None => return self.read_into(state),
        };
        let view = self.end_read(read)?;
        let bytes = (self.n as u64) * 2 * self.precision.bytes() as u64;
        let (state_bytes, counter) = view.split_at((2 * bytes) as usize);
        self.note_contacts(counter);
        let values = from_bytes(state_bytes, self.precision);
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
        state.non_finite = !state.state_is_finite();
        Ok(())
    }

    /// Starts the summary of the state as the steps submitted so far leave it (its energy
    /// under `gravity`, the links torn, the last step's contacts), without waiting:
    /// [`Self::finish_summary`] takes it. A summary already under way is kept.
    pub fn begin_summary(&self, gravity: DVec2) -> Result<(), GpuError> {
        let mut pending = self
            .summary_pending
            .lock()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        if pending.is_some() {
            return Ok(());
        }
        let pass = self.summary.get_or_init(|| {
            SummaryPass::new(
                &self.gpu,
                self.precision,
                self.n,
                self.dashpots,
                Sources {
                    x: [&self.x[0], &self.x[1]],
                    v: [&self.v[0], &self.v[1]],
                    w: &self.inv_mass,
                    links: &self.summary_sources.0,
                    spring: &self.summary_sources.1,
                    torn: self.tear.as_ref().map(|t| &t.torn),
                },
            )
        });
        pass.record(&self.gpu, self.precision, (self.n, self.current), gravity);
        let (at, length) = pass.total_at(self.precision);
        let mut ranges = vec![(&pass.sums, at, length)];
        if let Some(c) = &self.contact {
            ranges.push((&c.counter, 0, 16));
        }
        // The fixed particles move on the host: their share, as the card has them now.
        let mut host = Energy::default();
        for (_, x, v, m) in &self.fixed {
            host.kinetic += 0.5 * m * v.length_squared();
            host.potential_gravity -= m * gravity.dot(*x);
        }
        *pending = Some((self.start_read(1, &ranges)?, host));
        Ok(())
    }

    /// Whether a summary was started and not yet taken.
    pub fn summarising(&self) -> bool {
        self.summary_pending.lock().is_ok_and(|p| p.is_some())
    }

    /// Takes the summary [`Self::begin_summary`] started, waiting for the card only if it has
    /// not finished it; `None` without one under way.
    pub fn finish_summary(&self) -> Result<Option<Summary>, GpuError> {
        let taken = self
            .summary_pending
            .lock()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?
            .take();
        let Some((read, host)) = taken else {
            return Ok(None);
        };
        let bytes = self.end_read(read)?;
        let width = 4 * self.precision.bytes();
        let sums = from_bytes(&bytes[..width], self.precision);
        let contacts = self.note_contacts(&bytes[width..]).unwrap_or([0, 0]);
        Ok(Some(Summary {
            energy: Energy {
                kinetic: sums[0] + host.kinetic,
                potential_gravity: sums[1] + host.potential_gravity,
                potential_springs: sums[2],
                potential_gas: 0.0,
            },
            torn_links: sums[3].max(0.0).round() as u64,
            contacts,
        }))
    }

    /// The summary of the state now, waiting for the card.
    pub fn summary(&self, gravity: DVec2) -> Result<Summary, GpuError> {
        self.begin_summary(gravity)?;
        Ok(self.finish_summary()?.unwrap_or_default())
    }

    /// The contact pass's counter as a read brought it back (four u32 words; none without a
    /// contact pass), noted as the last step's contacts: with surfaces, and between particles.
    fn note_contacts(&self, counter: &[u8]) -> Option<[usize; 2]> {
        let words: Vec<usize> = counter
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
            .collect();
        let [_, surfaces, pairs, _] = words[..] else {
            return None;
        };
        let relaxed = std::sync::atomic::Ordering::Relaxed;
        self.contacts[0].store(surfaces, relaxed);
        self.contacts[1].store(pairs, relaxed);
        Some([surfaces, pairs])
    }

    fn lock_pending(&self) -> Result<std::sync::MutexGuard<'_, Option<Read>>, GpuError> {
        self.pending
            .lock()
            .map_err(|e| GpuError::ReadBack(e.to_string()))
    }

    /// The bytes of the buffers' ranges `(buffer, offset, length)`, one after the other,
    /// waiting for the card.
    fn read(&self, ranges: &[(&wgpu::Buffer, u64, u64)]) -> Result<Vec<u8>, GpuError> {
        let read = self.start_read(0, ranges)?;
        self.end_read(read)
    }

    /// Copies the ranges into the staging buffer of `slot` (0: the state's, 1: the
    /// summary's) and asks for it mapped, without waiting.
    fn start_read(
        &self,
        slot: usize,
        ranges: &[(&wgpu::Buffer, u64, u64)],
    ) -> Result<Read, GpuError> {
        let total: u64 = ranges.iter().map(|r| r.2).sum();
        // One staging buffer a slot, kept for the next read (the app reads every tick): a new
        // one only when a read is larger than the last.
        let mut kept = self.staging[slot]
            .lock()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let size = total.max(8).next_multiple_of(8);
        let staging = match kept.take() {
            Some(b) if b.size() >= size => b,
            _ => self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("read back"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("read back"),
            });
        let mut at = 0;
        for &(buffer, offset, length) in ranges {
            if length > 0 {
                encoder.copy_buffer_to_buffer(buffer, offset, &staging, at, length);
            }
            at += length;
        }
        self.gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        Ok(Read {
            staging,
            slot,
            total,
            mapped: rx,
        })
    }

    /// Waits for a started read (at once if the card has finished it) and returns its bytes;
    /// the staging buffer is kept for the next.
    fn end_read(&self, read: Read) -> Result<Vec<u8>, GpuError> {
        let Read {
            staging,
            slot,
            total,
            mapped,
        } = read;
        let done = match mapped.try_recv() {
            Ok(r) => r,
            Err(_) => {
                self.finish()?;
                mapped
                    .recv()
                    .map_err(|e| GpuError::ReadBack(e.to_string()))?
            }
        };
        done.map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let bytes = staging.slice(..).get_mapped_range()[..total as usize].to_vec();
        staging.unmap();
        if let Ok(mut kept) = self.staging[slot].lock() {
            *kept = Some(staging);
        }
        Ok(bytes)
    }

    /// The buffers the drawing reads: the positions (ping-ponged) and which holds the state,
    /// the inverse masses, and the springs' ends and rest lengths; and the most bytes the
    /// device binds as one storage buffer.
    pub(super) fn draw_buffers(
        &self,
    ) -> ([wgpu::Buffer; 2], usize, wgpu::Buffer, wgpu::Buffer, u64) {
        let limits = self.gpu.device.limits();
        (
            self.x.clone(),
            self.current,
            self.inv_mass.clone(),
            self.drawn_springs.clone(),
            limits.max_storage_buffer_binding_size,
        )
    }

    /// Particles in the uploaded state.
    pub fn particle_count(&self) -> usize {
        self.n as usize
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

impl TearPass {
    #[allow(clippy::too_many_arguments)]
    fn new(
        gpu: &Gpu,
        precision: Precision,
        source: &str,
        links: usize,
        x: [&wgpu::Buffer; 2],
        index: &wgpu::Buffer,
        spring: &wgpu::Buffer,
        settings: TearSettings,
    ) -> TearPass {
        let device = &gpu.device;
        let module = shader(device, source, "hooke tear", precision);
        let pipeline = pipeline(device, &module, "tear");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tear settings"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let torn = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("torn links"),
            size: (4 * links.max(4)) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
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
}

/// The state's buffers the contact pass reads and writes.
struct ContactBuffers<'a> {
    /// Positions and velocities, ping-ponged by the step.
    x: [&'a wgpu::Buffer; 2],
    v: [&'a wgpu::Buffer; 2],
    w: &'a wgpu::Buffer,
    /// The step's links: which pairs a spring joins.
    links: &'a wgpu::Buffer,
    /// XPBD's pass, whose substeps keep contact.
    xpbd: Option<&'a super::xpbd::XpbdPass>,
}

impl ContactPass {
    /// The pass for `count` obstacles, and with `pairs: Some(n)` the contact between the n
    /// particles.
    fn new(
        gpu: &Gpu,
        precision: Precision,
        count: usize,
        state: ContactBuffers,
        pairs: Option<usize>,
    ) -> ContactPass {
        let ContactBuffers {
            x,
            v,
            w,
            links,
            xpbd,
        } = state;
        let device = &gpu.device;
        let source = format!("{CONTACT}\n{PAIRS}");
        let module = shader(device, &source, "hooke contact", precision);
        let (collide, advance) = (
            pipeline(device, &module, "collide"),
            pipeline(device, &module, "advance"),
        );
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("contact settings"),
            size: 96,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let obstacles = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("obstacles"),
            size: (OBSTACLE_REALS * precision.bytes() * count.max(1)) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counter = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("contacts"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let control = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pair control"),
            size: 4 * super::pairs::CONTROL_WORDS,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let layout = collide.get_bind_group_layout(0);
        // After the step that read `x[from]`, `v[from]`: the start velocities, and the end
        // positions and velocities it wrote.
        let bind = |from: usize| {
            let to = 1 - from;
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke contact"),
                layout: &layout,
                entries: &entries(&[
                    (0, &params),
                    (1, v[from]),
                    (2, x[to]),
                    (3, v[to]),
                    (4, w),
                    (5, &obstacles),
                    (6, &counter),
                ]),
            })
        };
        let groups = [bind(0), bind(1)];
        let advance_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hooke obstacles"),
            layout: &advance.get_bind_group_layout(0),
            entries: &entries(&[(0, &params), (5, &obstacles), (6, &counter), (19, &control)]),
        });
        let pairs = pairs.map(|n| {
            // After the explicit step that read `x[0]`, the one that read `x[1]`; under XPBD,
            // after the step and inside the substeps.
            let targets = match xpbd {
                Some(xp) => vec![(x[0], v[0]), (&xp.pos, v[0])],
                None => vec![(x[1], v[1]), (x[0], v[0])],
            };
            let bound = super::pairs::Bound {
                params: &params,
                targets,
                w,
                obstacles: &obstacles,
                links,
                control: &control,
            };
            super::pairs::PairPass::new(gpu, &module, precision, n, bound)
        });
        let inside = xpbd.map(|xp| {
            let bind = |entry: &str, list: &[(u32, &wgpu::Buffer)]| {
                let pipeline = pipeline(device, &module, entry);
                let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("hooke contact in the solve"),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &entries(list),
                });
                (pipeline, group)
            };
            let o = &obstacles;
            InSolvePass {
                enter: bind(
                    "enter",
                    &[
                        (0, &params),
                        (4, w),
                        (5, o),
                        (23, &xp.pos),
                        (25, &xp.heading),
                    ],
                ),
                hold_out: bind(
                    "hold_out",
                    &[
                        (0, &params),
                        (4, w),
                        (5, o),
                        (23, &xp.pos),
                        (24, &xp.prev),
                        (25, &xp.heading),
                    ],
                ),
                settle: bind(
                    "settle",
                    &[
                        (0, &params),
                        (2, x[0]),
                        (3, v[0]),
                        (4, w),
                        (5, o),
                        (6, &counter),
                        (25, &xp.heading),
                    ],
                ),
            }
        });
        ContactPass {
            collide,
            advance,
            params,
            obstacles,
            count,
            counter,
            groups,
            advance_group,
            pairs,
            ground: false,
            inside,
        }
    }

    /// Whether the pass keeps particles out of surfaces (obstacles, or the ground).
    fn has_surfaces(&self) -> bool {
        self.count > 0 || self.ground
    }

    /// Records the contact after an explicit step that read `x[from]`: the pairs, then the
    /// surfaces, then the obstacles' motion.
    fn record_after_step(&self, pass: &mut wgpu::ComputePass, from: usize, particles: (u32, u32)) {
        if let Some(pairs) = &self.pairs {
            pairs.record(pass, from, false);
        }
        if self.has_surfaces() {
            dispatch(pass, &self.collide, &self.groups[from], particles);
        }
        self.record_advance(pass);
    }

    /// Records the contact after XPBD's step, which kept contact inside its substeps: the
    /// pairs (their push into the velocity), the surfaces' velocity pass, the obstacles' motion.
    fn record_after_solve(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        if let Some(pairs) = &self.pairs {
            pairs.record(pass, 0, true);
        }
        if let Some(inside) = self.inside.as_ref().filter(|_| self.has_surfaces()) {
            dispatch(pass, &inside.settle.0, &inside.settle.1, particles);
        }
        self.record_advance(pass);
    }

    fn record_advance(&self, pass: &mut wgpu::ComputePass) {
        let obstacles = ((self.count as u32).div_ceil(64).max(1), 1);
        dispatch(pass, &self.advance, &self.advance_group, obstacles);
    }

    /// Records the iterate held out of the surfaces before XPBD's first prediction, over the
    /// dispatch shape `particles`.
    pub(super) fn record_entry(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        if let Some(inside) = self.inside.as_ref().filter(|_| self.has_surfaces()) {
            dispatch(pass, &inside.enter.0, &inside.enter.1, particles);
        }
    }

    /// Records the contact after one of XPBD's substeps: pairs pushed apart, then the iterate
    /// held out of the surfaces along its path from the substep's start.
    pub(super) fn record_substep_end(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        let Some(inside) = &self.inside else { return };
        if let Some(pairs) = &self.pairs {
            pairs.record_pushes(pass, 1);
        }
        if self.has_surfaces() {
            dispatch(pass, &inside.hold_out.0, &inside.hold_out.1, particles);
        }
    }
}

/// The particles of `state` the step does not move (inverse mass 0), with their positions,
/// velocities and masses.
fn fixed(state: &State) -> Vec<(usize, DVec2, DVec2, f64)> {
    (state.inv_mass.iter().enumerate())
        .filter(|(_, w)| **w == 0.0)
        .map(|(i, _)| (i, state.x[i], state.v[i], state.mass[i]))
        .collect()
}

/// A segment's least thickness on the card: the CPU's in f64, 1e-5 m in f32 (see
/// `contact.wgsl`).
fn min_thickness(precision: Precision) -> f64 {
    match precision {
        Precision::F32 => 1e-5,
        Precision::F64 => MIN_THICKNESS,
    }
}

/// A compute pipeline for one entry point of `module`, its layout the one the kernel implies.
pub(super) fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A dispatch's shape for `threads` threads in work groups of `group`: at most [`MAX_GROUPS`]
/// groups a row, and at least one group (a kernel indexes its thread as `x + y · row`).
pub(super) fn shape(threads: u64, group: u32) -> (u32, u32) {
    let groups = threads.div_ceil(u64::from(group)).max(1) as u32;
    let across = groups.min(MAX_GROUPS);
    (across, groups.div_ceil(across))
}

/// One compute pass, recorded by `record`, submitted (not waited for).
pub(super) fn submit(gpu: &Gpu, label: &str, record: impl FnOnce(&mut wgpu::ComputePass)) {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        record(&mut pass);
    }
    gpu.queue.submit([encoder.finish()]);
}

/// One dispatch of `pipeline` with `group` over `groups` work groups.
pub(super) fn dispatch(
    pass: &mut wgpu::ComputePass,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    groups: (u32, u32),
) {
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(groups.0, groups.1, 1);
}

/// A storage or uniform buffer holding `contents`, never empty (a scene without springs still
/// binds its links): at least one vector of the widest precision.
pub(super) fn buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let mut padded = contents.to_vec();
    padded.resize(contents.len().max(16), 0);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &padded,
        usage,
    })
}

/// Writes a kernel's settings as its WGSL `Params` lays them out: four `u32`s, then the numbers
/// one after another in `precision` (each kernel orders its fields so that they pack so), the
/// rest of the uniform buffer zeroed.
pub(super) fn write_settings(
    queue: &wgpu::Queue,
    params: &wgpu::Buffer,
    precision: Precision,
    header: [u32; 4],
    values: &[f64],
) {
    let mut bytes: Vec<u8> = header.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(reals(values, precision));
    bytes.resize(params.size() as usize, 0);
    queue.write_buffer(params, 0, &bytes);
}

/// Bind group entries: each buffer whole at its binding.
pub(super) fn entries<'a>(list: &[(u32, &'a wgpu::Buffer)]) -> Vec<wgpu::BindGroupEntry<'a>> {
    list.iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// A kernel's module, its `real` alias set to the precision.
pub(super) fn shader(
    device: &wgpu::Device,
    source: &str,
    label: &str,
    precision: Precision,
) -> wgpu::ShaderModule {
    let source = match precision {
        Precision::F32 => source.to_string(),
        Precision::F64 => source
            .replace("alias real = f32;", "alias real = f64;")
            .replace(
                "const MIN_THICKNESS: real = 1e-5;",
                &format!("const MIN_THICKNESS: real = {MIN_THICKNESS:e};"),
            )
            .replace(
                "const SLOP: real = 1e-6;",
                &format!("const SLOP: real = {SLOP:e};"),
            ),
    };
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// Each particle's links: where each particle's list starts (n + 1 values), each link's other
/// end, each link's (k, L, c, 0) (c its dashpot, 0 without), and each link's spring: the
/// state's spring adjacency ([`State::spring_adjacency`]) with the springs' numbers.
type Links = (Vec<u32>, Vec<u32>, Vec<[f64; 4]>, Vec<u32>);

fn links(state: &State) -> Links {
    let (starts, entries) = state.spring_adjacency();
    let dashpot = state.materials.dashpot();
    let records = entries
        .iter()
        .map(|&(_, k)| {
            let s = &state.springs[k as usize];
            let c = dashpot.get(k as usize).copied().unwrap_or(0.0);
            [s.k, s.rest, c, 0.0]
        })
        .collect();
    let others = entries.iter().map(|&(other, _)| other).collect();
    let springs = entries.iter().map(|&(_, k)| k).collect();
    (starts, others, records, springs)
}

pub(super) fn reals(values: &[f64], precision: Precision) -> Vec<u8> {
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
