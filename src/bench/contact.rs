//! Contact (`hooke bench contact`): the shipped pile of six soft boxes under every method at
//! dt = 1/600, 1/240 and 1/60 s for 6 s, and what each does to it: how deep any particle went
//! into a wall or the ground, how close two particles that no spring joins came, the largest
//! energy above the start, when the pile came to rest, whether a cell turned inside out, and
//! the wall time per simulated second. The measure of "contact at a frame's step", as the
//! work-precision report is of motion.
//!
//! Rest: the kinetic energy under 1e-3 of the energy the drop gave up (the start's less
//! symplectic Euler's at 1e-4 s and 6 s, the reference). Checked at the end of every step; the
//! checks' time is kept out of the wall time.

use crate::scene::{Generator, LoadedScene, Scene, presets};
use crate::sim::{self, Integrator, Obstacles, SimParams, SimStatus, Solver};
use crate::solver::State;
use bevy::prelude::App;
use std::fmt::Write as _;
use std::time::Instant;

/// The steps compared, s.
pub const STEPS: [(f64, &str); 3] = [
    (1.0 / 600.0, "1/600"),
    (1.0 / 240.0, "1/240"),
    (1.0 / 60.0, "1/60"),
];

/// Simulated time of every run, s.
pub const SECONDS: f64 = 6.0;

/// One method at one step.
#[derive(Debug, Clone)]
pub struct Row {
    /// The integrator's command-line name.
    pub method: String,
    /// The step, as written (`1/60`).
    pub dt_label: String,
    /// The step, s.
    pub dt: f64,
    /// Simulated seconds it ran before it stopped (6 unless it blew up).
    pub ran: f64,
    /// The deepest any particle went into a wall or the ground, as a share of the radius.
    pub deepest: f64,
    /// The closest two particles that no spring joins came, as a share of 2r.
    pub closest: f64,
    /// The largest total energy above the start at the end of any step, J (0: none).
    pub energy_gain: f64,
    /// The total energy at the end, J.
    pub energy_end: f64,
    /// When the pile came to rest for good, s (`None`: still moving at the end).
    pub rest_at: Option<f64>,
    /// Cells whose signed area at the end has the other sign than at the start.
    pub cells_turned: usize,
    /// Wall time per simulated second, s.
    pub cost: f64,
}

/// The pile under `integrator` at `dt`, ready to step.
fn pile(scene: &Scene, integrator: Integrator, dt: f64) -> Result<App, String> {
    let mut scene = scene.clone();
    scene.integrator = integrator;
    scene.dt = dt;
    let loaded = LoadedScene::from_scene(scene, None).map_err(|e| e.to_string())?;
    let mut app = crate::headless_app();
    crate::scene::load_into_world(app.world_mut(), &loaded);
    app.world_mut().resource_mut::<SimParams>().paused = false;
    sim::pack(app.world_mut())?;
    Ok(app)
}

/// The cells of the scene's grids, as particle index quadruples (the pile is all grids).
fn cells(scene: &Scene) -> Result<Vec<[usize; 4]>, String> {
    let mut out = vec![];
    let mut base = scene.particles.len();
    for g in &scene.generate {
        let Generator::Grid { cols, rows, .. } = *g else {
            return Err("the contact report's scene must be made of grids".into());
        };
        for r in 0..rows - 1 {
            for c in 0..cols - 1 {
                let p = |c: usize, r: usize| base + r * cols + c;
                out.push([p(c, r), p(c + 1, r), p(c + 1, r + 1), p(c, r + 1)]);
            }
        }
        base += cols * rows;
    }
    Ok(out)
}

fn signed_areas(s: &State, cells: &[[usize; 4]]) -> Vec<f64> {
    let x = s.x();
    cells
        .iter()
        .map(|q| {
            (0..4)
                .map(|k| x[q[k]].perp_dot(x[q[(k + 1) % 4]]))
                .sum::<f64>()
                / 2.0
        })
        .collect()
}

/// What one state shows: the deepest particle (share of r) and the closest unjoined pair
/// (share of 2r).
fn look(app: &App, joined: &std::collections::HashSet<(u32, u32)>) -> (f64, f64) {
    let s = app.world().resource::<Solver>().state();
    let params = app.world().resource::<SimParams>();
    let r = params.contact.map_or(0.0, |c| c.radius).max(1e-12);
    let x = s.x();
    let mut closest = f64::INFINITY;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            if !joined.contains(&(i as u32, j as u32)) {
                closest = closest.min((x[i] - x[j]).length() / (2.0 * r));
            }
        }
    }
    let obstacles = app.world().resource::<Obstacles>();
    let mut deepest: f64 = 0.0;
    for p in x {
        if let Some(g) = params.ground {
            deepest = deepest.max((g + r - p.y) / r);
        }
        for o in obstacles.placed() {
            deepest = deepest.max((r - o.distance(*p).0) / r);
        }
    }
    (deepest, closest)
}

