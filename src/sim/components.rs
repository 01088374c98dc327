//! The ECS data model: particles and springs are entities.
//!
//! These components are the source of truth that users (the UI, scene loading, tests) read and
//! edit. The hot loop runs on a packed copy ([`crate::sim::Solver`]); edits made here reach it at
//! the start of the next fixed tick, and its results are written back here at the end of a tick.

use bevy::math::DVec2;
use bevy::prelude::*;

use bevy::ecs::lifecycle::HookContext;
use bevy::ecs::world::DeferredWorld;

/// Marks a particle: spawn it like any Bevy entity, `commands.spawn((Particle, Position(p)))`;
/// velocity, mass (1 kg) and the rest come with it. Its [`CreationOrder`] is assigned when it
/// is spawned: the solver orders particles by it, so that scene order (CSV rows, summation
/// order) survives archetype moves such as pinning.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[require(Position, Velocity, Mass, ExternalForce, SolverIndex, CreationOrder)]
#[component(on_add = assign_creation_order)]
pub struct Particle;

/// When a particle was made, among all of them: assigned from [`Serials`] when its
/// [`Particle`] is added (a value set by hand, non-zero, is kept). The solver orders particles
/// by it, so results do not depend on archetype layout.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CreationOrder(pub u64);

/// The hook of [`Particle`]: hands out the next serial (when the world has the
/// [`Serials`] of [`crate::sim::SimPlugin`]).
pub(crate) fn assign_creation_order(mut world: DeferredWorld, context: HookContext) {
    let unset = world
        .get::<CreationOrder>(context.entity)
        .is_some_and(|o| o.0 == 0);
    if !unset {
        return;
    }
    let Some(serial) = world
        .get_resource_mut::<Serials>()
        .map(|mut s| s.next_serial())
    else {
        return;
    };
    if let Some(mut order) = world.get_mut::<CreationOrder>(context.entity) {
        order.0 = serial;
    }
}

/// Position in metres (the scene lives in the unit square by convention).
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Position(pub DVec2);

/// Velocity in metres per second.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Velocity(pub DVec2);

/// Mass in kilograms; always positive and finite (scene validation guarantees it).
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Mass(pub f64);

impl Default for Mass {
    fn default() -> Self {
        Mass(1.0)
    }
}

/// The total force on the particle at the start of the last step (gravity plus springs).
/// Insert it on the particles whose force you want to read: the solver writes it back at the
/// end of every tick to the particles that have it. Editing it has no effect. A particle does
/// not come with one: a cloth of millions of particles would pay 24 bytes each (6 a spring)
/// for numbers nobody reads.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct Force(pub DVec2);

/// A force from outside the spring network, in newtons: wind, the app's mouse attraction, a
/// user's own field. The solver adds it to gravity wherever it evaluates forces, so every
/// integrator sees it at every stage (velocity Verlet's second evaluation, RK4's four, implicit
/// Euler's right-hand side). It is held constant over a fixed tick: write it from a system in
/// `Update` or `FixedUpdate` before [`crate::sim::PhysicsSystems::Prepare`]. A scene where every
/// external force is zero pays nothing for it.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq)]
pub struct ExternalForce(pub DVec2);

/// A particle moved by the user, not by forces: the integrators treat it as having infinite
/// mass (like [`Pinned`]) but it keeps the velocity written to its [`Velocity`], and moves with
/// it during the tick. The app's grab inserts it while the button is held. Adding or removing
/// it patches the solver in place (no repack).
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Kinematic;

/// A pinned particle never moves and keeps zero velocity.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Pinned;

/// A Hooke spring between two particle entities:
/// `f_a = -k (|x_a - x_b| - rest) (x_a - x_b) / |x_a - x_b|`, and `f_b = -f_a`.
/// Spawn it like any component, `commands.spawn(Spring::new(a, b, rest, k))`.
///
/// A spring is this component and nothing else (no index, no serial): a cloth has about four
/// springs per particle, and at millions of springs every byte per spring shows in memory.
/// The solver packs springs by their ends' indices (ties by entity), and finds a spring by its
/// ends when it is edited.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// One end (a particle entity).
    pub a: Entity,
    /// The other end.
    pub b: Entity,
    /// Rest length in metres.
    pub rest: f64,
    /// Stiffness k in N/m. [`crate::sim::SimParams::stiffness_override`] replaces it while set.
    pub stiffness: f64,
}

impl Spring {
    /// A spring from `a` to `b` of rest length `rest` (m) and stiffness `k` (N/m).
    pub fn new(a: Entity, b: Entity, rest: f64, stiffness: f64) -> Self {
        Spring {
            a,
            b,
            rest,
            stiffness,
        }
    }

