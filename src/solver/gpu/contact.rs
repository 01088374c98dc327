//! Contact on the card ([`contact.wgsl`], [`pairs.wgsl`]): after each explicit step, a free
//! particle that ended within its radius of an obstacle (or of the ground, with contact set)
//! is put back on its surface with the CPU's friction and restitution
//! ([`crate::solver::contact::obstacle`]); under XPBD the same, inside the substeps
//! ([`crate::solver::contact::inside`]); the obstacles move on by their velocities; and, when
//! pairs collide, the particles are pushed apart ([`super::pairs`]).

use super::context::{Gpu, Precision};
use super::kernel::{
    dispatch, empty, entries, pipeline, reals, settings_buffer, shader, write_settings,
};
use super::settings::{ExplicitMethod, ExplicitSettings};
use crate::solver::contact::obstacle::{MIN_THICKNESS, Placed, Shape};
use crate::solver::contact::pairs::Pairs;
use glam::DVec2;

/// The contact pass's kernels (`collide`; `advance`, `count` and `move_obstacles` for the
/// obstacles and the count), in f32.
const CONTACT: &str = include_str!("contact.wgsl");
/// The pair contact's kernels, appended to the contact pass's (whose functions they use).
const PAIRS: &str = include_str!("pairs.wgsl");
/// The overlap, as a share of 2r, under which the pair iterations stop (the CPU's).
const PAIR_TOLERANCE: f64 = crate::solver::contact::pairs::TOLERANCE;
/// Numbers in one obstacle's record (`Obstacle` in `contact.wgsl`).
const OBSTACLE_REALS: usize = 16;

/// The contact pass's pipelines and buffers.
#[derive(Debug)]
pub(super) struct ContactPass {
    collide: wgpu::ComputePipeline,
    /// After a step: the count kept, and the obstacles moved on by a step.
    advance: (wgpu::ComputePipeline, wgpu::BindGroup),
    params: wgpu::Buffer,
    obstacles: wgpu::Buffer,
    /// Obstacles on the card (as many as the pass was made with).
    count: usize,
    /// The last step's contacts, four words: with surfaces at 1, between particles at 2.
    pub(super) counter: wgpu::Buffer,
    /// Bind group `g` follows the step that read `x[g]`, `v[g]`: it places `x[1 - g]`.
    groups: [wgpu::BindGroup; 2],
    /// The contact between particles, when on.
    pairs: Option<super::pairs::PairPass>,
    /// Whether the ground is this pass's (contact is set and the scene has one): with no
    /// obstacles either, only the pairs' passes run.
    ground: bool,
    /// Under XPBD, the contact inside its substeps.
    inside: Option<InSolvePass>,
    /// Whether an obstacle moves (the last [`Self::place`]'s): XPBD's substeps move them.
    moving: bool,
}

/// The contact inside XPBD's substeps (`contact.wgsl`'s `enter`, `hold_out` and `settle`),
/// with the obstacles moved a substep at a time (`move_obstacles`) and the count kept after
/// the step (`count`).
#[derive(Debug)]
struct InSolvePass {
    enter: (wgpu::ComputePipeline, wgpu::BindGroup),
    hold_out: (wgpu::ComputePipeline, wgpu::BindGroup),
    settle: (wgpu::ComputePipeline, wgpu::BindGroup),
    move_obstacles: (wgpu::ComputePipeline, wgpu::BindGroup),
    count: (wgpu::ComputePipeline, wgpu::BindGroup),
}

/// The state's buffers the contact pass reads and writes.
pub(super) struct ContactBuffers<'a> {
    /// Positions and velocities, ping-ponged by the step.
    pub x: [&'a wgpu::Buffer; 2],
    pub v: [&'a wgpu::Buffer; 2],
    pub w: &'a wgpu::Buffer,
    /// The step's links: which pairs a spring joins.
    pub links: &'a wgpu::Buffer,
    /// Under XPBD, its iterate, whose substeps keep contact.
    pub xpbd: Option<Iterate<'a>>,
}

/// XPBD's buffers that the contact inside its substeps reads and writes: the iterate, each
/// substep's start, and each particle's heading before contact.
#[derive(Clone, Copy)]
pub(super) struct Iterate<'a> {
    pub pos: &'a wgpu::Buffer,
    pub prev: &'a wgpu::Buffer,
    pub heading: &'a wgpu::Buffer,
}