/// One run: the pile under `integrator` at `dt` for [`SECONDS`], `drop` the energy the drop
/// gave up (for the rest test; 0 while measuring the reference).
fn measure(
    scene: &Scene,
    integrator: Integrator,
    dt: f64,
    label: &str,
    drop: f64,
) -> Result<Row, String> {
    let mut app = pile(scene, integrator, dt)?;
    let cells = cells(scene)?;
    let gravity = app.world().resource::<SimParams>().gravity;
    let (start_areas, joined) = {
        let s = app.world().resource::<Solver>().state();
        let joined = s
            .springs()
            .iter()
            .map(|p| (p.a.min(p.b), p.a.max(p.b)))
            .collect();
        (signed_areas(s, &cells), joined)
    };
    let start = app
        .world()
        .resource::<Solver>()
        .state()
        .energy(gravity)
        .total();
    let steps = (SECONDS / dt).round() as u64;
    let (mut deepest, mut closest, mut peak) = (0.0f64, f64::INFINITY, start);
    let mut rest_at = Some(0.0);
    let mut cost = 0.0;
    let mut taken = 0;
    for k in 1..=steps {
        let clock = Instant::now();
        let n = sim::advance(app.world_mut(), 1);
        cost += clock.elapsed().as_secs_f64();
        if n < 1 || *app.world().resource::<SimStatus>() != SimStatus::Running {
            break;
        }
        taken = k;
        let (d, c) = look(&app, &joined);
        deepest = deepest.max(d);
        closest = closest.min(c);
        let e = app.world().resource::<Solver>().state().energy(gravity);
        peak = peak.max(e.total());
        if e.kinetic >= 1e-3 * drop {
            rest_at = None;
        } else if rest_at.is_none() {
            rest_at = Some(k as f64 * dt);
        }
    }
    let s = app.world().resource::<Solver>().state();
    let ran = taken as f64 * dt;
    let end_areas = signed_areas(s, &cells);
    let cells_turned = start_areas
        .iter()
        .zip(&end_areas)
        .filter(|(a, b)| a.signum() != b.signum())
        .count();
    Ok(Row {
        method: integrator.cli_name().to_string(),
        dt_label: label.to_string(),
        dt,
        ran,
        deepest,
        closest,
        energy_gain: (peak - start).max(0.0),
        energy_end: s.energy(gravity).total(),
        rest_at: if taken == steps { rest_at } else { None },
        cells_turned,
        cost: cost / ran.max(dt),
    })
}

/// The report: the reference run's end energy and drop, and a row per method and step.
pub struct Report {
    /// The start energy, J.
    pub start: f64,
    /// The energy the drop gave up under symplectic Euler at 1e-4 s, J.
    pub drop: f64,
    /// The reference run's row.
    pub reference: Row,
    /// Every method at every step.
    pub rows: Vec<Row>,
}

/// Runs every method at every step on the shipped pile.
pub fn run(mut progress: impl FnMut(&str)) -> Result<Report, String> {
    let scene = presets::resolve("pile").map_err(|e| e.to_string())?.scene;
    progress("the reference: symplectic-euler at 1e-4 s");
    let reference = measure(&scene, Integrator::SymplecticEuler, 1e-4, "1e-4", 0.0)?;
    let start = {
        let app = pile(&scene, Integrator::SymplecticEuler, 1e-4)?;
        let g = app.world().resource::<SimParams>().gravity;
        app.world().resource::<Solver>().state().energy(g).total()
    };
    let drop = start - reference.energy_end;
    let mut rows = vec![];
    for integrator in Integrator::ALL {
        for (dt, label) in STEPS {
            progress(&format!("{} at {label} s", integrator.cli_name()));
            rows.push(measure(&scene, integrator, dt, label, drop)?);
        }
    }
    Ok(Report {
        start,
        drop,
        reference,
        rows,
    })
}

fn cells_of(r: &Row) -> String {
    format!("{}", r.cells_turned)
}

/// The overlap the plot draws: how far the closest unjoined pair came inside 2r, as a share
/// of it (1e-4 for a pile that kept every pair apart: the log axis needs a floor).
pub const OVERLAP_FLOOR: f64 = 1e-4;

