//! One step of size dt, pass by pass: the step's semantics in one place.
//!
//! A step runs these passes in order (the Bevy layer runs each as a system in its public set,
//! [`crate::sim::StepSystems`], so that users can order their own systems between them):
//!
//! 0. **Actuate** ([`actuate`]): only with muscles, each muscle's rest length for the step.
//! 1. **Forces** ([`forces`]): f = m g + f_ext + Σ springs at the start-of-step positions, each
//!    spring evaluated once and scattered to its two ends, then, when the scene has them, the
//!    dashpots at the start-of-step velocities and the gas pressure
//!    ([`super::forces::material`]). Methods that work on positions (projective dynamics, XPBD) take
//!    only the body forces m g + f_ext ([`body_forces`]) and treat the materials in their
//!    solves.
//! 2. **Integrate** ([`integrate`]): the integrator's end-of-step velocity v1, and the drift
//!    velocity u the position update moves with:
//!
//!    | method | force evaluations | v1 | u |
//!    | --- | --- | --- | --- |
//!    | explicit Euler | 1 | v0 + dt a0 ([`kick`]) | v0 |
//!    | symplectic Euler | 1 | v0 + dt a0 ([`kick`]) | v1 (after damping and contact) |
//!    | velocity Verlet | 2 | v½ + dt/2 a(x0 + dt v½), v½ = v0 + dt/2 a0 | v½ |
//!    | RK4 | 4 | v0 + dt/6 (a1 + 2a2 + 2a3 + a4) | (v0 + 2 v2 + 2 v3 + v4)/6 |
//!    | implicit Euler | 1 + CG | (M − dt² K) Δv = dt (f0 + dt K v0), Newton steps after | v1 |
//!    | projective dynamics | body forces | (x1 − x0)/dt, x1 by local/global iterations | v1 |
//!    | XPBD | body forces | the last substep's velocity | (x1 − x0)/dt |
//!    | BDF2 | body forces | (x1 − x̂)/ĥ, x1 by local/global iterations, ĥ = 2dt/3 | (x1 − x0)/dt |
//!    | VBD | body forces | (x1 − x0)/dt, x1 by vertex block descent | v1 |
//!
//!    with a = f/m, and a = 0 for pinned and kinematic particles (inverse mass 0). The methods'
//!    own code is in `methods/`, a file a method.
//! 3. **Damping** ([`damp`]): v *= exp(−μ dt), when μ ≠ 0 and the method does not take the
//!    drag inside its solve (BDF2 always does; projective dynamics and VBD when asked).
//! 4. **Ground** ([`ground`]): a free particle below the ground is put on it and its vertical
//!    velocity zeroed, when the scene has a ground. The test reads the start-of-step position,
//!    except for implicit Euler and projective dynamics, which read where the step will end,
//!    x + dt v ([`super::Contact`]): at their large steps a particle would otherwise end each
//!    step dt·|v_y| under the ground.
//! 5. **Advance** ([`advance`]): x += dt u (u = v for symplectic and implicit Euler and
//!    projective dynamics, the start-of-step v for explicit Euler, the drift for the others),
//!    and a check that everything stayed finite.
//! 6. **Collide** ([`collide`]): only when the scene has obstacles or contact settings. First,
//!    with `particles` on, pairs of particles closer than 2r are pushed apart and lose their
//!    approach velocity ([`super::contact::pairs`]). Then each
//!    free particle that ended the step within its radius of an obstacle (or of the ground,
//!    when contact is set: the ground then leaves pass 4) is put back on the surface, after a
//!    swept test of its path so that it cannot pass through a thin one, and its velocity
//!    relative to the surface loses its approach (keeping the restitution's share) and up to
//!    μ times that of its sliding ([`super::contact`]).
//! 7. **Yield** ([`yield_springs`]): only with plastic springs, each strained past its yield
//!    moves its rest length toward its length.
//!
//! By default the Bevy layer runs passes 2 (the Euler kick only: the other methods' solves run
//! before) to 5 as one sweep over the particles ([`sweep`]), assembled from the passes in use,
//! bit for bit the same result.
//!
//! Every function here takes the packed [`State`], the per-method buffers ([`Workspace`]) and
//! the thread pool ([`Threads`]); none knows who owns the particles.

