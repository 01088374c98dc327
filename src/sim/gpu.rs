//! The world's step on the graphics card (the `gpu` feature): what of a scene the card runs,
//! and stepping the world's packed state there ([`advance_on_gpu`]).
//!
//! The card runs symplectic and explicit Euler with gravity, external forces, damping, the
//! ground, pins, dashpots, tearing, the obstacles and the ground's contact with friction and
//! restitution, and contact between particles; and XPBD (to a fixed count of sweeps) with the
//! same, its contact inside its substeps as on the CPU ([`crate::solver::gpu`]). A scene that uses
//! anything else stays on the CPU, and [`unsupported`] says what keeps it there, in words a user
//! reads. The fixed tick steps there under [`CardStep`], which reads the card's state back each
//! tick, in the background, or on demand (the app's way: [`CardStep::on_demand`]).

use super::obstacles::Obstacles;
use super::params::{SimClock, SimParams, SimStatus};
use super::solver::Solver;
use super::watch::EnergyPeak;
use crate::solver::gpu::{
    ExplicitMethod, ExplicitSettings, Gpu, GpuStep, Precision, Summary, TearSettings,
};
use crate::solver::method::Integrator;
use bevy::ecs::change_detection::DetectChangesMut;
use bevy::ecs::world::World;
use bevy::math::DVec2;
use std::time::{Duration, Instant};

/// The most steps recorded into one submit by [`advance_on_gpu`]; the state is read back (and
/// the energy peak taken) after each.
pub const STEPS_PER_READ: u64 = 1000;

/// What in the world's scene the card does not run, as a sentence; `None` when it runs all of
/// it. Read after the state is packed ([`super::pack`]) and the obstacles gathered (a tick
/// gathers them, and [`advance_on_gpu`] does before it asks).
pub fn unsupported(world: &World) -> Option<String> {
    let params = world.resource::<SimParams>();
    let method = match params.integrator {
        Integrator::SymplecticEuler | Integrator::ExplicitEuler => None,
        Integrator::Xpbd if params.iterations.xpbd_tolerance > 0.0 => {
            Some("the GPU runs XPBD with a fixed count of sweeps, not to a tolerance".into())
        }
        Integrator::Xpbd => None,
        other => Some(format!(
            "the GPU runs symplectic Euler, explicit Euler and XPBD, not {other}"
        )),
    };
    let mut what = vec![];
    if params.contact.is_some_and(|c| c.outlines && c.radius > 0.0) {
        what.push("contact by outlines".to_string());
    }
    if let Some(m) = GpuStep::unsupported(&world.resource::<Solver>().state) {
        what.push(m);
    }
    let obstacles = world.resource::<Obstacles>();
    if obstacles
        .placed()
        .iter()
        .any(|o| matches!(o.shape, crate::solver::Shape::Polygon(_)))
    {
        what.push("convex polygon obstacles".to_string());
    }
    // The world's bodies, not `feel`, which the first tick's gather sets: a run asks before it.
    #[cfg(feature = "avian")]
    if super::avian::has_bodies(world) {
        what.push("obstacles that feel the particles (rigid bodies)".to_string());
    }
    let materials = (!what.is_empty())
        .then(|| format!("the GPU does not run {} yet", crate::readable::list(&what)));
    match (method, materials) {
        (None, None) => None,
        (Some(a), None) | (None, Some(a)) => Some(a),
        (Some(a), Some(b)) => Some(format!("{a}, and {b}")),
    }
}

/// The card's step settings from the world's parameters; tearing looks every
/// `steps_per_tick` steps, at the end of each of the CPU's ticks.
pub fn settings(params: &SimParams, steps_per_tick: u64) -> ExplicitSettings {
    ExplicitSettings {
        method: match params.integrator {
            Integrator::ExplicitEuler => ExplicitMethod::ExplicitEuler,
            Integrator::Xpbd => ExplicitMethod::Xpbd {
                substeps: params.iterations.xpbd_substeps,
                sweeps: params.iterations.xpbd_sweeps,
            },
            _ => ExplicitMethod::SymplecticEuler,
        },
        dt: params.dt,
        gravity: params.gravity,
        damping: params.damping,
        ground: params.ground,
        contact: params.contact,
        tear: params.tear.map(|strain| TearSettings {
            strain,
            every: steps_per_tick.min(u32::MAX as u64) as u32,
        }),
    }
}

