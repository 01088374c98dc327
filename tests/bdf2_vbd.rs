//! BDF2 and vertex block descent against independent references, and XPBD's energy at
//! h·ω = 100 on a cloth, setting by setting.

mod common;

use bevy::math::DVec2;
use common::*;
use hooke::scene::{LoadedScene, Scene};
use hooke::sim::{Integrator, Iterations, SimParams};
use std::path::Path;

/// A `cols × rows` cloth over (0, 0)–(1, 1), mass 1 per particle, shear springs, pinned
/// along its top (`pin: First`), no ground.
fn cloth(integrator: Integrator, dt: f64, cols: usize, k: f64, damping: f64) -> Scene {
    let text = format!(
        "(gravity: (0.0, -9.8), damping: {damping:?}, ground: None, integrator: {},
          dt: {dt:?}, generate: [Grid(cols: {cols}, rows: {cols}, min: (0.0, 0.0),
          max: (1.0, 1.0), mass: 1.0, stiffness: {k:?}, shear: true, pin: First)])",
        ron_name(integrator)
    );
    LoadedScene::parse(&text, Path::new("cloth.ron"))
        .expect("the cloth parses")
        .scene
}

fn ron_name(i: Integrator) -> &'static str {
    match i {
        Integrator::Bdf2 => "Bdf2",
        Integrator::Vbd => "Vbd",
        Integrator::Xpbd => "Xpbd",
        Integrator::ProjectiveDynamics => "ProjectiveDynamics",
        _ => "ImplicitEuler",
    }
}

/// The packed system an independent step reads: masses, pins, springs, gravity.
struct System {
    mass: Vec<f64>,
    free: Vec<bool>,
    springs: Vec<(usize, usize, f64, f64)>,
    gravity: DVec2,
}

impl System {
    fn of(app: &bevy::prelude::App) -> System {
        let s = solver(app);
        System {
            mass: s.mass().to_vec(),
            free: s.inv_mass().iter().map(|&w| w != 0.0).collect(),
            springs: s
                .springs()
                .iter()
                .map(|p| (p.a as usize, p.b as usize, p.rest, p.k))
                .collect(),
            gravity: app.world().resource::<SimParams>().gravity,
        }
    }

    /// The implicit step's end positions by Newton's method on the dense 2n × 2n system:
    /// s M (x − y)/ĥ² − f_springs(x) = 0, y = x̂ + (ĥ/s)(v̂ + ĥ g), s = 1 + ĥμ; pinned
    /// particles held at x̂ (they do not move here). The exact spring Hessian, no projection.
    fn solve(&self, h: f64, mu: f64, xhat: &[DVec2], vhat: &[DVec2]) -> Vec<DVec2> {
        let n = self.mass.len();
        let scale = 1.0 + h * mu;
        let y: Vec<DVec2> = (0..n)
            .map(|i| xhat[i] + (vhat[i] + self.gravity * h) * (h / scale))
            .collect();
        let mut x: Vec<DVec2> = (0..n)
            .map(|i| if self.free[i] { y[i] } else { xhat[i] })
            .collect();
        for _ in 0..50 {
            let dim = 2 * n;
            let mut a = vec![0.0; dim * dim];
            let mut r = vec![0.0; dim];
            for i in 0..n {
                let m = scale * self.mass[i] / (h * h);
                a[(2 * i) * dim + 2 * i] += m;
                a[(2 * i + 1) * dim + 2 * i + 1] += m;
                let g = (x[i] - y[i]) * m;
                r[2 * i] += g.x;
                r[2 * i + 1] += g.y;
            }
            for &(p, q, rest, k) in &self.springs {
                let d = x[p] - x[q];
                let l = d.length();
                let u = d / l;
                let f = u * (k * (l - rest)); // the gradient at p
                let t = k * (1.0 - rest / l);
                let kk = [
                    [t + (k - t) * u.x * u.x, (k - t) * u.x * u.y],
                    [(k - t) * u.x * u.y, t + (k - t) * u.y * u.y],
                ];
                for (e, sign) in [(p, 1.0), (q, -1.0)] {
                    r[2 * e] += sign * f.x;
                    r[2 * e + 1] += sign * f.y;
                }
                for (e1, s1) in [(p, 1.0), (q, -1.0)] {
                    for (e2, s2) in [(p, 1.0), (q, -1.0)] {
                        for c1 in 0..2 {
                            for c2 in 0..2 {
                                a[(2 * e1 + c1) * dim + 2 * e2 + c2] += s1 * s2 * kk[c1][c2];
                            }
                        }
                    }
                }
            }
            // Pinned rows: δ = 0.
            for i in (0..n).filter(|&i| !self.free[i]) {
                for c in 0..2 {
                    let row = 2 * i + c;
                    for j in 0..dim {
                        a[row * dim + j] = 0.0;
                        a[j * dim + row] = 0.0;
                    }
                    a[row * dim + row] = 1.0;
                    r[row] = 0.0;
                }
            }
            let delta = gauss(a, r, dim);
            let mut step: f64 = 0.0;
            for i in 0..n {
                let d = DVec2::new(delta[2 * i], delta[2 * i + 1]);
                x[i] -= d;
                step = step.max(d.length());
            }
            if step < 1e-14 {
                break;
            }
        }
        x
    }
}