use super::contact::inside::InSolve;
use super::contact::outline::Outlines;
use super::contact::pairs::{PairReport, Pairs};
use super::contact::{self, Surroundings};
use super::forces::kernels;
use super::forces::sweep::{Motion, Sweep};
use super::method::{Integrator, Iterations};
use super::methods::bdf2::{self, Bdf2};
use super::methods::evaluate::{self, forces_at};
use super::methods::explicit::{rk4, velocity_verlet};
use super::methods::implicit_euler::{CgSettings, Ground, implicit_euler};
use super::methods::projective::{self, FactorOrder, Projective};
use super::methods::scratch::Scratch;
use super::methods::vbd::{self, Vbd};
use super::methods::xpbd::{self, Xpbd};
use super::state::State;
use super::threads::Threads;
use glam::DVec2;

/// What the methods keep from step to step besides the state: the multi-stage and implicit
/// methods' buffers and the pair passes' thread split, projective dynamics' factor, XPBD's
/// colouring, and their counters.
#[derive(Debug, Default)]
pub struct Workspace {
    pub(crate) scratch: Scratch,
    pub(crate) projective: Projective,
    pub(crate) xpbd: Xpbd,
    pub(crate) bdf2: Bdf2,
    pub(crate) vbd: Vbd,
    pub(crate) pairs: Pairs,
    /// The bodies' outlines and the step's particle–edge candidates.
    pub(crate) outlines: Outlines,
    /// Each particle's velocity before contact in the last step whose solve kept contact
    /// (its start velocity plus a step of its forces' acceleration), for the restitution
    /// after it; empty when the last step's solve did not.
    pub(crate) pre_contact: Vec<DVec2>,
    /// The velocity jumps the contact pass would make, spread through the bodies after a
    /// backward Euler step ([`Projective::spread`]).
    jump: Vec<DVec2>,
    /// Each obstacle's reach for the step's solve ([`contact::reaches`]).
    pub(crate) reach: Vec<f64>,
    /// How long each obstacle has been moving onto the particles ([`Surroundings::leads`]).
    pub(crate) lead: Vec<super::contact::obstacle::Lead>,
    /// Where the last step's solve moved the bodies among its unknowns: each of their
    /// obstacles' velocities over the step ([`Self::solved_motion`]).
    solved: Vec<(usize, DVec2, f64)>,
}

impl Workspace {
    /// The obstacles whose bodies the last step's solve moved among its unknowns, each as
    /// (its index, the linear velocity of its centre and the angular velocity that take it
    /// from where the step began to where the solve left it): what whatever moves the
    /// obstacles after the step moves them by, so that the contact after the solve meets each
    /// body moving as the solve moved it, and the body ends where the solve left it. Empty
    /// when the solve moved none (every method but VBD, and VBD without bodies).
    pub fn solved_motion(&self) -> &[(usize, DVec2, f64)] {
        &self.solved
    }

    /// A workspace for a repacked state: new buffers (their sizes and thread split follow the
    /// new arrays), while the large-step methods' precomputation and every counter carry on
    /// (the state's new revision makes them redo the precomputation).
    pub(crate) fn repacked(&mut self) -> Workspace {
        Workspace {
            scratch: self.scratch.repacked(),
            projective: std::mem::take(&mut self.projective),
            xpbd: std::mem::take(&mut self.xpbd),
            bdf2: std::mem::take(&mut self.bdf2).repacked(),
            vbd: std::mem::take(&mut self.vbd).repacked(),
            // The lists name particles by index, which the repacking changed.
            pairs: Pairs::default(),
            outlines: Outlines::default(),
            pre_contact: Vec::new(),
            jump: Vec::new(),
            reach: Vec::new(),
            lead: Vec::new(),
            solved: Vec::new(),
        }
    }

