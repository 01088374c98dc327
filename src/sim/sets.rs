//! The names of the simulation's order: the fixed tick's sets, the step's schedule and its
//! sets. A system of yours, or an adapter's (`sim::avian`), joins the order by them;
//! [`super::schedule`] puts hooke's own systems in them.

use bevy::ecs::schedule::ScheduleLabel;
use bevy::prelude::*;

/// The sets of a fixed tick, in `FixedUpdate`, in this order. A user system joins the tick by
/// going into one of them, or between two (`.after(PhysicsSystems::Writeback)`):
///
/// ```
/// # use bevy::prelude::*;
/// # use hooke::sim::{PhysicsSystems, Solver, advance};
/// #[derive(Resource, Default)]
/// struct Lowest(f64);
///
/// // Reads the state of the tick just taken.
/// fn lowest_point(solver: Res<Solver>, mut lowest: ResMut<Lowest>) {
///     lowest.0 = solver.x().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
/// }
///
/// let rope = hooke::scene::presets::resolve("rope").unwrap();
/// let mut app = hooke::running_app(&rope).unwrap();
/// app.init_resource::<Lowest>();
/// app.add_systems(FixedUpdate, lowest_point.after(PhysicsSystems::Writeback));
/// advance(app.world_mut(), 1000);
/// assert!(app.world().resource::<Lowest>().0 > 0.0); // above the ground
/// ```
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PhysicsSystems {
    /// 1. Check what users wrote ([`super::inputs`]) and bring ECS edits into the solver:
    ///    write [`super::ExternalForce`], positions and the like before it.
    Prepare,
    /// 2. Run this tick's steps (the [`PhysicsStep`] schedule,
    ///    [`TickPlan::steps_per_tick`](super::TickPlan::steps_per_tick) times).
    Step,
    /// 3. Write results back into the components.
    Writeback,
    /// 4. Break overstretched springs ([`super::tear`]; only while tearing is on).
    Tear,
}

/// The old name of [`PhysicsSystems`] (Bevy names system sets `...Systems` since 0.17).
#[deprecated(since = "0.1.0", note = "renamed to `PhysicsSystems`")]
pub type PhysicsSet = PhysicsSystems;

/// One step of size dt. Its sets ([`StepSystems`]) run in order, with a single-threaded
/// executor, and the schedule is built with ambiguity detection at the error level: a system
/// added to it without an order against the systems it conflicts with fails at build time
/// instead of racing silently.
#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct PhysicsStep;

/// The passes of one step, in [`PhysicsStep`], in this order (`docs/integrators.md`):
///
/// ```
/// # use bevy::prelude::*;
/// # use hooke::sim::{PhysicsStep, Solver, StepSystems, advance};
/// #[derive(Resource, Default)]
/// struct LargestForce(f64);
///
/// // Sees every step's forces before the integrator uses them.
/// fn largest_force(solver: Res<Solver>, mut largest: ResMut<LargestForce>) {
///     let now = solver.f().iter().map(|f| f.length()).fold(0.0, f64::max);
///     largest.0 = largest.0.max(now);
/// }
///
/// let rope = hooke::scene::presets::resolve("rope").unwrap();
/// let mut app = hooke::running_app(&rope).unwrap();
/// app.init_resource::<LargestForce>();
/// app.add_systems(
///     PhysicsStep,
///     largest_force.after(StepSystems::Forces).before(StepSystems::Integrate),
/// );
/// advance(app.world_mut(), 100);
/// assert!(app.world().resource::<LargestForce>().0 > 0.0);
/// ```
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepSystems {
    /// 0. Only with moving obstacles: they move to where the step ends, so that its contact
    ///    sees them there (XPBD's substeps each where the substep ends; not a body that feels
    ///    the particles: those move after the contact, in `Collide`). Only with muscles: each
    ///    muscle's rest length for the step's start time. Runs first, before the forces.
    Actuate,
    /// 1. f = m g + f_ext + Σ spring forces at the start-of-step positions.
    Forces,
    /// 2. The integrator's velocity update (and what it needs for the position update).
    Integrate,
    /// 3. v *= exp(-μ dt).
    Damping,
    /// 4. Ground contact on the start-of-step position (implicit Euler and projective
    ///    dynamics: on the end-of-step position, see [`crate::solver::Contact`]).
    Ground,
    /// 5. The position update, x += dt u, with u the integrator's drift velocity; checks
    ///    finiteness.
    Advance,
    /// 6. Contact between particles when [`SimParams::contact`](super::SimParams::contact)
    ///    asks for it ([`crate::solver::contact::pairs`]), then with the obstacles, and with the
    ///    ground when contact is set ([`crate::solver::contact`]); then the bodies that feel
    ///    the particles, which stood where the step began, move by their velocities.
    ///    Runs only when the scene has obstacles, contact with a ground, or particle pairs.
    Collide,
    /// 7. Only with plastic springs: each strained past its yield moves its rest length toward
    ///    its length ([`crate::sim::Plastic`]).
    Yield,
}

/// The old name of [`StepSystems`].
#[deprecated(since = "0.1.0", note = "renamed to `StepSystems`")]
pub type StepSet = StepSystems;
