#![warn(missing_docs)]
#![doc(test(attr(deny(warnings))))]
//! hooke: an interactive 2D mass-spring simulator on Bevy.
//!
//! # Quick start
//!
//! A headless app (`MinimalPlugins` + [`SimPlugin`]), a pinned particle and a free one joined
//! by a spring, spawned like any Bevy entities, then one simulated second:
//!
//! ```
//! use bevy::math::DVec2;
//! use hooke::sim::{Particle, Pinned, Position, SimParams, Solver, Spring, advance};
//!
//! let mut app = hooke::headless_app();
//! let world = app.world_mut();
//! world.resource_mut::<SimParams>().paused = false;
//! let top = world.spawn((Particle, Position(DVec2::new(0.5, 0.9)), Pinned)).id();
//! let bob = world.spawn((Particle, Position(DVec2::new(0.6, 0.9)))).id();
//! world.spawn(Spring::new(top, bob, 0.1, 1e4));
//!
//! let steps = advance(world, 10_000); // dt = 1e-4 s, through the app's fixed ticks
//! assert_eq!(steps, 10_000);
//! let solver = world.resource::<Solver>();
//! assert!(solver.x()[1].y < 0.9, "the bob swung down");
//! println!("energy after 1 s: {:.3} J", solver.energy(DVec2::new(0.0, -9.8)).total());
//! ```
//!
//! In a full Bevy app, add [`SimPlugin`] to your plugins: the simulation runs in
//! `FixedUpdate` in the ordered sets [`sim::PhysicsSystems`], and each step in the
//! [`sim::PhysicsStep`] schedule's [`sim::StepSystems`]; `examples/` has a headless app, an
//! app with its own drawing (`embed`) and a user force (`custom_force`).
//!
//! # The guide
//!
//! The long explanations live in the guide, in the repository's `docs/` (and in the package):
//! `docs/library.md` (the sets, the components, what is checked, the crate's layout),
//! `docs/integrators.md` (the step pass by pass, and what each integrator computes),
//! `docs/scene-format.md`, `docs/command-line.md`, `docs/large-steps.md`,
//! `docs/stability.md`, `docs/performance.md`, `docs/app.md` and `docs/testing.md`. These
//! API docs say what each item is and does, and name the guide's page where the why is long.
//!
//! # Modules
//!
//! * [`sim`]: the headless simulation ([`sim::SimPlugin`]): particles and springs as entities,
//!   parameters and status as resources, fixed-tick systems in ordered public sets, and the
//!   packed [`sim::Solver`] (read-only).
//! * [`scene`]: the RON scene format, generators, validation and loading.
//! * [`runner`]: headless runs of a scene (`hooke run`).
//! * [`bench`](mod@bench): measured reports (`hooke bench ...`).
//! * [`readable`]: figures as the panel and the command line print them.
//! * `ui` (feature `gui`): the desktop app (`ui::AppPlugin`): panel, pointer gestures (grab,
//!   add, cut, attract), keyboard edits, undo history, zoom and pan.
//!
//! # What is public, and why
//!
//! Users change the simulation through what Bevy users know: components ([`sim::Particle`],
//! [`sim::Position`], [`sim::Velocity`], [`sim::Mass`], [`sim::Pinned`],
//! [`sim::Kinematic`], [`sim::ExternalForce`], [`sim::Spring`]), resources
//! ([`sim::SimParams`] and the others in [`sim`]) and system sets to order their own systems
//! against. Whatever they write is checked before every tick ([`sim::inputs`]): a bad value
//! pauses the simulation with a status that names it, and never panics. The packed state is
//! read through [`sim::Solver`]'s accessors. The solver's machinery (kernels, the AVX pass,
//! the stiffness blocks, thread splits, the integrators' scratch buffers and the ECS sync) is
//! private to the crate: it keeps invariants only the sync maintains, and it changes as the
//! solver gets faster.
//!
//! Outside forces enter through one input: each particle's [`sim::ExternalForce`], which the
//! solver adds wherever it evaluates forces (every stage of every integrator). The app's mouse
//! attraction writes it; so can any user system (wind, a field).

pub mod bench;
pub mod readable;
pub mod runner;
pub mod scene;
pub mod sim;
pub mod solver;
#[cfg(feature = "gui")]
pub mod ui;

pub use sim::SimPlugin;

/// The README's Rust code, compiled and run as a doc-test so that the front door stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

#[cfg(feature = "gui")]
pub use ui::AppPlugin;

use bevy::prelude::*;

/// A headless Bevy app with the simulation and nothing else (no window, no GPU), stepped with
/// [`sim::advance`] or `app.update()`.
///
/// Its schedules run single-threaded: the simulation's systems run one after the other anyway
/// (the step spreads its own work over the solver's threads), and the multi-threaded executor
/// only woke Bevy's task pool threads on every run, which took 15 % of a 64² XPBD run at
/// dt = 1/60 and competed with the solver's threads for the cores. An app with systems of its
/// own to run in parallel can set its executors back.
pub fn headless_app() -> App {
    use bevy::app::{FixedFirst, FixedLast, FixedPostUpdate, FixedPreUpdate};
    use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, SimPlugin));
    let schedules = [
        First.intern(),
        PreUpdate.intern(),
        Update.intern(),
        PostUpdate.intern(),
        Last.intern(),
        FixedFirst.intern(),
        FixedPreUpdate.intern(),
        FixedUpdate.intern(),
        FixedPostUpdate.intern(),
        FixedLast.intern(),
    ];
    for label in schedules {
        app.edit_schedule(label, |s| {
            // `new`, not `default`: the default executor never applies the systems' commands
            // at the schedule's end.
            s.set_executor(SingleThreadedExecutor::new());
        });
    }
    app
}

/// Adds avian's plugins, coupled ([`sim::avian::HookeAvianPlugin`]), to a headless app when
/// the scene has rigid bodies, readied as `App::run` would (`finish`, `cleanup`); nothing for
/// a scene without, so that its runs step exactly as they did.
pub fn add_bodies_for(app: &mut App, loaded: &scene::LoadedScene) {
    #[cfg(feature = "avian")]
    if !loaded.scene.bodies.is_empty() {
        app.add_plugins((
            bevy::transform::TransformPlugin,
            avian2d::prelude::PhysicsPlugins::default(),
            sim::avian::HookeAvianPlugin,
        ));
        app.finish();
        app.cleanup();
    }
    #[cfg(not(feature = "avian"))]
    let _ = (app, loaded);
}

/// A headless app with the scene loaded, running (not paused) and packed into the solver: ready
/// to step, and its state readable before the first step.
pub fn running_app(loaded: &scene::LoadedScene) -> Result<App, String> {
    let mut app = headless_app();
    add_bodies_for(&mut app, loaded);
    let world = app.world_mut();
    scene::load_into_world(world, loaded);
    world.resource_mut::<sim::SimParams>().paused = false;
    sim::pack(world)?;
    Ok(app)
}