    /// What the iterative methods did so far: iterations per step, factorisations and their
    /// time, colours.
    pub fn solve_stats(&self) -> SolveStats {
        let (sc, pd) = (&self.scratch, &self.projective);
        SolveStats {
            newton_iterations_per_step: sc.newton_iterations_per_step(),
            cg_iterations_per_step: sc.cg_iterations_per_step(),
            projective_iterations_per_step: pd.iterations_per_step(),
            projective_line_searches_per_step: pd.line_searches_per_step(),
            factorizations: pd.factorizations,
            factorization_seconds: pd.factor_seconds,
            symbolic_factorizations: pd.symbolic_factorizations,
            factor_nonzeros: pd.factor_nonzeros(),
            factor_bytes_per_value: pd.factor_bytes_per_value(),
            factor_supernodes: pd.factor_supernodes(),
            factor_halves: pd.factor_halves(),
            factor_order: pd.factor_order(),
            xpbd_sweeps_per_step: self.xpbd.sweeps_per_step(),
            xpbd_colours: self.xpbd.colours(),
            xpbd_constraint_error: self.xpbd.constraint_error(),
            xpbd_force_carried: self.xpbd.force_carried(),
            bdf2_iterations_per_step: self.bdf2.iterations_per_step(),
            bdf2_startup_steps: self.bdf2.startup_steps,
            bdf2_retaken_steps: self.bdf2.retaken_steps,
            bdf2_factorizations: self.bdf2.main.factorizations + self.bdf2.startup.factorizations,
            bdf2_factorization_seconds: self.bdf2.main.factor_seconds
                + self.bdf2.startup.factor_seconds,
            vbd_iterations_per_step: self.vbd.iterations_per_step(),
            vbd_colours: self.vbd.colours(),
            vbd_colourings: self.vbd.colourings,
            vbd_colouring_seconds: self.vbd.colouring_seconds,
            pair_list_builds: self.pairs.rebuilds,
            pair_iterations_per_step: self.pairs.iterations_per_step(),
        }
    }
}