/// What follows a submit of `n` steps on the CPU's side: the obstacles moved in f64 as the
/// step moves them, and the clock.
fn after_run(world: &mut World, n: u64) {
    let dt = world.resource::<SimParams>().dt;
    {
        let mut o = world.resource_mut::<Obstacles>();
        for _ in 0..n {
            o.advance(dt, true);
            o.advance(dt, false);
        }
    }
    let mut clock = world.resource_mut::<SimClock>();
    clock.steps += n;
    clock.time += n as f64 * dt;
}

/// The state the card sends back, into the solver (a read [`GpuStep::begin_read`] started,
/// waited for only if the card has not finished it; else one read now): the positions and
/// velocities (a spring the card broke carries nothing from here on: its index goes into
/// `torn`, its entity at the end of the run), the last step's contacts, the energy peak when
/// one is kept, and a blow-up's status. Returns whether the state is finite.
fn take_state(world: &mut World, card: &GpuStep, torn: &mut Vec<usize>) -> Result<bool, String> {
    {
        let mut solver = world.resource_mut::<Solver>();
        card.finish_read_into(&mut solver.state)
            .map_err(|e| e.to_string())?;
        solver.energy_on_card = None;
        for i in card.torn_springs().map_err(|e| e.to_string())? {
            solver.state.springs[i].k = 0.0;
            torn.push(i);
        }
    }
    world.resource_mut::<Obstacles>().contacts = crate::solver::Contacts {
        surfaces: card.contacts(),
        pairs: card.pair_contacts(),
        ..Default::default()
    };
    if world.contains_resource::<EnergyPeak>() {
        let gravity = world.resource::<SimParams>().gravity;
        let energy = world.resource::<Solver>().energy(gravity).total();
        if !world.resource_mut::<EnergyPeak>().note(energy) {
            // As on the CPU: an energy past the floats is a blow-up, the state finite or not.
            world.resource_mut::<Solver>().non_finite = true;
        }
    }
    let clock = *world.resource::<SimClock>();
    let finite = !world.resource::<Solver>().non_finite;
    if !finite {
        *world.resource_mut::<SimStatus>() = SimStatus::BlewUp {
            step: clock.steps,
            time: clock.time,
        };
        world.resource_mut::<SimParams>().paused = true;
    }
    Ok(finite)
}

/// The world's packed state uploaded to `gpu` in `precision`, with the obstacles gathered as
/// a tick gathers them; why not, when the card does not run the scene or refuses it.
pub fn card_for(world: &mut World, gpu: &Gpu, precision: Precision) -> Result<GpuStep, String> {
    world
        .run_system_cached(super::obstacles::gather_obstacles)
        .map_err(|e| e.to_string())?;
    if let Some(why) = unsupported(world) {
        return Err(why);
    }
    let params = world.resource::<SimParams>();
    let per_tick = world
        .resource::<super::params::TickPlan>()
        .steps_at(params.dt);
    let obstacles = world.resource::<Obstacles>().placed();
    let state = &world.resource::<Solver>().state;
    GpuStep::new(
        gpu,
        state,
        &settings(params, per_tick),
        obstacles,
        precision,
    )
    .map_err(|e| e.to_string())
}

/// Steps the world's packed state `steps` times on `gpu` in `precision`, in submits of up to
/// [`STEPS_PER_READ`] steps, reading it back after each: the clock advances, an
/// [`EnergyPeak`] present takes the energy after each submit (not after every step, as on the
/// CPU), and a non-finite state stops the run as a blow-up does on the CPU (at the end of the
/// submit it was found in). Returns the steps taken, or why the card could not run the
/// scene (nothing is stepped then).
pub fn advance_on_gpu(
    world: &mut World,
    gpu: &Gpu,
    precision: Precision,
    steps: u64,
) -> Result<u64, String> {
    advance_on_gpu_telling(world, gpu, precision, steps, |_| {})
}

