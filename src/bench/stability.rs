//! Largest stable dt per hard scene and integrator, found by bisection, against the
//! theoretical limit; and the energy change at half that dt.
//!
//! A trial runs a fixed number of steps with the energy watch on (as the app does); it is
//! *stable* when neither a non-finite value nor the energy watch stopped it. The search starts at
//! 1/16 of the theoretical stable dt (see [`crate::sim::stability`]), doubles dt up to the first
//! unstable trial and bisects that octave 6 times in log space: the result is within 1.1 % of
//! the first edge the trials see. Near its edge an instability grows slowly, so a finite trial
//! can find a run stable a little past the asymptotic limit (explicit Euler most of all).

use crate::scene::{LoadedScene, Scene, presets};
use crate::sim::watch::EnergyWatch;
use crate::sim::{self, Integrator, SimParams, SimStatus, Solver, stability};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Implicit Euler is tried up to this dt; stable there counts as "no limit found".
pub const LARGEST_DT: f64 = 0.1;

#[derive(Debug, Clone, Serialize)]
/// One hard scene under one integrator: the predicted and the measured stable dt.
pub struct Row {
    /// The scene's file stem.
    pub scene: String,
    /// The integrator's CLI name.
    pub integrator: String,
    /// The stable dt the estimate predicts (infinite: unconditional).
    pub theory_dt: f64,
    /// The largest dt found stable (a lower bound when `limit_found` is false).
    pub measured_dt: f64,
    /// Whether bisection found an unstable dt (else `measured_dt` is the largest tried).
    pub limit_found: bool,
    /// Relative energy change over the trial at half the measured dt.
    pub energy_change_at_half: f64,
    /// Steps per trial.
    pub steps_per_trial: u64,
}

struct Trial {
    stable: bool,
    energy_change: f64,
}

fn trial(scene: &Scene, integrator: Integrator, dt: f64, steps: u64) -> Result<Trial, String> {
    let scene = Scene {
        integrator,
        dt,
        ..scene.clone()
    };
    let loaded = LoadedScene::from_scene(scene, None).map_err(|e| e.to_string())?;
    let mut app = crate::running_app(&loaded)?;
    let world = app.world_mut();
    world.insert_resource(EnergyWatch::default());
    let g = world.resource::<SimParams>().gravity;
    let e0 = world.resource::<Solver>().energy(g).total();
    sim::advance(world, steps);
    let e1 = world.resource::<Solver>().energy(g).total();
    Ok(Trial {
        stable: *world.resource::<SimStatus>() == SimStatus::Running,
        energy_change: (e1 - e0) / e0.abs().max(1e-12),
    })
}

fn theory(scene: &Scene, integrator: Integrator) -> Result<f64, String> {
    let loaded = LoadedScene::from_scene(scene.clone(), None).map_err(|e| e.to_string())?;
    let mut app = crate::running_app(&loaded)?;
    let world = app.world_mut();
    let mut params = world.resource::<SimParams>().clone();
    params.integrator = integrator;
    Ok(stability::estimate(world.resource::<Solver>(), &params).stable_dt)
}

/// The hard scenes in `dir` (assets/scenes/hard/: those files, else the built-in copies), by
/// name.
pub fn hard_scenes(dir: &Path) -> Result<Vec<(String, Scene)>, String> {
    let scenes = presets::scenes_in(dir).map_err(|e| e.to_string())?;
    Ok(scenes.into_iter().map(|l| (l.name(), l.scene)).collect())
}