/// Solves a x = b (dense, partial pivoting).
fn gauss(mut a: Vec<f64>, mut b: Vec<f64>, n: usize) -> Vec<f64> {
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i * n + c].abs().total_cmp(&a[j * n + c].abs()))
            .unwrap();
        if p != c {
            for j in 0..n {
                a.swap(c * n + j, p * n + j);
            }
            b.swap(c, p);
        }
        for i in c + 1..n {
            let f = a[i * n + c] / a[c * n + c];
            if f != 0.0 {
                for j in c..n {
                    a[i * n + j] -= f * a[c * n + j];
                }
                b[i] -= f * b[c];
            }
        }
    }
    let mut x = vec![0.0; n];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|j| a[c * n + j] * x[j]).sum();
        x[c] = (b[c] - s) / a[c * n + c];
    }
    x
}

/// A cloth started bent and moving, so that its springs are stretched and compressed at once.
fn disturbed(app: &mut bevy::prelude::App) {
    use hooke::sim::{Particle, Position, Velocity};
    let world = app.world_mut();
    let mut q =
        world.query_filtered::<(&mut Position, &mut Velocity), bevy::prelude::With<Particle>>();
    for (mut p, mut v) in q.iter_mut(world) {
        let (x, y) = (p.0.x, p.0.y);
        if y < 0.999 {
            p.0 += DVec2::new(0.05 * (6.0 * y).sin(), -0.03 * x * (1.0 - y));
            v.0 = DVec2::new(0.5 * (3.0 * x).cos(), -0.4 * y);
        }
    }
}

