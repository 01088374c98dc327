//! Checks, at the start of every fixed tick, what users can write: the [`SimParams`],
//! [`TickPlan`] and [`CgSettings`] resources and the particles' [`Mass`] and springs'
//! [`Spring`] components and their materials (those added or changed
//! since the last tick). A bad value pauses the simulation with
//! [`SimStatus::InvalidInput`], which names the field and the value; until it is mended the
//! solver is neither fed nor stepped nor written back, so the last good state stays and no NaN
//! is drawn. Mended, the status goes back to running (still paused).

use super::components::{Dashpot, Mass, Muscle, Particle, Plastic, PressureBody, Spring};
use super::obstacles::{Obstacle, ObstaclePose, ObstacleVelocity};
pub use super::params::InputProblem;
use super::params::{CgSettings, Iterations, SimParams, SimStatus, TickPlan};
use bevy::prelude::*;

fn problem(field: &'static str, value: f64, rule: &'static str) -> InputProblem {
    InputProblem {
        field,
        value: Some(value),
        entity: None,
        rule,
    }
}

/// A spring end that is not what it must be.
fn bad_end(field: &'static str, rule: &'static str) -> InputProblem {
    InputProblem {
        value: None,
        ..problem(field, f64::NAN, rule)
    }
}

/// The first problem with the parameters, if any.
pub fn check_params(p: &SimParams) -> Option<InputProblem> {
    const POSITIVE: &str = "must be finite and > 0";
    const NON_NEGATIVE: &str = "must be finite and >= 0";
    const FINITE: &str = "must be finite";
    let bad_positive = |v: f64| !(v.is_finite() && v > 0.0);
    let bad_non_negative = |v: f64| !(v.is_finite() && v >= 0.0);
    if let Some(rule) = super::params::dt_problem(p.dt) {
        return Some(problem("SimParams.dt", p.dt, rule));
    }
    for (field, v) in [
        ("SimParams.gravity.x", p.gravity.x),
        ("SimParams.gravity.y", p.gravity.y),
    ] {
        if !v.is_finite() {
            return Some(problem(field, v, FINITE));
        }
    }
    if bad_non_negative(p.damping) {
        return Some(problem("SimParams.damping", p.damping, NON_NEGATIVE));
    }
    if bad_non_negative(p.spring_damping) {
        return Some(problem(
            "SimParams.spring_damping",
            p.spring_damping,
            NON_NEGATIVE,
        ));
    }
    if let Some(g) = p.ground.filter(|g| !g.is_finite()) {
        return Some(problem("SimParams.ground", g, FINITE));
    }
    if let Some(k) = p.stiffness_override.filter(|k| bad_non_negative(*k)) {
        return Some(problem("SimParams.stiffness_override", k, NON_NEGATIVE));
    }
    if let Some(s) = p.tear.filter(|s| bad_positive(*s)) {
        return Some(problem("SimParams.tear", s, POSITIVE));
    }
    if let Some((field, v)) = p.iterations.out_of_range() {
        let field = super::params::ITERATION_FIELDS[field];
        return Some(problem(field, v as f64, Iterations::RULE));
    }
    if let Some((name, v, rule)) = p.iterations.bad_real() {
        let field = match name {
            "xpbd_tolerance" => "SimParams.iterations.xpbd_tolerance",
            _ => "SimParams.iterations.vbd_chebyshev",
        };
        return Some(problem(field, v, rule));
    }
    if let Some((field, v, rule)) = p.contact.as_ref().and_then(|c| c.problem()) {
        let field = match field {
            "radius" => "SimParams.contact.radius",
            "friction" => "SimParams.contact.friction",
            _ => "SimParams.contact.restitution",
        };
        return Some(problem(field, v, rule));
    }
    None
}