impl ContactPass {
    /// The pass for `count` obstacles, and with `pairs: Some(n)` the contact between the n
    /// particles.
    pub(super) fn new(
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
        let collide = pipeline(device, &module, "collide");
        // A pipeline and its bind group (the entry point's own bindings, exactly).
        let bind = |entry: &str, list: &[(u32, &wgpu::Buffer)]| {
            let pipeline = pipeline(device, &module, entry);
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hooke contact"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries(list),
            });
            (pipeline, group)
        };
        let params = settings_buffer(device, "contact settings", 96);
        let obstacles = empty(
            device,
            "obstacles",
            (OBSTACLE_REALS * precision.bytes() * count.max(1)) as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let counter = empty(
            device,
            "contacts",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let control = empty(
            device,
            "pair control",
            4 * super::pairs::CONTROL_WORDS,
            wgpu::BufferUsages::STORAGE,
        );
        let layout = collide.get_bind_group_layout(0);
        // After the step that read `x[from]`, `v[from]`: the start velocities, and the end
        // positions and velocities it wrote.
        let bind_step = |from: usize| {
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
        let groups = [bind_step(0), bind_step(1)];
        let advance = bind(
            "advance",
            &[(0, &params), (5, &obstacles), (6, &counter), (19, &control)],
        );
        let pairs = pairs.map(|n| {
            // After the explicit step that read `x[0]`, the one that read `x[1]`; under XPBD,
            // after the step and inside the substeps.
            let targets = match xpbd {
                Some(xp) => vec![(x[0], v[0]), (xp.pos, v[0])],
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
            let o = &obstacles;
            InSolvePass {
                enter: bind(
                    "enter",
                    &[(0, &params), (4, w), (5, o), (23, xp.pos), (25, xp.heading)],
                ),
                hold_out: bind(
                    "hold_out",
                    &[
                        (0, &params),
                        (4, w),
                        (5, o),
                        (23, xp.pos),
                        (24, xp.prev),
                        (25, xp.heading),
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
                        (25, xp.heading),
                    ],
                ),
                move_obstacles: bind("move_obstacles", &[(0, &params), (5, o)]),
                count: bind("count", &[(6, &counter), (19, &control)]),
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
            pairs,
            ground: false,
            inside,
            moving: false,
        }
    }

    /// Writes the pass's settings for `n` particles.
    pub(super) fn set(
        &mut self,
        gpu: &Gpu,
        precision: Precision,
        n: u32,
        settings: &ExplicitSettings,
    ) {
        let contact = settings.contact.unwrap_or_default();
        let ground = settings.contact.and(settings.ground);
        self.ground = ground.is_some();
        let flags = u32::from(ground.is_some())
            | (u32::from(settings.method == ExplicitMethod::ExplicitEuler) << 1);
        let table = self.pairs.as_ref().map_or(0, |p| p.table);
        let header = [n, self.count as u32, flags, table];
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
        write_settings(&gpu.queue, &self.params, precision, header, &values);
    }

    /// Writes the obstacles' shapes and poses (as many as the pass was made with), each to
    /// move by its velocities a `span` at a time (a step's dt, or a substep's): the caller's
    /// poses, in f64, are the truth, and the card moves its copy within a submit. With
    /// `ahead` (the explicit methods), each is written where the coming step ends, moved on
    /// by its velocities over the span in f64 as the CPU's step moves it before its contact
    /// (`sim::schedule`), and each step's `advance` moves it to where the next one ends.
    /// XPBD's step moves it a substep at a time inside its substeps, from where the step
    /// begins (`InSolve::at_substep` on the CPU).
    pub(super) fn place(
        &mut self,
        gpu: &Gpu,
        precision: Precision,
        (span, ahead): (f64, bool),
        obstacles: &[Placed],
    ) {
        if self.count == 0 || obstacles.len() != self.count {
            return;
        }
        let mut values = Vec::with_capacity(OBSTACLE_REALS * obstacles.len());
        for o in obstacles {
            let (kind, a, b, size) = match o.shape {
                Shape::Circle { radius } => (0.0, DVec2::ZERO, DVec2::ZERO, radius),
                Shape::Box { half } => (1.0, half, DVec2::ZERO, 0.0),
                Shape::Segment { a, b, thickness } => {
                    (2.0, a, b, thickness.max(min_thickness(precision)))
                }
                // Refused when the step was made; the obstacles changed since: the caller's
                // check (`sim::gpu::unsupported`) takes the scene back to the CPU.
                Shape::Polygon(_) => return,
            };
            let mut o = *o;
            if ahead {
                o.advance(span);
            }
            let p = &o.pose;
            let (sin, cos) = p.angle.sin_cos();
            let (turn_sin, turn_cos) = (p.angular_velocity * span).sin_cos();
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
                span,
            ]);
        }
        self.moving = obstacles.iter().any(Placed::moves);
        gpu.queue
            .write_buffer(&self.obstacles, 0, &reals(&values, precision));
    }

    /// Whether the pass keeps particles out of surfaces (obstacles, or the ground).
    fn has_surfaces(&self) -> bool {
        self.count > 0 || self.ground
    }

    /// Records the contact after an explicit step that read `x[from]`: the pairs, then the
    /// surfaces, then the obstacles' motion.
    pub(super) fn record_after_step(
        &self,
        pass: &mut wgpu::ComputePass,
        from: usize,
        particles: (u32, u32),
    ) {
        if let Some(pairs) = &self.pairs {
            pairs.record(pass, from, false);
        }
        if self.has_surfaces() {
            dispatch(pass, &self.collide, &self.groups[from], particles);
        }
        self.record_advance(pass);
    }

    /// Records the contact after XPBD's step, which kept contact inside its substeps and moved
    /// the obstacles there: the pairs (their push into the velocity), the surfaces' velocity
    /// pass, the count.
    pub(super) fn record_after_solve(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        let Some(inside) = &self.inside else { return };
        if let Some(pairs) = &self.pairs {
            pairs.record(pass, 0, true);
        }
        if self.has_surfaces() {
            dispatch(pass, &inside.settle.0, &inside.settle.1, particles);
        }
        dispatch(pass, &inside.count.0, &inside.count.1, (1, 1));
    }

    /// The work groups over the obstacles.
    fn over_obstacles(&self) -> (u32, u32) {
        ((self.count as u32).div_ceil(64).max(1), 1)
    }

    fn record_advance(&self, pass: &mut wgpu::ComputePass) {
        dispatch(
            pass,
            &self.advance.0,
            &self.advance.1,
            self.over_obstacles(),
        );
    }

    /// Records the iterate held out of the surfaces before XPBD's first prediction, over the
    /// dispatch shape `particles`.
    pub(super) fn record_entry(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        if let Some(inside) = self.inside.as_ref().filter(|_| self.has_surfaces()) {
            dispatch(pass, &inside.enter.0, &inside.enter.1, particles);
        }
    }

    /// Records the contact after one of XPBD's substeps: the moving obstacles moved to where
    /// it ends, pairs pushed apart, then the iterate held out of the surfaces along its path
    /// from the substep's start, in the obstacles' frames.
    pub(super) fn record_substep_end(&self, pass: &mut wgpu::ComputePass, particles: (u32, u32)) {
        let Some(inside) = &self.inside else { return };
        if self.moving {
            let (pipeline, group) = &inside.move_obstacles;
            dispatch(pass, pipeline, group, self.over_obstacles());
        }
        if let Some(pairs) = &self.pairs {
            pairs.record_pushes(pass, 1);
        }
        if self.has_surfaces() {
            dispatch(pass, &inside.hold_out.0, &inside.hold_out.1, particles);
        }
    }
}

/// A segment's least thickness on the card: the CPU's in f64, 1e-5 m in f32 (see
/// `contact.wgsl`).
fn min_thickness(precision: Precision) -> f64 {
    match precision {
        Precision::F32 => 1e-5,
        Precision::F64 => MIN_THICKNESS,
    }
}
