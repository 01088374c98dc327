//! Simulation parameters, clock and status: the resources a user or a test turns and reads.

use bevy::math::DVec2;
use bevy::prelude::*;

pub use crate::solver::{ContactSettings, Integrator, Iterations};

/// The solver's threads as a resource (the core's [`crate::solver::Threads`]): all cores by
/// default, one to run everything on the calling thread.
///
/// ```
/// # use hooke::sim::SolverThreads;
/// let mut app = hooke::headless_app();
/// app.insert_resource(SolverThreads::new(1).unwrap()); // everything on the calling thread
/// ```
#[derive(Resource, Debug, Clone, Default, Deref)]
pub struct SolverThreads(pub crate::solver::Threads);

impl SolverThreads {
    /// A pool of `threads` solver threads (1: no pool); fails for 0, or when the OS refuses
    /// the threads.
    pub fn new(threads: usize) -> Result<Self, String> {
        crate::solver::Threads::new(threads).map(SolverThreads)
    }
}

/// Settings of the implicit Euler solve, as a resource (the core's
/// [`crate::solver::CgSettings`]).
///
/// ```
/// # use hooke::sim::CgSettings;
/// let mut app = hooke::headless_app();
/// let mut cg = app.world_mut().resource_mut::<CgSettings>();
/// cg.tolerance = 1e-10;
/// cg.max_iterations = 2000;
/// ```
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Deref, DerefMut)]
pub struct CgSettings(pub crate::solver::CgSettings);

impl CgSettings {
    /// Stop at the relative residual `tolerance` or after `max_iterations`.
    pub fn new(tolerance: f64, max_iterations: u32) -> Self {
        CgSettings(crate::solver::CgSettings {
            tolerance,
            max_iterations,
        })
    }
}

/// The paths of [`Iterations`]' fields in [`SimParams`] (for [`InputProblem::field`]), in the
/// order of [`Iterations::NAMES`].
pub const ITERATION_FIELDS: [&str; 7] = [
    "SimParams.iterations.newton",
    "SimParams.iterations.projective",
    "SimParams.iterations.xpbd_substeps",
    "SimParams.iterations.xpbd_sweeps",
    "SimParams.iterations.bdf2",
    "SimParams.iterations.vbd",
    "SimParams.iterations.xpbd_max_sweeps",
];

/// What the simulation does each step. Defaults are the assignment's.
///
/// ```
/// # use hooke::sim::{Integrator, SimParams};
/// let mut app = hooke::headless_app();
/// let mut params = app.world_mut().resource_mut::<SimParams>();
/// params.integrator = Integrator::VelocityVerlet;
/// params.damping = 0.0;
/// params.stiffness_override = Some(5e4); // every spring, until set back to None
/// params.paused = false;
/// ```
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct SimParams {
    /// Gravitational acceleration, m/s².
    pub gravity: DVec2,
    /// Velocity damping rate μ, 1/s: each step multiplies velocities by exp(-μ dt). 0 = off.
    /// It slows every motion alike, falling included (air drag); [`Self::spring_damping`]
    /// damps only the springs' vibration.
    pub damping: f64,
    /// The dashpot c (N·s/m) of every spring without a [`crate::sim::Dashpot`] of its own
    /// (the panel's slider and `--spring-damping`). 0 = off, and no dashpot pass runs.
    pub spring_damping: f64,
    /// Projective dynamics and VBD take the damping μ inside their solve, as the force
    /// −μ m v, instead of multiplying by exp(−μ dt) after the step (BDF2 always does): at
    /// large steps the splitting is a first-order error of its own. Off by default.
    pub drag_in_solve: bool,
    /// Height of the ground; `None` = no ground.
    pub ground: Option<f64>,
    /// The time integrator.
    pub integrator: Integrator,
    /// Time step, s: above 0 and at most [`MAX_DT`].
    pub dt: f64,
    /// While set, no step runs (the app's G key).
    pub paused: bool,
    /// While set, every spring uses this stiffness instead of its own (the stiffness slider and
    /// `--stiffness`). Clearing it restores each spring's own stiffness.
    pub stiffness_override: Option<f64>,
    /// Tearing: a spring stretched past (1 + strain) × its rest length breaks (is despawned) at
    /// the end of the tick. `None` = springs never break, and the tear pass does not run.
    pub tear: Option<f64>,
    /// Iteration counts of implicit Euler, projective dynamics, XPBD, BDF2 and VBD, XPBD's
    /// tolerance and VBD's Chebyshev ρ.
    pub iterations: Iterations,
    /// Contact: the particles' radius and the friction and restitution of every contact (the
    /// ground's and the obstacles'). `None`: particles are points, the ground clamps with no
    /// friction, and obstacles ([`crate::sim::Obstacle`]) are frictionless and inelastic.
    pub contact: Option<ContactSettings>,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            gravity: DVec2::new(0.0, -9.8),
            damping: 10.0,
            spring_damping: 0.0,
            drag_in_solve: false,
            ground: Some(0.0),
            integrator: Integrator::SymplecticEuler,
            dt: 1e-4,
            paused: false,
            stiffness_override: None,
            tear: None,
            iterations: Iterations::default(),
            contact: None,
        }
    }
}