/// [`advance_on_gpu`], calling `after_read` with the steps taken so far after each read-back
/// (`hooke run`'s progress line): the card's run is the same, bit for bit.
pub fn advance_on_gpu_telling(
    world: &mut World,
    gpu: &Gpu,
    precision: Precision,
    steps: u64,
    mut after_read: impl FnMut(u64),
) -> Result<u64, String> {
    // The obstacles as the tick gathers them from their entities (and writes back after).
    let mut card = card_for(world, gpu, precision)?;
    let mut taken = 0;
    let mut torn = vec![];
    while taken < steps {
        let n = (steps - taken).min(STEPS_PER_READ);
        card.place(world.resource::<Obstacles>().placed());
        card.run(n as u32);
        if taken + n == steps {
            // The CPU tears at the end of every tick, its run's last (shorter) one too.
            card.tear_now();
        }
        taken += n;
        after_run(world, n);
        if !take_state(world, &card, &mut torn)? {
            break;
        }
        after_read(taken);
    }
    world
        .run_system_cached(super::obstacles::write_back_obstacles)
        .map_err(|e| e.to_string())?;
    // The entities take the card's state, as the tick's write-back gives them the CPU's: the
    // next repack (the torn springs' removal is one) builds from them.
    if !world.resource::<Solver>().non_finite {
        world
            .run_system_cached(super::sync::sync_from_solver)
            .map_err(|e| e.to_string())?;
    }
    if !torn.is_empty() {
        let entities: Vec<_> = {
            let solver = world.resource::<Solver>();
            torn.iter()
                .filter_map(|&i| solver.spring_entity_in(world, i))
                .collect()
        };
        world.resource_mut::<super::params::Tearing>().pending = entities;
        world
            .run_system_cached(super::tear::remove_torn_springs)
            .map_err(|e| e.to_string())?;
        // Repacked now, as the next tick would, so that the state reads without them.
        super::pack(world)?;
    }
    Ok(taken)
}

/// The fixed tick's steps on the card: the panel's switch, and what a library user sets to
/// step a world there tick by tick. With `wanted` on and a card given
/// ([`CardStep::use_card`]; the app hands over its renderer's), each tick whose scene the card
/// runs steps there: the state is uploaded when the CPU changed it (a repack, a drag, an
/// edit), the tick's steps run in one submit, and the state comes back for the write-back,
/// the drawing and tearing, which then run as on the CPU. A scene the card does not run
/// steps on the CPU, and `why_not` says why.
#[derive(bevy::prelude::Resource, Default)]
pub struct CardStep {
    /// Step on the card when it can.
    pub wanted: bool,
    /// The width the card computes in.
    pub precision: Option<Precision>,
    /// Why this tick's steps ran on the CPU although the card was wanted; `None` while they run
    /// on the card or the card is not wanted.
    pub why_not: Option<String>,
    /// Read the state back in the background: a tick's steps are submitted with a copy of the
    /// state that the next tick takes ([`receive_from_card`]), so that no frame waits for the
    /// card (the app's way); the solver then shows the state one tick behind the card's, and
    /// [`catch_up`] brings it level. Off: each tick waits for its state.
    pub background_reads: bool,
    /// Read the card's state only when something needs it (the app's way): each tick brings
    /// back only the card's [`Summary`] (the energy by kind, springs torn, contacts), and the
    /// card tears the springs itself. The state comes back in the background while reads are
    /// wanted ([`CardStep::keep_reading`]: the app asks on every input, for picking and
    /// editing), for [`catch_up`] (saving, a library user's look), before the CPU takes the
    /// steps back, before an edit of the world goes into the solver, and when springs tore or
    /// the state blew up. Meanwhile the packed state and the entities lag the card's, and
    /// [`Solver::energy_now`] gives the card's sum.
    pub on_demand: bool,
    gpu: Option<Gpu>,
    step: Option<GpuStep>,
    /// What the card's copy was made from: the state's revision, particles and obstacles, the
    /// settings, the precision, and whether an external force was set.
    made_for: Option<MadeFor>,
    /// The state's edit count when the card last had the state.
    edits: u64,
    /// Whether the last tick's steps ran on the card.
    active: bool,
    /// The last tick's submit time and steps, while its state is read in the background.
    submitted: Option<(std::time::Duration, u64)>,
    /// Steps ran on the card since the solver last took its state.
    behind: bool,
    /// Until when each tick reads the state back ([`CardStep::keep_reading`]).
    read_until: Option<Instant>,
    /// The last summary the card sent.
    summary: Option<Summary>,
}