/// The iterative methods' work so far (see [`Workspace::solve_stats`]); a figure is `None` (or
/// 0) when its method has not run.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SolveStats {
    /// Implicit Euler: Newton steps per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newton_iterations_per_step: Option<f64>,
    /// Implicit Euler: conjugate-gradient iterations per time step, all Newton steps together.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cg_iterations_per_step: Option<f64>,
    /// Projective dynamics: local/global iterations per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projective_iterations_per_step: Option<f64>,
    /// Projective dynamics: line searches of the contact forces per time step, each one more
    /// solve with the factor (0 where contact never acts inside the solve).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projective_line_searches_per_step: Option<f64>,
    /// Projective dynamics: factorisations of M + h²L.
    pub factorizations: u64,
    /// Projective dynamics: their wall time, s.
    pub factorization_seconds: f64,
    /// Projective dynamics: of the factorisations, the ones that ordered the matrix anew (its
    /// pattern had changed: springs, pins); the others kept the last order and structure.
    pub symbolic_factorizations: u64,
    /// Projective dynamics: nonzeros of the last Cholesky factor.
    pub factor_nonzeros: usize,
    /// Projective dynamics: bytes per stored value of the factor, 4 (f32) or 8 (f64, for an
    /// ill-conditioned matrix); 0 before the first step.
    pub factor_bytes_per_value: usize,
    /// Projective dynamics: supernodes (dense column blocks) of the last factor; a substitution
    /// pays for each beyond its values.
    pub factor_supernodes: usize,
    /// Projective dynamics: the parts of the last factor's elimination tree that the
    /// substitutions run at once on two or more threads: 2, or 1 when the tree does not split
    /// into halves of nearly equal work or the factor has under 65,536 values; 0 before the
    /// first step.
    pub factor_halves: usize,
    /// Projective dynamics: the fill-reducing order of the last factor, the cheaper of
    /// minimum degree and nested dissection for the substitutions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor_order: Option<FactorOrder>,
    /// XPBD: constraint sweeps per time step (substeps × sweeps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xpbd_sweeps_per_step: Option<f64>,
    /// XPBD: colours of the constraint graph (sweeps run colour by colour).
    pub xpbd_colours: usize,
    /// XPBD: after the last step, the largest error of a compliant constraint,
    /// |C + α̃λ|/L (the springs' violation of what k asks, relative to their rest length),
    /// measured after the last substep's sweeps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xpbd_constraint_error: Option<f64>,
    /// XPBD: after the last step, the force its springs carry, Σ|λ|/hₛ², as a share of the
    /// force k asks for at the same stretch, Σ k|C|: under 1, the cloth is softer than its
    /// stiffness (unconverged sweeps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xpbd_force_carried: Option<f64>,
    /// BDF2: local/global iterations per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bdf2_iterations_per_step: Option<f64>,
    /// BDF2: the backward Euler steps that started (or restarted) its history, or that it
    /// took where contact acts.
    pub bdf2_startup_steps: u64,
    /// BDF2: its steps solved again as backward Euler steps, since contact acted in them.
    pub bdf2_retaken_steps: u64,
    /// BDF2: factorisations, of both its matrices.
    pub bdf2_factorizations: u64,
    /// BDF2: their wall time, s.
    pub bdf2_factorization_seconds: f64,
    /// VBD: iterations per time step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vbd_iterations_per_step: Option<f64>,
    /// VBD: colours of the vertex graph.
    pub vbd_colours: usize,
    /// VBD: colourings so far (one per change of the springs or pins: all it precomputes).
    pub vbd_colourings: u64,
    /// VBD: their wall time, s.
    pub vbd_colouring_seconds: f64,
    /// Contact between particles: neighbour-list builds so far (a build lists every pair
    /// within 2r plus the skin; the lists are kept while no unlisted pair can have come
    /// within 2r).
    pub pair_list_builds: u64,
    /// Contact between particles: position iterations per step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair_iterations_per_step: Option<f64>,
}

/// Pass 1, the body forces alone: f = m g + f_ext (what the position-based methods read).
pub fn body_forces(s: &mut State, gravity: DVec2, threads: &Threads) {
    let external = s.external_active.then_some(&s.external[..]);
    evaluate::body_forces(
        threads,
        s.springs.len(),
        &mut s.f,
        &s.mass,
        external,
        gravity,
    );
}

/// Pass 1, in one parallel region: f = m g + f_ext + Σ spring forces at the start-of-step
/// positions, each thread starting its own particles with their body forces before adding its
/// springs' (bit for bit [`body_forces`] then the spring pass).
pub fn forces(s: &mut State, w: &mut Workspace, gravity: DVec2, threads: &Threads) {
    let mut f = std::mem::take(&mut s.f);
    let xv = (&s.x[..], &s.v[..]);
    forces_at(s, &mut w.scratch.pairs, &mut f, xv, gravity, threads);
    s.f = f;
}

/// Pass 0, muscles: every muscle's rest length for the step that starts at time `t`
/// (held over the step, as a controller's command is).
pub fn actuate(s: &mut State, t: f64) {
    s.materials.actuate(&mut s.springs, t);
}

/// Pass 7, plasticity: every plastic spring strained past its yield moves its rest length
/// toward its length. Returns whether any moved.
pub fn yield_springs(s: &mut State, dt: f64) -> bool {
    s.materials.yield_springs(&mut s.springs, &s.x, dt)
}