/// The rows as the work-precision diagram draws them: the overlap 1 − closest against the
/// cost per simulated second, a line per method through its three steps, the runs that blew
/// up as crosses.
pub fn diagram_rows(report: &Report) -> Vec<super::work_precision::Row> {
    report
        .rows
        .iter()
        .map(|r| super::work_precision::Row {
            scene: "pile".into(),
            integrator: r.method.clone(),
            dt: r.dt,
            steps: (r.ran / r.dt).round() as u64,
            wall_s: r.cost,
            error: (1.0 - r.closest).max(OVERLAP_FLOOR),
            stable: r.ran >= SECONDS - r.dt && r.energy_gain < report.start,
            cg_iterations_per_step: 0.0,
        })
        .collect()
}

fn rest_of(r: &Row) -> String {
    r.rest_at.map_or("no".into(), |t| format!("{t:.2} s"))
}

/// The reference row's rest column: its own end defines rest, so it has none.
const REFERENCE_REST: &str = "(the reference)";

/// The rows as CSV, with a header.
pub fn csv(report: &Report) -> String {
    let mut out = String::from(
        "method,dt,ran_s,deepest_of_r,closest_of_2r,energy_gain_j,energy_end_j,rest_at_s,cells_turned,wall_s_per_sim_s\n",
    );
    for r in std::iter::once(&report.reference).chain(&report.rows) {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{}",
            r.method,
            r.dt,
            r.ran,
            r.deepest,
            r.closest,
            r.energy_gain,
            r.energy_end,
            r.rest_at.map_or(String::new(), |t| t.to_string()),
            r.cells_turned,
            r.cost
        );
    }
    out
}

/// The report as markdown: how it was made, and the table.
pub fn markdown(report: &Report, machine: &str, command: &str) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Contact: the pile at three steps\n");
    let _ = writeln!(
        md,
        "Measured on {machine} with `{command}`. The shipped `pile` (six soft boxes, 5 × 5 grids \
         with shear springs, r = 8 mm, μ = 0.5, particle pairs on) for {SECONDS} s under every \
         method at its default iterations. Start energy {:.1} J; symplectic Euler at 1e-4 s ends at \
         {:.1} J, so the drop gave up {:.1} J, and rest is a kinetic energy under {:.3} J for good.\n",
        report.start,
        report.reference.energy_end,
        report.drop,
        1e-3 * report.drop
    );
    let _ = writeln!(
        md,
        "Deepest: how far any particle went into a wall or the ground, as a share of r. Closest: \
         the closest two particles that no spring joins came, as a share of 2r. Gain: the largest \
         total energy above the start at the end of any step. Cells: of the 96 cells, those turned \
         inside out at the end. Cost: wall time per simulated second (the checks' time left out). \
         \"blew up at t\": the method stopped (non-finite, or the energy watch).\n"
    );
    let _ = writeln!(md, "![contact](contact.png)\n");
    let _ = writeln!(
        md,
        "| method | dt | deepest (r) | closest (2r) | gain (J) | end (J) | at rest from | cells | cost (s/s) |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (i, r) in std::iter::once(&report.reference)
        .chain(&report.rows)
        .enumerate()
    {
        if r.ran < SECONDS - r.dt {
            let _ = writeln!(
                md,
                "| {} | {} | blew up at {:.2} s | | | | | | |",
                r.method, r.dt_label, r.ran
            );
            continue;
        }
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} | {:.1} | {:.1} | {} | {} | {:.3} |",
            r.method,
            r.dt_label,
            r.deepest,
            r.closest,
            r.energy_gain,
            r.energy_end,
            if i == 0 {
                REFERENCE_REST.to_string()
            } else {
                rest_of(r)
            },
            cells_of(r),
            r.cost
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pile's six 5×5 grids give 96 cells, each a quadrilateral of one grid's particles,
    /// and at the start every cell has the same orientation.
    #[test]
    fn the_piles_cells_are_its_grids_quads() {
        let scene = presets::resolve("pile").unwrap().scene;
        let cells = cells(&scene).unwrap();
        assert_eq!(cells.len(), 96);
        assert!(cells.iter().all(|q| q.iter().all(|&i| i / 25 == q[0] / 25)));
        let app = pile(&scene, Integrator::Xpbd, 1.0 / 60.0).unwrap();
        let areas = signed_areas(app.world().resource::<Solver>().state(), &cells);
        assert!(
            areas
                .iter()
                .all(|a| a.signum() == areas[0].signum() && a.abs() > 1e-5)
        );
    }
}