impl CardStep {
    /// The card to step on.
    pub fn use_card(&mut self, gpu: Gpu) {
        self.gpu = Some(gpu);
        self.step = None;
        self.made_for = None;
    }

    /// With [`CardStep::on_demand`]: read the state back each tick for `span` from now (the
    /// app asks on every input, so that picking and edits see the state of the tick before).
    pub fn keep_reading(&mut self, span: Duration) {
        let until = Instant::now() + span;
        if self.read_until.is_none_or(|t| t < until) {
            self.read_until = Some(until);
        }
    }

    /// Whether the packed state (and the entities) lag the card's: steps ran there since the
    /// solver last took its state ([`catch_up`] brings it level).
    pub fn behind(&self) -> bool {
        self.behind
    }

    /// The last [`Summary`] the card sent (with [`CardStep::on_demand`]).
    pub fn summary(&self) -> Option<Summary> {
        self.summary
    }

    /// Whether this tick's state comes back.
    fn reads_wanted(&self) -> bool {
        !self.on_demand || self.read_until.is_some_and(|t| Instant::now() < t)
    }

    /// The card's name, when one was given.
    pub fn adapter(&self) -> Option<String> {
        self.gpu.as_ref().map(Gpu::adapter)
    }

    /// Whether the last tick's steps ran on the card.
    pub fn active(&self) -> bool {
        self.active
    }

    /// What a drawing of the card's state reads, while the ticks step there.
    pub fn draw_source(&self) -> Option<crate::solver::gpu::DrawSource> {
        self.step
            .as_ref()
            .filter(|_| self.active)
            .and_then(GpuStep::draw_source)
    }

    /// The card failed (a device lost, a buffer refused): the steps go back to the CPU, and the
    /// panel says why.
    fn give_up(&mut self, why: String) {
        tracing::warn!("hooke: {why}; stepping on the CPU");
        self.wanted = false;
        self.forget_copy();
        self.why_not = Some(why);
    }

    /// Lets the card's copy of the state go: the next tick on the card uploads it afresh.
    /// (Whoever calls it brought the solver level first, or the card failed.)
    fn forget_copy(&mut self) {
        self.active = false;
        self.step = None;
        self.made_for = None;
        self.behind = false;
        self.summary = None;
    }

    /// The precision in use: the one asked for, else f32.
    fn precision(&self) -> Precision {
        self.precision.unwrap_or(Precision::F32)
    }
}

/// What a card's copy of the state was made from ([`CardStep`]).
type MadeFor = (u64, usize, usize, ExplicitSettings, Precision, bool);

/// Run condition: this tick's steps go to the card (the card is wanted, given, and runs the
/// scene; [`decide_device`] settled it).
pub fn on_card(card: Option<bevy::prelude::Res<CardStep>>) -> bool {
    card.is_some_and(|c| c.active)
}