/// Keeps the start-of-step velocity as the drift: explicit Euler's position update moves with
/// it. The separate kick does this; the fused sweep needs it only for the contact pass, which
/// reads the path the step took.
pub fn keep_start_velocity(s: &mut State) {
    s.drift_buffer();
    s.drift.copy_from_slice(&s.v);
}

/// Pass 2 for the Euler methods: v += dt f/m; explicit Euler first keeps the start-of-step
/// velocity as the drift.
pub fn kick(s: &mut State, integrator: Integrator, dt: f64, threads: &Threads) {
    if integrator == Integrator::ExplicitEuler {
        keep_start_velocity(s);
    }
    let data = (&mut s.v[..], &s.f[..], &s.inv_mass[..]);
    threads.each(s.springs.len(), data, |(v, f, w)| {
        kernels::kick(v, f, w, dt)
    });
}

/// What one step needs to know of the method: the integrator, dt, gravity, the ground (XPBD
/// resolves contact inside its substeps), the iteration counts and the CG settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Method {
    /// The integrator.
    pub integrator: Integrator,
    /// The step, s.
    pub dt: f64,
    /// Gravitational acceleration, m/s².
    pub gravity: DVec2,
    /// The ground's height, when the scene has one.
    pub ground: Option<f64>,
    /// The iterative methods' counts.
    pub iterations: Iterations,
    /// Implicit Euler's solve.
    pub cg: CgSettings,
    /// The contact radius when particle pairs collide: XPBD pushes pairs apart inside its
    /// substeps too, as it treats the ground.
    pub pair_radius: Option<f64>,
    /// The air damping μ, 1/s, that the method takes inside its solve (BDF2; projective
    /// dynamics and VBD when asked); 0 when the damping pass applies it.
    pub drag: f64,
}

/// Pass 2: the integrator's update (the Euler methods' [`kick`], or the method's solve).
/// The large-step methods keep their iterate out of `around`'s surfaces and, when the settings
/// ask, out of the other particles inside their solves (`contact/inside.rs`); the explicit methods
/// leave contact to pass 6. Fails only when projective dynamics cannot factor its matrix
/// (memory ran out).
pub fn integrate(
    s: &mut State,
    w: &mut Workspace,
    m: &Method,
    around: Option<&Surroundings>,
    threads: &Threads,
) -> Result<(), String> {
    let (dt, g, it) = (m.dt, m.gravity, m.iterations);
    let drag = m.drag;
    if let Some(around) = around {
        ready_outlines(s, w, dt, around);
    }
    let bare_ground = holds_bare_ground(m.integrator);
    let around = around.filter(|a| {
        m.integrator.unconditionally_stable() && (a.active() || bare_ground && a.ground.is_some())
    });
    if let Some(r) = around.and(m.pair_radius) {
        // The pair lists, with a skin that covers how far two particles can close in the
        // step; lists of the step's own pairs (each within its relative closing) for the
        // methods whose iterate moves along the step's velocities: XPBD's substeps and VBD's
        // vertex steps. Implicit Euler's Newton iterates and the global solves move farther
        // (with such lists, the pile under implicit Euler at 1/60 s rose to 206 J from 181 J).
        let per_pair = matches!(m.integrator, Integrator::Xpbd | Integrator::Vbd);
        w.pairs.ready_for_step(s, r, dt, per_pair, threads);
    }
    // Where each particle heads before contact: the side of a thin segment it belongs on,
    // and the approach that restitution keeps a share of after the step (neither there for
    // the bare ground, which pass 6 leaves to the clamp).
    w.pre_contact.clear();
    if around.is_some_and(|a| a.active()) {
        let data = (&s.v[..], &s.f[..], &s.inv_mass[..]);
        w.pre_contact
            .extend((0..s.x.len()).map(|i| data.0[i] + data.1[i] * (data.2[i] * dt)));
    }
    if let Some(a) = around {
        w.reach = contact::reaches(a.obstacles, a.settings.map_or(0.0, |c| c.radius));
        w.lead = a.leads(dt);
    }
    let contact = around.and_then(|a| {
        let (pairs, outlines) = (Some(&w.pairs), Some(&w.outlines));
        InSolve::new(
            a,
            pairs,
            outlines,
            &w.pre_contact,
            (&w.reach, &w.lead),
            dt,
            bare_ground,
        )
    });
    let contact = contact.as_ref();
    w.solved.clear();
    match m.integrator {
        Integrator::ExplicitEuler | Integrator::SymplecticEuler => {
            kick(s, m.integrator, dt, threads)
        }
        Integrator::VelocityVerlet => velocity_verlet(s, &mut w.scratch, dt, g, threads),
        Integrator::Rk4 => rk4(s, &mut w.scratch, dt, g, threads),
        Integrator::ImplicitEuler => {
            let held = (contact, held_ground(m.ground, contact));
            implicit_euler(s, &mut w.scratch, dt, m.cg, it.newton, g, held, threads)
        }
        Integrator::ProjectiveDynamics => {
            let pd = &mut w.projective;
            projective::step(s, pd, dt, drag, it.projective, contact, threads)?
        }
        Integrator::Xpbd => xpbd::step(s, &mut w.xpbd, dt, &it, m.ground, contact, threads),
        Integrator::Bdf2 => {
            let b = &mut w.bdf2;
            bdf2::step(s, b, dt, drag, it.bdf2, m.ground, contact, threads)?
        }
        Integrator::Vbd => {
            let settings = vbd::Settings {
                iterations: it.vbd,
                drag,
                chebyshev: it.vbd_chebyshev,
            };
            vbd::step(s, &mut w.vbd, dt, settings, contact, threads);
            w.solved.extend(w.vbd.solved_motion());
        }
    }
    Ok(())
}