/// The problem with an obstacle's shape, pose or velocity, if any.
pub fn check_obstacle(
    e: Entity,
    shape: &Obstacle,
    pose: &ObstaclePose,
    velocity: &ObstacleVelocity,
) -> Option<InputProblem> {
    let (what, v, rule) = super::obstacles::placed(shape, pose, velocity).problem()?;
    let field = match what {
        "center.x" | "center.y" => "ObstaclePose.center",
        "angle" => "ObstaclePose.angle",
        "velocity.x" | "velocity.y" => "ObstacleVelocity.linear",
        "angular velocity" => "ObstacleVelocity.angular",
        "radius" => "Obstacle: the circle's radius",
        "half.x" | "half.y" => "Obstacle: the box's half-extents",
        "thickness" => "Obstacle: the segment's thickness",
        "length" => "Obstacle: the segment",
        _ => "Obstacle: the segment's ends",
    };
    Some(InputProblem {
        field,
        value: Some(v),
        entity: Some(e),
        rule,
    })
}

/// The problem with the tick plan, if any (the tick planner checks it too, before sizing the
/// fixed timestep from it).
pub fn check_tick_plan(plan: &TickPlan) -> Option<InputProblem> {
    let t = plan.target_tick_seconds;
    (!(t.is_finite() && t > 0.0))
        .then(|| problem("TickPlan.target_tick_seconds", t, "must be finite and > 0"))
}

/// The first problem with the tick plan or the implicit solve's settings, if any.
pub fn check_settings(plan: &TickPlan, cg: &CgSettings) -> Option<InputProblem> {
    if let Some(p) = check_tick_plan(plan) {
        return Some(p);
    }
    if !(cg.tolerance.is_finite() && cg.tolerance >= 0.0) {
        return Some(problem(
            "CgSettings.tolerance",
            cg.tolerance,
            "must be finite and >= 0",
        ));
    }
    None
}

fn check_mass(e: Entity, m: &Mass) -> Option<InputProblem> {
    (!(m.0.is_finite() && m.0 > 0.0)).then_some(InputProblem {
        entity: Some(e),
        ..problem("Mass", m.0, "must be finite and > 0")
    })
}

fn check_spring(
    e: Entity,
    s: &Spring,
    is_particle: impl Fn(Entity) -> bool,
) -> Option<InputProblem> {
    let on = |p: InputProblem| {
        Some(InputProblem {
            entity: Some(e),
            ..p
        })
    };
    if !(s.stiffness.is_finite() && s.stiffness >= 0.0) {
        return on(problem(
            "Spring.stiffness",
            s.stiffness,
            "must be finite and >= 0",
        ));
    }
    if !(s.rest.is_finite() && s.rest >= 0.0) {
        return on(problem("Spring.rest", s.rest, "must be finite and >= 0"));
    }
    if s.a == s.b {
        return on(bad_end("Spring.b", "is the same particle as Spring.a"));
    }
    for (field, end) in [("Spring.a", s.a), ("Spring.b", s.b)] {
        if !is_particle(end) {
            return on(bad_end(field, "is not a particle"));
        }
    }
    None
}

/// An entity's materials, as the input check reads them.
type MaterialsOf = (
    Entity,
    Option<&'static Dashpot>,
    Option<&'static Muscle>,
    Option<&'static Plastic>,
    Option<&'static PressureBody>,
);

/// The first problem with an entity's materials: a dashpot, a muscle, plasticity, a gas.
fn check_materials(
    (e, dashpot, muscle, plastic, body): (
        Entity,
        Option<&Dashpot>,
        Option<&Muscle>,
        Option<&Plastic>,
        Option<&PressureBody>,
    ),
) -> Option<InputProblem> {
    const NON_NEGATIVE: &str = "must be finite and >= 0";
    let bad = |v: f64| !(v.is_finite() && v >= 0.0);
    let found = if let Some(d) = dashpot.filter(|d| bad(d.0)) {
        Some(problem("Dashpot", d.0, NON_NEGATIVE))
    } else if let Some(m) = muscle.filter(|m| !(m.amplitude.is_finite() && m.amplitude.abs() < 1.0))
    {
        Some(problem(
            "Muscle.amplitude",
            m.amplitude,
            "must be finite and between -1 and 1",
        ))
    } else if let Some(m) = muscle.filter(|m| bad(m.frequency)) {
        Some(problem("Muscle.frequency", m.frequency, NON_NEGATIVE))
    } else if let Some(m) = muscle.filter(|m| !m.phase.is_finite()) {
        Some(problem("Muscle.phase", m.phase, "must be finite"))
    } else if let Some(p) = plastic.filter(|p| bad(p.yield_strain)) {
        Some(problem(
            "Plastic.yield_strain",
            p.yield_strain,
            NON_NEGATIVE,
        ))
    } else if let Some(p) = plastic.filter(|p| bad(p.rate)) {
        Some(problem("Plastic.rate", p.rate, NON_NEGATIVE))
    } else if muscle.is_some() && plastic.is_some() {
        Some(bad_end(
            "Plastic",
            "cannot go with a Muscle on one spring: a muscle's rest length follows its actuation",
        ))
    } else {
        body.filter(|b| bad(b.nrt))
            .map(|b| problem("PressureBody.nrt", b.nrt, NON_NEGATIVE))
    };
    found.map(|p| InputProblem {
        entity: Some(e),
        ..p
    })
}