    /// A spring from `a` to `b` at rest at their current distance; `None` unless both are
    /// particles.
    pub fn at_current_length(world: &World, a: Entity, b: Entity, stiffness: f64) -> Option<Self> {
        let at = |e: Entity| {
            world
                .get::<Position>(e)
                .filter(|_| world.get::<Particle>(e).is_some())
        };
        let rest = at(a)?.0.distance(at(b)?.0);
        Some(Spring::new(a, b, rest, stiffness))
    }
}

/// A dashpot along a spring: `f_a = −c ((v_a − v_b)·n) n`, and `f_b = −f_a`, with n the unit
/// vector from b to a and `c` in N·s/m. It damps the spring's own vibration and leaves the
/// motion of the whole alone (a falling body falls as fast with it). Put it on a spring's
/// entity beside its [`Spring`]; springs without one take [`crate::sim::SimParams::spring_damping`].
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Dashpot(pub f64);

/// A muscle: the spring's rest length oscillates as L(t) = L₀ (1 + A sin(2π f t + φ)), with L₀
/// its [`Spring::rest`] and t the simulated time ([`crate::sim::SimClock::time`]). The rest
/// length is set at the start of each step.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Muscle {
    /// A, a fraction of the rest length.
    pub amplitude: f64,
    /// f, Hz.
    pub frequency: f64,
    /// φ, rad.
    pub phase: f64,
}

/// A plastic spring: strained past `yield_strain` (|l − L|/L), its rest length creeps toward
/// its length at `rate` (1/s), so that a bent thing stays bent. The solver writes the new rest
/// length back to the [`Spring`].
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub struct Plastic {
    /// ε_y, the strain past which the spring yields.
    pub yield_strain: f64,
    /// r, 1/s.
    pub rate: f64,
}

/// A closed loop of particles filled with an ideal gas: the pressure at area A is `nrt / A`,
/// and it pushes each edge of the loop outward with the pressure times the edge's length
/// (Matyka and Ollila 2004). `particles` go around the loop in order, either way round; `nrt`
/// is nRT in N·m (2D). Spawn it as an entity of its own:
/// `commands.spawn(PressureBody { particles, nrt: 20.0 })`. A despawned particle leaves the
/// loop, which closes over the rest.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct PressureBody {
    /// The loop's particles, in order.
    pub particles: Vec<Entity>,
    /// nRT, N·m.
    pub nrt: f64,
}

/// A command that joins `particle` to every other particle within `radius` of it, each by a
/// spring at rest at their current distance (the app's click rule):
/// `commands.queue(JoinWithin { particle, radius: 0.15, stiffness: 1e4 })`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JoinWithin {
    /// The particle to join (already spawned).
    pub particle: Entity,
    /// m.
    pub radius: f64,
    /// N/m.
    pub stiffness: f64,
}

impl Command for JoinWithin {
    type Out = ();

    fn apply(self, world: &mut World) {
        let Some(&Position(at)) = world.get::<Position>(self.particle) else {
            return;
        };
        let mut near: Vec<(CreationOrder, Entity, f64)> = world
            .query_filtered::<(Entity, &Position, &CreationOrder), With<Particle>>()
            .iter(world)
            .filter(|(e, _, _)| *e != self.particle)
            .map(|(e, p, o)| (*o, e, p.0.distance(at)))
            .filter(|(_, _, d)| *d <= self.radius)
            .collect();
        near.sort_by_key(|n| n.0);
        let springs: Vec<Spring> = near
            .into_iter()
            .map(|(_, e, d)| Spring::new(self.particle, e, d, self.stiffness))
            .collect();
        world.spawn_batch(springs);
    }
}

/// Dense index of a particle in the solver's arrays (`u32::MAX` until the next sync packs
/// it). Maintained by the solver sync; read-only for everyone else.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolverIndex(pub u32);

impl Default for SolverIndex {
    fn default() -> Self {
        SolverIndex(u32::MAX)
    }
}

/// Hands out creation serials for particles (see [`CreationOrder`]).
///
/// ```
/// # use hooke::sim::Serials;
/// let mut serials = Serials::default();
/// assert_eq!(serials.next_serial(), 1);
/// ```
#[derive(Resource, Debug, Default)]
pub struct Serials {
    next: u64,
}

impl Serials {
    /// The next serial (the first is 1; 0 means unassigned).
    pub fn next_serial(&mut self) -> u64 {
        self.next += 1;
        self.next
    }
}

/// The query filter for entities whose materials were added or changed.
pub(crate) type MaterialChanged = bevy::ecs::query::Or<(
    bevy::ecs::query::Changed<Dashpot>,
    bevy::ecs::query::Changed<Muscle>,
    bevy::ecs::query::Changed<Plastic>,
    bevy::ecs::query::Changed<PressureBody>,
)>;
