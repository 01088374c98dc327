//! The step on the card ([`GpuStep`]): the state's buffers and the passes in their order (the
//! explicit kernel, [`explicit.wgsl`], or XPBD's ([`super::xpbd`]); then the contact
//! ([`super::contact`]) and tearing ([`super::tear`])), many steps a submit, the state read
//! back only when asked ([`super::readback`]).
//!
//! The layout is the lean one: per particle its position, velocity and inverse mass (0 for a
//! pin, so the kick needs no flag); per particle a list of its links (a spring appears in both
//! ends' lists), each link its other end and its (k, L) read together. Each thread gathers
//! its own particle's force, so no two threads write one value and no atomics are needed: a
//! spring's length is computed twice, once per end, which costs less on a card than a scatter.

use super::contact::{ContactBuffers, ContactPass};
use super::context::{Gpu, GpuError, Precision, ready};
use super::kernel::{
    buffer, dispatch, entries, from_bytes, pipeline, reals, settings_buffer, shader, shape, submit,
    vectors, write_settings,
};
use super::readback::{Read, ReadBack};
use super::settings::{ExplicitMethod, ExplicitSettings};
use super::summary::{Sources, Summary, SummaryPass};
use super::tear::{LinkBuffers, TearPass};
use super::xpbd::{StateBuffers, XpbdPass};
use crate::solver::contact::obstacle::{Placed, Shape};
use crate::solver::state::{Energy, State};
use glam::DVec2;

/// The step kernel's source, in f32.
const SOURCE: &str = include_str!("explicit.wgsl");
/// Threads in a work group (the kernel's `@workgroup_size`).
const GROUP: u32 = 256;

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
    /// The read-back's staging buffers, kept between reads: the state's (slot 0), and the
    /// summary's (slot 1).
    readback: ReadBack,
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
    xpbd: Option<XpbdPass>,
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
        let params = settings_buffer(device, "step settings", 64);
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
            ExplicitMethod::Xpbd { substeps, sweeps } => Some(XpbdPass::new(
                gpu,
                precision,
                state,
                (settings.dt, substeps, sweeps),
                StateBuffers {
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
                xpbd: xpbd.as_ref().map(XpbdPass::iterate),
            };
            ContactPass::new(gpu, precision, obstacles.len(), state, pairs.then_some(n))
        });
        let tear = settings.tear.map(|t| {
            let buffers = LinkBuffers {
                x: [&x0, &x1],
                index: &links,
                spring: &spring,
                links: others.len(),
                dashpots,
            };
            TearPass::new(gpu, precision, buffers, t)
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
            readback: ReadBack::default(),
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
        let shape = (self.n, across);
        let both = (external, self.dashpots);
        if let Some(x) = &self.xpbd {
            x.set(&self.gpu, self.precision, shape, settings, both, decay);
        }
        if let Some(c) = &mut self.contact {
            c.set(&self.gpu, self.precision, self.n, settings);
        }
    }

    /// Writes tearing's settings to the card (its strain; how often it looks is fixed when the
    /// step is made).
    fn set_tear(&mut self, settings: &ExplicitSettings) {
        let (Some(t), Some(strain)) = (&self.tear, settings.tear.map(|t| t.strain)) else {
            return;
        };
        let shape = (self.n, self.dispatch.0 * GROUP);
        t.set(&self.gpu, self.precision, shape, strain);
    }

    /// Writes the obstacles' shapes and poses to the card (as many as it was made with): the
    /// caller's poses, where the coming step begins, in f64, are the truth, and the card
    /// moves its copy within a submit (a step at a time, or under XPBD a substep at a time).
    pub fn place(&mut self, obstacles: &[Placed]) {
        if let Some(c) = &mut self.contact {
            let moves = match &self.xpbd {
                Some(x) => (x.substep(self.dt), false),
                None => (self.dt, true),
            };
            c.place(&self.gpu, self.precision, moves, obstacles);
        }
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
                        t.record(pass, self.current, self.dispatch);
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
            t.record(pass, self.current, self.dispatch);
        });
        self.since_tear = 0;
    }

    /// The springs (their indices in the state's spring order) that tore since the last call,
    /// read from the card.
    pub fn torn_springs(&self) -> Result<Vec<usize>, GpuError> {
        let Some(t) = &self.tear else {
            return Ok(vec![]);
        };
        let ranges = [(&t.torn, 0, 4 * t.links as u64)];
        let bytes = self.readback.now(&self.gpu, &ranges)?;
        let mut torn: Vec<usize> = bytes
            .chunks_exact(4)
            .enumerate()
            .filter(|(_, b)| b.iter().any(|&x| x != 0))
            .map(|(link, _)| self.link_spring[link] as usize)
            .collect();
        torn.sort_unstable();
        torn.dedup();
        if !torn.is_empty() {
            t.clear(&self.gpu);
        }
        Ok(torn)
    }

    /// Waits until every submitted step has run.
    pub fn finish(&self) -> Result<(), GpuError> {
        self.gpu.wait()
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
        *pending = Some(self.readback.start(&self.gpu, 0, &ranges)?);
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
        let view = self.readback.end(&self.gpu, read)?;
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
        *pending = Some((self.readback.start(&self.gpu, 1, &ranges)?, host));
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
        let bytes = self.readback.end(&self.gpu, read)?;
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

/// The particles of `state` the step does not move (inverse mass 0), with their positions,
/// velocities and masses.
fn fixed(state: &State) -> Vec<(usize, DVec2, DVec2, f64)> {
    (state.inv_mass.iter().enumerate())
        .filter(|(_, w)| **w == 0.0)
        .map(|(i, _)| (i, state.x[i], state.v[i], state.mass[i]))
        .collect()
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