/// The masses, springs and materials added or changed since the last check (a filtered scan:
/// it reads change ticks, not components, for the rest).
#[derive(bevy::ecs::system::SystemParam)]
pub struct ChangedInputs<'w, 's> {
    masses: Query<'w, 's, (Entity, &'static Mass), Changed<Mass>>,
    springs: Query<'w, 's, (Entity, &'static Spring), Changed<Spring>>,
    materials: Query<'w, 's, MaterialsOf, crate::sim::components::MaterialChanged>,
    /// Any entity's materials (the standing problem's, checked again).
    all_materials: Query<'w, 's, MaterialsOf>,
}

/// Run condition: the inputs passed the last check.
pub fn inputs_valid(status: Res<SimStatus>) -> bool {
    !matches!(*status, SimStatus::InvalidInput(_))
}

/// Checks the inputs (see the module docs): the parameters and settings every tick, masses
/// and springs when added or changed. While a problem stands, that one is checked again every
/// tick, so that mending it (or removing its entity) is seen; a spring left dangling by a
/// despawned particle elsewhere is no problem (the solver leaves it out).
#[allow(clippy::too_many_arguments)]
pub fn check_inputs(
    mut params: ResMut<SimParams>,
    mut status: ResMut<SimStatus>,
    plan: Res<TickPlan>,
    cg: Res<CgSettings>,
    masses: Query<(Entity, &Mass)>,
    springs: Query<(Entity, &Spring)>,
    particles: Query<(), With<Particle>>,
    changed: ChangedInputs,
    obstacles: Query<(Entity, &Obstacle, &ObstaclePose, &ObstacleVelocity)>,
) {
    let is_particle = |e: Entity| particles.contains(e);
    let standing = match *status {
        SimStatus::InvalidInput(p) => Some(p),
        _ => None,
    };
    // The standing problem's entity (a particle's mass or a spring), if it still has one.
    let still = standing.and_then(|p| p.entity).and_then(|e| {
        let mass = masses.get(e).ok().and_then(|(e, m)| check_mass(e, m));
        let spring = || {
            let (e, s) = springs.get(e).ok()?;
            check_spring(e, s, is_particle)
        };
        let materials = || check_materials(changed.all_materials.get(e).ok()?);
        mass.or_else(spring).or_else(materials)
    });
    let found = still
        .or_else(|| check_params(&params))
        .or_else(|| check_settings(&plan, &cg))
        .or_else(|| {
            // A handful of entities, whose poses move every tick: all of them, every tick.
            obstacles
                .iter()
                .find_map(|(e, o, pose, vel)| check_obstacle(e, o, pose, vel))
        })
        .or_else(|| changed.masses.iter().find_map(|(e, m)| check_mass(e, m)))
        .or_else(|| {
            changed
                .springs
                .iter()
                .find_map(|(e, s)| check_spring(e, s, is_particle))
        })
        .or_else(|| changed.materials.iter().find_map(check_materials));
    match found {
        Some(p) => {
            if *status != SimStatus::InvalidInput(p) {
                *status = SimStatus::InvalidInput(p);
            }
            if !params.paused {
                params.paused = true;
            }
        }
        None if standing.is_some() => *status = SimStatus::Running,
        None => {}
    }
}