/// Whether the method keeps its iterate out of the ground while it solves even when the scene
/// sets no contact (a frictionless floor for points, as the clamp of pass 4 is). Projective
/// dynamics, BDF2 and VBD do: clamped only after their solve, a body landing at a frame's step
/// has its bottom row stopped while the solve has already pulled the rows above through it.
/// The shipped `soft_box` at 1/60 s ended at 47 % of its height under projective dynamics and
/// 39 % under BDF2, tangled, and a gas ball resting on the ground under VBD at its default 10
/// iterations settled at 64 % of its area (`docs/integrators.md`, pass 4). XPBD's substeps
/// already clamp the ground inside its solve, and implicit Euler holds it in its linear solves
/// by its own means (`methods/implicit_euler/ground.rs`): its contact in the solve, a
/// projection after each Newton step, tangled that box (42 of its 98 triangles turned at 1/60
/// s).
fn holds_bare_ground(integrator: Integrator) -> bool {
    matches!(
        integrator,
        Integrator::ProjectiveDynamics | Integrator::Bdf2 | Integrator::Vbd
    )
}

/// The ground implicit Euler holds in its linear solves (`methods/implicit_euler/ground.rs`):
/// with contact set, the contact's, at its height plus the radius and with its friction (the
/// contact's projection keeps it too); otherwise the bare ground, frictionless as the clamp
/// is, whether or not obstacles bring contact into the solve.
fn held_ground(ground: Option<f64>, contact: Option<&InSolve>) -> Option<Ground> {
    match contact.and_then(InSolve::ground) {
        Some((height, friction)) => Some(Ground { height, friction }),
        None => ground.map(|height| Ground {
            height,
            friction: 0.0,
        }),
    }
}

/// The strongest body-force acceleration: with the fastest particle, how far two particles
/// can close in a step.
fn strongest(s: &State) -> f64 {
    (s.f.iter().zip(&s.inv_mass)).fold(0.0f64, |m, (f, w)| m.max(f.length() * w))
}