/// Before the tick's steps: whether they go to the card, and if not although it is wanted, why.
/// Steps leaving the card take its state first.
pub fn decide_device(world: &mut World) {
    let Some(card) = world.get_resource::<CardStep>() else {
        return;
    };
    if !card.wanted {
        if card.active || card.why_not.is_some() || card.step.is_some() {
            with_card(world, |world, card| {
                level_or_give_up(world, card);
                card.forget_copy();
                card.why_not = None;
            });
        }
        return;
    }
    let why = if card.gpu.is_none() {
        Some("no graphics card was given".to_string())
    } else if world
        .resource::<super::pull::Attraction>()
        .active_at
        .is_some()
    {
        Some("the GPU does not run the pull yet".to_string())
    } else {
        unsupported(world)
    };
    let leaving = card.active && why.is_some();
    with_card(world, |world, card| {
        if leaving {
            level_or_give_up(world, card);
            card.forget_copy();
        }
        card.active = why.is_none();
        if card.why_not != why {
            card.why_not = why;
        }
    });
}

/// Runs `f` with the card taken out of the world (so that both can be borrowed).
fn with_card<T>(world: &mut World, f: impl FnOnce(&mut World, &mut CardStep) -> T) -> Option<T> {
    let mut card = world.remove_resource::<CardStep>()?;
    let out = f(world, &mut card);
    world.insert_resource(card);
    Some(out)
}

/// Brings the solver and the entities level with the card's state ([`level`]); a card that
/// fails gives the steps back to the CPU.
fn level_or_give_up(world: &mut World, card: &mut CardStep) {
    if let Err(e) = level(world, card) {
        card.give_up(e);
    }
}