/// BDF2 by local/global iterations, iterated to convergence, is the BDF2 step solved by
/// Newton's method on the dense system, to 1e-8 m, step by step over 10 steps (the first a
/// backward Euler step, the others BDF2 on the history): an 8 × 8 cloth with shear springs,
/// bent and moving, at dt = 1/60 s with the drag μ = 10 inside the solve.
#[test]
fn converged_bdf2_is_newton_bdf2() {
    let (dt, mu) = (1.0 / 60.0, 10.0);
    let mut app = app_with(cloth(Integrator::Bdf2, dt, 8, 1e4, mu));
    disturbed(&mut app);
    set_iterations(
        &mut app,
        Iterations {
            bdf2: 3000,
            ..Default::default()
        },
    );
    hooke::sim::pack(app.world_mut()).unwrap();
    let sys = System::of(&app);
    let (mut x, mut v) = (solver(&app).x().to_vec(), solver(&app).v().to_vec());
    let mut last: Option<(Vec<DVec2>, Vec<DVec2>)> = None;
    for step in 1..=10 {
        let (h, xhat, vhat) = match &last {
            None => (dt, x.clone(), v.clone()),
            Some((xp, vp)) => (
                dt * 2.0 / 3.0,
                x.iter()
                    .zip(xp)
                    .map(|(a, b)| (*a * 4.0 - *b) / 3.0)
                    .collect(),
                v.iter()
                    .zip(vp)
                    .map(|(a, b)| (*a * 4.0 - *b) / 3.0)
                    .collect(),
            ),
        };
        let x1 = sys.solve(h, mu, &xhat, &vhat);
        let v1: Vec<DVec2> = (0..x1.len())
            .map(|i| {
                if sys.free[i] {
                    (x1[i] - xhat[i]) / h
                } else {
                    v[i]
                }
            })
            .collect();
        last = Some((x.clone(), v.clone()));
        (x, v) = (x1, v1);
        common::step(&mut app, 1);
        let dx = max_difference(solver(&app).x(), &x);
        let dv = max_difference(solver(&app).v(), &v);
        assert!(
            dx < 1e-8 && dv * dt < 1e-8,
            "step {step}: |Δx| {dx:e}, |Δv| {dv:e}"
        );
    }
    let stats = solver(&app).solve_stats();
    assert_eq!(stats.bdf2_startup_steps, 1, "one backward Euler step");
    assert_eq!(stats.bdf2_factorizations, 2, "one factor each, kept");
}

/// VBD iterated to convergence is the backward Euler step solved by Newton's method, to 1e-8
/// m, over 10 steps of the same bent, moving 8 × 8 cloth at dt = 1/60 s (the drag μ = 10
/// after the step, as the damping pass applies it), on one thread and on two; and with the
/// drag inside the solve.
#[test]
fn converged_vbd_is_newton_backward_euler() {
    let (dt, mu) = (1.0 / 60.0, 10.0);
    for (threads, inside) in [(1, false), (2, false), (1, true)] {
        let mut app = app_with(cloth(Integrator::Vbd, dt, 8, 1e4, mu));
        app.world_mut().resource_mut::<SimParams>().drag_in_solve = inside;
        app.insert_resource(hooke::sim::SolverThreads::new(threads).unwrap());
        disturbed(&mut app);
        set_iterations(
            &mut app,
            Iterations {
                vbd: 3000,
                ..Default::default()
            },
        );
        hooke::sim::pack(app.world_mut()).unwrap();
        let sys = System::of(&app);
        let (mut x, mut v) = (solver(&app).x().to_vec(), solver(&app).v().to_vec());
        for step in 1..=10 {
            let x1 = sys.solve(dt, if inside { mu } else { 0.0 }, &x, &v);
            let decay = if inside { 1.0 } else { (-mu * dt).exp() };
            v = (0..x1.len())
                .map(|i| {
                    if sys.free[i] {
                        (x1[i] - x[i]) / dt * decay
                    } else {
                        v[i]
                    }
                })
                .collect();
            x = (0..x1.len()).map(|i| x[i] + v[i] * dt).collect();
            common::step(&mut app, 1);
            let dx = max_difference(solver(&app).x(), &x);
            let dv = max_difference(solver(&app).v(), &v);
            assert!(
                dx < 1e-8 && dv * dt < 1e-8,
                "threads {threads}, drag inside {inside}, step {step}: |Δx| {dx:e}, |Δv| {dv:e}"
            );
        }
        assert_eq!(solver(&app).solve_stats().vbd_colourings, 1);
    }
}