/// Lists the step's particle–outline candidates when bodies collide by their outlines, before
/// the step moves anything (the side each particle starts on is what keeps it out): from
/// [`integrate`], and by the adapter before the fused sweep of the Euler methods.
pub fn ready_outlines(s: &State, w: &mut Workspace, dt: f64, around: &Surroundings) {
    if let Some(contact) = around.outlines() {
        let fastest = s.v.iter().fold(0.0f64, |m, v| m.max(v.length()));
        let closing = 2.0 * (fastest * dt + strongest(s) * dt * dt);
        let reach = 1.5 * contact + 2.0 * closing;
        w.outlines.ready(s, reach, around.obstacles);
    }
}

/// Pass 3: v *= exp(−μ dt).
pub fn damp(s: &mut State, damping: f64, dt: f64, threads: &Threads) {
    threads.each(s.springs.len(), &mut s.v[..], |v| {
        kernels::damp(v, damping, dt)
    });
}

/// Pass 4: ground contact, on the start-of-step position or, for the methods that end the step
/// with their end velocity, on where the position update will put the particle
/// ([`Motion::contact`]).
pub fn ground(s: &mut State, integrator: Integrator, dt: f64, ground: f64, threads: &Threads) {
    let data = (&mut s.x[..], &mut s.v[..], &s.inv_mass[..]);
    let contact = motion(integrator).contact(dt);
    threads.each(s.springs.len(), data, |(x, v, w)| {
        kernels::ground_contact(x, v, w, ground, contact)
    });
}

/// How an integrator's step ends: with the Euler kick or without, and which velocity moves the
/// particles (the position update's drift).
pub fn motion(integrator: Integrator) -> Motion {
    match integrator {
        Integrator::ExplicitEuler => Motion::ExplicitEuler,
        Integrator::SymplecticEuler => Motion::SymplecticEuler,
        Integrator::ImplicitEuler | Integrator::ProjectiveDynamics | Integrator::Vbd => {
            Motion::EndVelocity
        }
        Integrator::VelocityVerlet | Integrator::Rk4 | Integrator::Xpbd | Integrator::Bdf2 => {
            Motion::Drift
        }
    }
}

/// Pass 5: x += dt u with the integrator's drift velocity; records whether the step stayed
/// finite.
pub fn advance(s: &mut State, integrator: Integrator, dt: f64, threads: &Threads) {
    let drift = match motion(integrator) {
        Motion::ExplicitEuler | Motion::Drift => &s.drift,
        Motion::SymplecticEuler | Motion::EndVelocity => &s.v,
    };
    let finite = threads.chunked(
        s.springs.len(),
        (&mut s.x[..], &drift[..], &s.v[..]),
        |(x, u, v)| kernels::advance(x, u, v, dt),
        |a, b| a & b,
    );
    s.non_finite = !finite;
}