/// The assignment's spring stiffness, N/m.
pub const DEFAULT_STIFFNESS: f64 = 1e4;
/// The assignment's particle mass, kg.
pub const DEFAULT_MASS: f64 = 1.0;

/// Simulated time and the number of steps taken since the scene was loaded.
///
/// ```
/// # use hooke::sim::{SimClock, advance};
/// let mut app = hooke::headless_app();
/// advance(app.world_mut(), 10);
/// let clock = *app.world().resource::<SimClock>();
/// assert_eq!(clock.steps, 10);
/// assert!((clock.time - 10.0 * 1e-4).abs() < 1e-15);
/// ```
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub struct SimClock {
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
}

/// Whether the simulation is healthy.
///
/// ```
/// # use hooke::sim::{SimParams, SimStatus, advance};
/// let mut app = hooke::headless_app();
/// app.world_mut().resource_mut::<SimParams>().dt = 0.0; // a bad value
/// advance(app.world_mut(), 1);
/// let status = *app.world().resource::<SimStatus>();
/// assert!(matches!(status, SimStatus::InvalidInput(p) if p.field == "SimParams.dt"));
/// ```
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub enum SimStatus {
    #[default]
    /// Healthy.
    Running,
    /// A step produced a non-finite position or velocity, or (where
    /// [`crate::sim::watch::EnergyPeak`] is kept) a state whose energy is not finite. The
    /// simulation paused itself.
    BlewUp {
        /// The 1-based number of the step that did it.
        step: u64,
        /// Simulated time then, s.
        time: f64,
    },
    /// A value a user wrote is unusable (see [`crate::sim::inputs`]); paused, and the solver
    /// keeps its last good state until it is mended.
    InvalidInput(InputProblem),
    /// The total energy rose past the watch's bound (see [`crate::sim::watch`]); paused.
    EnergyGrew {
        /// The 1-based step after which the watch stopped it.
        step: u64,
        /// Simulated time then, s.
        time: f64,
        /// The total energy then, J.
        energy: f64,
        /// The bound it passed, J.
        bound: f64,
    },
}

/// How many times each pass has run since the scene was loaded: shows which systems a scene
/// needs, and proves that the others do not run.
///
/// ```
/// # use hooke::sim::PassCounts;
/// let app = hooke::headless_app();
/// let counts = *app.world().resource::<PassCounts>();
/// assert_eq!(counts.damping, 0); // nothing has stepped yet
/// ```
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PassCounts {
    /// Gravity (the start of the force pass).
    pub gravity: u64,
    /// Spring force passes.
    pub springs: u64,
    /// Integrator updates.
    pub integrate: u64,
    /// Damping passes.
    pub damping: u64,
    /// Ground contact passes.
    pub ground: u64,
    /// Position updates.
    pub advance: u64,
    /// Fused particle sweeps ([`crate::sim::ParticleSweep`]): each also counts as the passes it
    /// did (the kick as `integrate`, `damping`, `ground`, `advance`).
    pub sweeps: u64,
    /// Tear checks (one per tick, only while [`SimParams::tear`] is set).
    pub tear: u64,
    /// Contact passes (only while the scene has obstacles, or contact with a ground).
    pub contact: u64,
    /// Steps that evaluated dashpot or gas forces (only while the scene has them).
    pub materials: u64,
    /// Muscle passes, which set the muscles' rest lengths (only while the scene has muscles).
    pub actuate: u64,
    /// Plasticity passes (only while the scene has plastic springs).
    pub yield_springs: u64,
}