/// Brings the solver and the entities level with the card's state, where steps ran there since
/// the solver last took it: the read under way, or one now. An entity whose position or
/// velocity differs from what the solver last gave it was edited since, and keeps its edit
/// (the tick's sync brings it into the solver). Springs the card tore are noted for removal.
fn level(world: &mut World, card: &mut CardStep) -> Result<(), String> {
    if !card.behind {
        return Ok(());
    }
    card.behind = false;
    let Some(step) = card.step.as_ref() else {
        return Ok(());
    };
    let before = motion(world);
    // A summary under way describes the state this read brings: taken, so that no later
    // tick reads it as news.
    step.finish_summary().map_err(|e| e.to_string())?;
    let mut torn = vec![];
    let finite = take_state(world, step, &mut torn)?;
    note_torn(world, &torn);
    if finite {
        world
            .run_system_cached_with(write_back_unedited, before)
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// The solver's positions and velocities as they stand: what [`write_back_unedited`] compares
/// the particles' components with, after a read changed the solver.
fn motion(world: &World) -> (Vec<DVec2>, Vec<DVec2>) {
    let s = &world.resource::<Solver>().state;
    (s.x.clone(), s.v.clone())
}

/// The solver's positions and velocities into the particles' components, without flagging them
/// as changed, where a component still holds what the solver had before (`before`): one that
/// differs was edited since, and keeps its edit.
fn write_back_unedited(
    bevy::prelude::In((x, v)): bevy::prelude::In<(Vec<DVec2>, Vec<DVec2>)>,
    solver: bevy::prelude::Res<Solver>,
    mut particles: bevy::prelude::Query<
        (
            &super::components::SolverIndex,
            &mut super::components::Position,
            &mut super::components::Velocity,
        ),
        bevy::prelude::With<super::components::Particle>,
    >,
) {
    for (index, mut pos, mut vel) in &mut particles {
        let i = index.0 as usize;
        let (Some(&x0), Some(&v0), Some(&x1), Some(&v1)) =
            (x.get(i), v.get(i), solver.x.get(i), solver.v.get(i))
        else {
            continue;
        };
        if pos.0 == x0 && vel.0 == v0 {
            pos.bypass_change_detection().0 = x1;
            vel.bypass_change_detection().0 = v1;
        }
    }
}

/// The springs the card tore (their packed indices) go to the tick's tearing, which removes
/// their entities (and the app records them for undo).
fn note_torn(world: &mut World, torn: &[usize]) {
    if torn.is_empty() {
        return;
    }
    let entities: Vec<_> = {
        let solver = world.resource::<Solver>();
        torn.iter()
            .filter_map(|&i| solver.spring_entity_in(world, i))
            .collect()
    };
    // Each torn spring once: the card's list has no repeats, and the CPU does not tear
    // while the card does.
    world
        .resource_mut::<super::params::Tearing>()
        .pending
        .extend(entities);
}

/// The tick's steps on the card (in place of the CPU's `run_steps`, under [`on_card`]).
pub fn run_steps_on_card(world: &mut World) {
    let steps = u64::from(world.resource::<super::params::TickPlan>().steps_per_tick);
    let start = std::time::Instant::now();
    let Some(mut card) = world.remove_resource::<CardStep>() else {
        return;
    };
    if let Err(e) = tick_on_card(world, &mut card, steps) {
        card.give_up(e);
    }
    let submitted = start.elapsed();
    let reading = card
        .step
        .as_ref()
        .is_some_and(|s| s.reading() || s.summarising());
    if reading {
        // The steps' cost is known once their state comes back: the next tick's wait adds to
        // the submit's time ([`receive_from_card`]), so that the frame budget sees what the
        // card takes, not only what it took to ask.
        card.submitted = Some((submitted, steps));
    }
    world.insert_resource(card);
    if !reading {
        world
            .resource_mut::<super::budget::StepBudget>()
            .note_steps(submitted, steps);
    }
}

fn tick_on_card(world: &mut World, card: &mut CardStep, steps: u64) -> Result<(), String> {
    let Some(gpu) = card.gpu.clone() else {
        return Ok(());
    };
    let params = world.resource::<SimParams>().clone();
    let precision = card.precision();
    let all = settings(&params, steps);
    let settings = ExplicitSettings {
        // Tearing is the tick's own (the CPU's systems read the state the card sends back),
        // unless the state comes back on demand: then the card tears, and its summary says so.
        tear: all.tear.filter(|_| card.on_demand),
        ..all
    };
    let (revision, n, edits, external) = {
        let s = &world.resource::<Solver>().state;
        (s.revision, s.particle_count(), s.edits, s.external_active())
    };
    let obstacles = world.resource::<Obstacles>().placed().len();
    let key = (revision, n, obstacles, settings, precision, external);
    let stale = card.made_for != Some(key);
    if stale && card.behind {
        // New settings for the same state (an edit of the world would have brought it level
        // at the tick's start): the old copy's state first.
        level(world, card)?;
    }
    let step = match card.step.take() {
        Some(mut step) if !stale => {
            // The CPU changed the state since the card last had it (a drag, an undo, a user
            // force): the card takes it.
            let state = &world.resource::<Solver>().state;
            if card.edits != edits || state.external_active() {
                step.write_state(state);
            } else {
                // A held particle dragged (its moves are not edits: the step does not move it).
                step.write_fixed(state);
            }
            step
        }
        _ => {
            let solver = world.resource::<Solver>();
            let placed = world.resource::<Obstacles>().placed();
            card.made_for = Some(key);
            GpuStep::new(&gpu, &solver.state, &settings, placed, precision)
                .map_err(|e| e.to_string())?
        }
    };
    let reads_wanted = card.reads_wanted();
    let step = card.step.insert(step);
    step.place(world.resource::<Obstacles>().placed());
    step.run(steps as u32);
    after_run(world, steps);
    card.behind = true;
    if card.on_demand {
        step.begin_summary(params.gravity)
            .map_err(|e| e.to_string())?;
        if reads_wanted {
            step.begin_read().map_err(|e| e.to_string())?;
        }
    } else if card.background_reads {
        // Taken at the start of the next tick ([`receive_from_card`]), by when the card has
        // run the steps and copied the state while the frame went on.
        step.begin_read().map_err(|e| e.to_string())?;
    } else {
        // The card does not tear here (only with reads on demand): nothing torn to note.
        take_state(world, step, &mut vec![])?;
        card.behind = false;
    }
    card.edits = world.resource::<Solver>().state.edits;
    Ok(())
}

/// At the start of a tick, before the ECS's edits go into the solver: what the last tick's
/// steps left on the card, read in the background ([`CardStep::background_reads`]), into the
/// solver; with [`CardStep::on_demand`], the card's summary, and the state where it came back
/// too, or where the summary or the world's edits need it ([`CardStep::on_demand`]). It waits
/// only where the card has not finished those steps and their copy.
pub fn receive_from_card(world: &mut World) {
    receive(world);
}

/// Takes the state or the summary of a read under way, if there is one, and brings the solver
/// level where the world's edits need it; returns whether a state was taken.
fn receive(world: &mut World) -> bool {
    with_card(world, |world, card| {
        let start = std::time::Instant::now();
        let taken = take_reads(world, card);
        if let Some((submit, steps)) = card.submitted.take() {
            world
                .resource_mut::<super::budget::StepBudget>()
                .note_steps(submit + start.elapsed(), steps);
        }
        match taken {
            Ok(state) => state,
            Err(e) => {
                card.give_up(e);
                false
            }
        }
    })
    .unwrap_or(false)
}

/// [`receive`]'s work; returns whether a state was taken.
fn take_reads(world: &mut World, card: &mut CardStep) -> Result<bool, String> {
    let Some(step) = card.step.as_ref() else {
        return Ok(false);
    };
    let summary = step.finish_summary().map_err(|e| e.to_string())?;
    let mut state = false;
    if step.reading() {
        let mut torn = vec![];
        take_state(world, step, &mut torn)?;
        note_torn(world, &torn);
        card.behind = false;
        state = true;
    }
    if let Some(s) = summary {
        card.summary = Some(s);
    }
    if !card.behind {
        return Ok(state);
    }
    if let Some(s) = summary {
        world.resource_mut::<Obstacles>().contacts = crate::solver::Contacts {
            surfaces: s.contacts[0],
            pairs: s.contacts[1],
            ..Default::default()
        };
        let total = s.energy.total();
        // Not a change of the solver: nothing downstream redoes its work for it (the
        // write-back of every entity least of all).
        world
            .resource_mut::<Solver>()
            .bypass_change_detection()
            .energy_on_card = Some(s.energy);
        if let Some(mut peak) = world.get_resource_mut::<EnergyPeak>() {
            peak.note(total);
        }
        if !total.is_finite() || s.torn_links > 0 {
            // A blow-up takes the CPU's way (the state rolls back), and torn springs go.
            level(world, card)?;
            return Ok(true);
        }
    }
    if world
        .run_system_cached(super::sync::edits_pending)
        .map_err(|e| e.to_string())?
    {
        level(world, card)?;
        return Ok(true);
    }
    Ok(state)
}

/// Takes the state of a read under way into the solver and the entities now (waiting for the
/// card), or, with [`CardStep::on_demand`], reads it now: what a library user calls after
/// stepping with background reads, to see the last tick's state rather than an older one.
pub fn catch_up(world: &mut World) -> Result<(), String> {
    let before = motion(world);
    if receive(world) && !world.resource::<Solver>().non_finite {
        // Edits of the world since the last tick keep theirs, as with `level`.
        world
            .run_system_cached_with(write_back_unedited, before)
            .map_err(|e| e.to_string())?;
    }
    with_card(world, level).unwrap_or(Ok(()))
}

/// Before a frame's input is handled: while reads are wanted ([`CardStep::keep_reading`]: the
/// app asks on every input), the solver and the entities level with the card, so that picking
/// and edits see the state of the last tick.
pub fn catch_up_while_reading(world: &mut World) {
    let wanted = world
        .get_resource::<CardStep>()
        .is_some_and(|c| c.on_demand && c.active && c.behind && c.reads_wanted());
    if wanted && let Err(e) = catch_up(world) {
        with_card(world, |_, card| card.give_up(e));
    }
}