/// The 16 × 16 cloth of the issue at h·ω_max = 100: k = 1e4, shear springs, pinned along its
/// top, μ = 0, no ground, dt = 0.356 s (ω_max = 280.8 rad/s), 100 steps. The total energy,
/// measured with the true stiffness, against its start (1,254 J):
/// * BDF2 and VBD at their defaults, and projective dynamics, never exceed it (1e-9 relative
///   for round-off) and end below it;
/// * XPBD swept to a constraint tolerance of 1e-3 does not either;
/// * XPBD at its defaults (10 substeps × 1 sweep) does gain: measured 1,254 → 40,559 J, its
///   unconverged sweeps are not the implicit step they approximate. The test holds it to a
///   gain of more than 10×, so that it says what the default does.
#[test]
fn energy_at_h_omega_100_on_a_cloth() {
    let dt = 0.356;
    let tolerance = Iterations {
        xpbd_tolerance: 1e-3,
        ..Default::default()
    };
    for (integrator, iterations, gains) in [
        (Integrator::Bdf2, Iterations::default(), false),
        (Integrator::Vbd, Iterations::default(), false),
        (Integrator::ProjectiveDynamics, Iterations::default(), false),
        (Integrator::Xpbd, tolerance, false),
        (Integrator::Xpbd, Iterations::default(), true),
    ] {
        let mut app = app_with(cloth(integrator, dt, 16, 1e4, 0.0));
        set_iterations(&mut app, iterations);
        let params = app.world().resource::<SimParams>().clone();
        let e = hooke::sim::stability::estimate(solver(&app), &params);
        assert!((e.h_omega / 100.0 - 1.0).abs() < 0.01, "hω {}", e.h_omega);
        let g = params.gravity;
        let start = solver(&app).energy(g).total();
        let mut highest = start;
        for _ in 0..100 {
            common::step(&mut app, 1);
            assert!(solver(&app).state_is_finite(), "{integrator}");
            highest = highest.max(solver(&app).energy(g).total());
        }
        let end = solver(&app).energy(g).total();
        if gains {
            assert!(
                highest > 10.0 * start,
                "{integrator} {iterations:?}: {start} J rose only to {highest} J"
            );
        } else {
            assert!(
                highest <= start + 1e-9 * start.abs() && end < start,
                "{integrator} {iterations:?}: {start} J rose to {highest} J (ends {end} J)"
            );
        }
    }
}

/// A stiff cloth crushed to 40 % of its rest size (8 × 8, k = 1e6, no pins, no gravity) and
/// released at dt = 1/60 s: VBD's steps stay finite, its energy never rises above the start,
/// and the cloth springs open (from 554,222 J to a few percent of it or less), at 3, 10 and
/// 100 iterations. Every spring starts compressed: without the clamp of their transverse
/// stiffness at 0 (the Hessian made positive semi-definite), the block steps went to NaN.
#[test]
fn vbd_opens_a_crushed_stiff_cloth() {
    let (n, spacing, rest, k) = (8usize, 0.04, 0.1, 1e6);
    for iterations in [3, 10, 100] {
        let mut scene = bare_scene(Integrator::Vbd, 1.0 / 60.0);
        scene.gravity = (0.0, 0.0);
        scene.particles = (0..n * n)
            .map(|r| {
                let (i, j) = ((r / n) as f64, (r % n) as f64);
                particle(0.3 + j * spacing, 0.3 + i * spacing, false)
            })
            .collect();
        for i in 0..n {
            for j in 0..n {
                for (di, dj) in [(0i64, 1i64), (1, 0), (1, 1), (1, -1)] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if (0..n as i64).contains(&a) && (0..n as i64).contains(&b) {
                        let length = rest * ((di * di + dj * dj) as f64).sqrt();
                        scene.springs.push(spring(
                            i * n + j,
                            a as usize * n + b as usize,
                            k,
                            length,
                        ));
                    }
                }
            }
        }
        let mut app = app_with(scene);
        set_iterations(
            &mut app,
            Iterations {
                vbd: iterations,
                ..Default::default()
            },
        );
        let g = app.world().resource::<SimParams>().gravity;
        let start = solver(&app).energy(g).total();
        for step in 1..=120 {
            common::step(&mut app, 1);
            let e = solver(&app).energy(g).total();
            assert!(
                solver(&app).state_is_finite() && e <= start * (1.0 + 1e-9),
                "{iterations} iterations, step {step}: {start} J -> {e} J"
            );
        }
        let end = solver(&app).energy(g).total();
        assert!(
            end < 0.05 * start,
            "{iterations} iterations: {start} J -> {end} J"
        );
    }
}