/// Springs broken by tearing since the scene was loaded, and those found this tick (despawned
/// by [`crate::sim::tear::remove_torn_springs`], after whatever wants to see them first).
///
/// ```
/// # use hooke::sim::{SimParams, Tearing};
/// let mut app = hooke::headless_app();
/// app.world_mut().resource_mut::<SimParams>().tear = Some(0.5); // break past 150 % length
/// assert_eq!(app.world().resource::<Tearing>().torn, 0);
/// ```
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct Tearing {
    /// Springs broken so far.
    pub torn: u64,
    /// Springs found overstretched this tick, not yet removed.
    pub pending: Vec<Entity>,
}

/// The longest time step, s (32 years). Bevy's clocks, avian's among them, hold a step as
/// whole nanoseconds with a u64 of seconds; a step of 1e19 s does not fit, and the clock of a
/// scene with rigid bodies panicked at it.
pub const MAX_DT: f64 = 1e9;

/// What is wrong with a time step, as the end of a sentence that starts with its field's name
/// ("dt must be at most 1e9 s"); `None` for a step above 0 and at most [`MAX_DT`]. The one rule
/// for the scene file, `--dt`, the panel's field, the tick's input check and `advance`.
pub fn dt_problem(dt: f64) -> Option<&'static str> {
    if !(dt.is_finite() && dt > 0.0) {
        Some("must be finite and > 0")
    } else if dt > MAX_DT {
        Some("must be at most 1e9 s")
    } else {
        None
    }
}

/// What is wrong with an input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputProblem {
    /// The field, as a user writes it (`SimParams.dt`, `Mass`, `Spring.b`, ...).
    pub field: &'static str,
    /// Its value; `None` for a spring end (an entity, not a number).
    pub value: Option<f64>,
    /// The entity it belongs to, for a component.
    pub entity: Option<Entity>,
    /// What it must be.
    pub rule: &'static str,
}

impl std::fmt::Display for InputProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.field)?;
        if let Some(e) = self.entity {
            write!(f, " of {e}")?;
        }
        if let Some(v) = self.value {
            write!(f, " = {v}")?;
        }
        write!(f, ": {}", self.rule)
    }
}

/// How many steps one fixed tick runs.
///
/// ```
/// # use hooke::sim::TickPlan;
/// let mut app = hooke::headless_app();
/// // Ticks of 1/60 s of simulated time instead of 1/120 s.
/// app.world_mut().resource_mut::<TickPlan>().target_tick_seconds = 1.0 / 60.0;
/// ```
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct TickPlan {
    /// Steps each fixed tick runs.
    pub steps_per_tick: u32,
    /// The simulated time a tick should cover in the app; `steps_per_tick` follows from it and dt.
    pub target_tick_seconds: f64,
}

impl TickPlan {
    /// The steps of a tick at `dt` when ticks are stepped back to back (headless runs,
    /// [`crate::sim::advance`], and the card's tearing), the app's frame budget aside.
    pub fn steps_at(&self, dt: f64) -> u64 {
        ((self.target_tick_seconds / dt).round() as u64).clamp(1, 10_000)
    }
}

impl Default for TickPlan {
    fn default() -> Self {
        TickPlan {
            steps_per_tick: 1,
            target_tick_seconds: 1.0 / 120.0,
        }
    }
}

impl SimParams {
    /// The μ the integrator takes inside its solve: the damping when it takes the drag there
    /// (BDF2 always, projective dynamics and VBD with [`Self::drag_in_solve`]), else 0 (the
    /// damping pass applies it).
    pub fn solve_drag(&self) -> f64 {
        let inside = self.integrator.drags_in_solve()
            || (self.drag_in_solve && self.integrator.can_drag_in_solve());
        if inside { self.damping } else { 0.0 }
    }
}