/// Bisects the largest stable dt of every scene in `scenes` under every integrator; `progress` is told what runs.
pub fn run(
    scenes: &[(String, Scene)],
    steps: u64,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Row>, String> {
    let mut rows = vec![];
    for (name, scene) in scenes {
        for integrator in Integrator::ALL {
            progress(&format!("{name}: {integrator}"));
            let theory_dt = theory(scene, integrator)?;
            let start = if theory_dt.is_finite() && theory_dt > 0.0 {
                theory_dt
            } else if theory_dt == 0.0 {
                1e-5
            } else {
                LARGEST_DT
            };
            // Scan up from well below the prediction by factors of 2 to the first unstable dt,
            // then bisect: this finds the *first* edge even where the stable set is not one
            // interval (explicit Euler with damping is stable again at very large dt).
            let mut lo = start / 16.0;
            while !trial(scene, integrator, lo, steps)?.stable && lo > 1e-9 {
                lo /= 4.0;
            }
            let mut hi = None;
            let mut next = lo * 2.0;
            while next <= LARGEST_DT {
                if trial(scene, integrator, next, steps)?.stable {
                    lo = next;
                    next *= 2.0;
                } else {
                    hi = Some(next);
                    break;
                }
            }
            let limit_found = hi.is_some();
            if let Some(mut hi) = hi {
                for _ in 0..6 {
                    let mid = (lo * hi).sqrt();
                    if trial(scene, integrator, mid, steps)?.stable {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
            }
            let half = trial(scene, integrator, lo / 2.0, steps)?;
            rows.push(Row {
                scene: name.clone(),
                integrator: integrator.cli_name().to_string(),
                theory_dt,
                measured_dt: lo,
                limit_found,
                energy_change_at_half: half.energy_change,
                steps_per_trial: steps,
            });
        }
    }
    Ok(rows)
}

/// The rows as CSV, with a header.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,integrator,theory_dt,measured_dt,limit_found,energy_change_at_half,steps_per_trial\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{:.6e},{:.6e},{},{:.6e},{}",
            r.scene,
            r.integrator,
            r.theory_dt,
            r.measured_dt,
            r.limit_found,
            r.energy_change_at_half,
            r.steps_per_trial
        );
    }
    s
}

/// The report as markdown, with the command that made it.
pub fn markdown(rows: &[Row], command: &str) -> String {
    let mut s = String::from("# Stability on the hard cases\n\n");
    let _ = writeln!(
        s,
        "Made by `{command}`. For each scene in `assets/scenes/hard/` and each integrator: the \
         stable dt the estimate predicts (h·ω_max at the limit, ω_max by Lanczos on the initial \
         state; ∞ = unconditionally stable), the largest dt found stable (doubling dt from 1/16 of \
         the prediction to the first unstable trial, then bisecting; a trial runs {} steps with the \
         energy watch on, as the app does; `≥` = stable up to the largest dt tried, {LARGEST_DT} s), \
         their ratio, and the relative energy change over a trial at half the measured dt. Damping \
         makes it negative; ground contact, which lifts a particle that sank below the ground, \
         adds potential energy and can make it positive at large dt. Near an edge an instability \
         grows slowly, so a finite trial may pass a little beyond the asymptotic limit (explicit \
         Euler most of all: its modes grow by well under 1 % a step there).\n",
        rows.first().map_or(0, |r| r.steps_per_trial)
    );
    let _ = writeln!(
        s,
        "| scene | integrator | theory dt (s) | measured dt (s) | measured / theory | ΔE/E at half |"
    );
    let _ = writeln!(s, "| --- | --- | ---: | ---: | ---: | ---: |");
    for r in rows {
        let theory = if r.theory_dt.is_finite() {
            format!("{:.3e}", r.theory_dt)
        } else {
            "∞".into()
        };
        let measured = if r.limit_found {
            format!("{:.3e}", r.measured_dt)
        } else {
            format!("≥ {:.3e}", r.measured_dt)
        };
        let ratio = if r.theory_dt.is_finite() && r.theory_dt > 0.0 {
            format!("{:.2}", r.measured_dt / r.theory_dt)
        } else {
            "–".into()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {theory} | {measured} | {ratio} | {:+.2e} |",
            r.scene, r.integrator, r.energy_change_at_half
        );
    }
    s
}