/// Pass 6: contact between particles (when the settings ask for it, [`super::contact::pairs`]), then
/// with the obstacles, and with the ground when contact is set ([`super::contact`]), on where
/// the step ended. Returns the contacts it resolved.
pub fn collide(
    s: &mut State,
    w: &mut Workspace,
    integrator: Integrator,
    dt: f64,
    gravity: DVec2,
    around: &Surroundings,
    threads: &Threads,
) -> Contacts {
    let pairs = match around.settings {
        Some(c) if c.particles => {
            let reach = contact::reaches(around.obstacles, c.radius);
            let keep_out = |p, from| around.keep_out(p, from, &reach);
            let surface = around.surface(dt, gravity);
            // The methods whose velocity is where the step went (implicit Euler, projective
            // dynamics, XPBD) take the push into it, as position-based dynamics does.
            let follows = integrator.unconditionally_stable().then_some(dt);
            w.pairs
                .collide(s, c.radius, surface, &keep_out, follows, threads)
        }
        _ => PairReport::default(),
    };
    let outlines = match around.outlines() {
        Some(contact) => {
            let surface = around.surface(dt, gravity);
            let follows = integrator.unconditionally_stable().then_some(dt);
            let reactions = around.reactions;
            w.outlines
                .collide(s, contact, surface, follows, OUTLINE_PASSES, reactions)
        }
        None => 0,
    };
    let drift = contact::moves_with_drift(motion(integrator));
    let u = drift.then_some(&s.drift[..]);
    let springs = s.springs.len();
    let surfaces = if w.pre_contact.len() == s.x.len() {
        // The solve kept the particles out of the surfaces: the velocities' response alone.
        // After a backward Euler step the jumps spread through the bodies first
        // ([`Projective::spread`]), where no obstacle stands for a body that would take
        // their reaction.
        let spreads = match integrator {
            Integrator::ProjectiveDynamics => Some(&mut w.projective),
            Integrator::Bdf2 => w.bdf2.backward_euler_solve(),
            _ => None,
        };
        if let Some(pd) = spreads.filter(|_| around.reactions.is_none()) {
            let jump = &mut w.jump;
            jump.clear();
            jump.extend_from_slice(&s.v);
            let pre = &w.pre_contact;
            let (x, w_) = (&s.x, &s.inv_mass);
            contact::settle(x, jump, pre, w_, dt, gravity, around, threads, springs);
            for (j, v) in jump.iter_mut().zip(&s.v) {
                *j -= *v;
            }
            pd.spread(s, jump, threads);
        }
        let pre = &w.pre_contact;
        contact::settle(
            &s.x,
            &mut s.v,
            pre,
            &s.inv_mass,
            dt,
            gravity,
            around,
            threads,
            springs,
        )
    } else {
        contact::collide(
            &mut s.x,
            &mut s.v,
            u,
            &s.inv_mass,
            dt,
            gravity,
            around,
            threads,
            springs,
        )
    };
    Contacts {
        surfaces,
        pairs: pairs.contacts,
        listed_pairs: pairs.listed,
        outlines,
    }
}

/// Gauss–Seidel passes of the outline contact after the step, at most: it stops once the
/// deepest contact is under 1 % of 2r.
const OUTLINE_PASSES: usize = 8;

/// What one step's contact pass resolved.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Contacts {
    /// Particle–surface contacts: the ground and the obstacles.
    pub surfaces: usize,
    /// Particle pairs touching (each pair once).
    pub pairs: usize,
    /// Pairs in the neighbour lists (within 2r plus the skin).
    pub listed_pairs: usize,
    /// Particles touching another body's outline edge ([`super::contact::outline`]).
    pub outlines: usize,
}

impl Contacts {
    /// Every contact: surfaces and pairs.
    pub fn total(&self) -> usize {
        self.surfaces + self.pairs + self.outlines
    }
}

/// Passes 2 (the Euler kick only: the other methods' solves run before) to 5 as one sweep over
/// the particles, with only the parts in use: no damping work when μ = 0, no contact test
/// without a ground (each combination its own loop). Returns the [`Sweep`] it ran.
pub fn sweep(
    s: &mut State,
    integrator: Integrator,
    dt: f64,
    damping: f64,
    ground: Option<f64>,
    threads: &Threads,
) -> Sweep {
    let sweep = Sweep {
        motion: motion(integrator),
        decay: (damping != 0.0).then(|| kernels::decay(damping, dt)),
        ground,
    };
    if sweep.motion == Motion::Drift {
        s.drift_buffer();
    }
    let drift = match sweep.motion {
        Motion::Drift => &s.drift[..],
        // Not read: any array of the particles' length.
        _ => &s.f[..],
    };
    let data = (&mut s.x[..], &mut s.v[..], &s.f[..], &s.inv_mass[..], drift);
    let finite = threads.chunked(
        s.springs.len(),
        data,
        |data| kernels::particle_sweep(data, dt, sweep),
        |a, b| a & b,
    );
    s.non_finite = !finite;
    sweep
}
