//! The true static shape of a scene: the minimiser of its potential energy
//! U(x) = −Σ m g·x − Σ f_ext·x + Σ ½ k (|x_a − x_b| − L)², found directly (not by stepping):
//! Newton's method, each Newton system H δ = −∇U solved by conjugate gradients with H the
//! spring stiffness (compressed springs' transverse term dropped, so H stays positive
//! semi-definite) and a backtracking line search on U. Pinned particles stay where they are.

use crate::sim::{PackedSpring, Solver};
use crate::solver::forces::kernels;
use crate::solver::forces::stiffness::{self, Block};
use bevy::math::DVec2;

/// The forces −∇U at x: body forces plus springs, zero on fixed particles.
fn forces(s: &Solver, x: &[DVec2], gravity: DVec2, out: &mut [DVec2]) {
    for (i, o) in out.iter_mut().enumerate().take(x.len()) {
        *o = if s.inv_mass()[i] != 0.0 {
            gravity * s.mass()[i] + s.external_force(i)
        } else {
            DVec2::ZERO
        };
    }
    kernels::for_each_spring_force(x, s.springs(), |i, f| {
        if s.inv_mass()[i] != 0.0 {
            out[i] += f
        }
    });
}

fn potential(s: &Solver, x: &[DVec2], gravity: DVec2) -> f64 {
    let mut u = 0.0;
    for (i, p) in x.iter().enumerate() {
        u -= (gravity * s.mass()[i] + s.external_force(i)).dot(*p);
    }
    for sp in s.springs() {
        let PackedSpring { a, b, rest, k } = *sp;
        let stretch = (x[a as usize] - x[b as usize]).length() - rest;
        u += 0.5 * k * stretch * stretch;
    }
    u
}

/// The equilibrium nearest `start` (the scene's particles, springs and pins as packed in `s`),
/// and the largest remaining force on a free particle, N.
pub fn equilibrium(s: &Solver, start: &[DVec2], gravity: DVec2) -> (Vec<DVec2>, f64) {
    let n = start.len();
    let mut x = start.to_vec();
    let (mut f, mut trial) = (vec![DVec2::ZERO; n], vec![DVec2::ZERO; n]);
    let weight = (0..n)
        .map(|i| (gravity * s.mass()[i]).length())
        .fold(0.0, f64::max)
        .max(1e-300);
    let free = |i: usize| s.inv_mass()[i] != 0.0;
    let mut blocks: Vec<Block> = vec![];
    let (mut d, mut r, mut p, mut hp) = (
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
        vec![DVec2::ZERO; n],
    );
    let mut residual = f64::INFINITY;
    for _ in 0..200 {
        forces(s, &x, gravity, &mut f);
        residual = f.iter().map(|v| v.length()).fold(0.0, f64::max);
        if residual < 1e-12 * weight {
            break;
        }
        // H d = f by CG (H = K, tiny Tikhonov term for the zero modes of a slack spring).
        stiffness::blocks(s.springs(), &x, &mut blocks);
        let scale = s.springs().iter().map(|sp| sp.k).fold(0.0, f64::max) * 1e-12;
        let apply = |u: &[DVec2], out: &mut [DVec2]| {
            out.iter_mut().for_each(|o| *o = DVec2::ZERO);
            stiffness::apply(out, u, &blocks);
            for i in 0..n {
                out[i] = if free(i) {
                    out[i] + u[i] * scale
                } else {
                    DVec2::ZERO
                };
            }
        };
        d.iter_mut().for_each(|v| *v = DVec2::ZERO);
        r.copy_from_slice(&f);
        p.copy_from_slice(&f);
        let dot = |a: &[DVec2], b: &[DVec2]| a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum::<f64>();
        let (b2, mut r2) = (dot(&f, &f), dot(&f, &f));
        for _ in 0..20 * n.max(10) {
            if r2 <= 1e-24 * b2 {
                break;
            }
            apply(&p, &mut hp);
            let php = dot(&p, &hp);
            if php.is_nan() || php <= 0.0 {
                break;
            }
            let alpha = r2 / php;
            for i in 0..n {
                d[i] += p[i] * alpha;
                r[i] -= hp[i] * alpha;
            }
            let r2_new = dot(&r, &r);
            let beta = r2_new / r2;
            r2 = r2_new;
            for i in 0..n {
                p[i] = r[i] + p[i] * beta;
            }
        }
        // Backtracking on U along d (a descent direction: f·d > 0).
        let u0 = potential(s, &x, gravity);
        let slope = dot(&f, &d);
        let mut step = 1.0;
        loop {
            for i in 0..n {
                trial[i] = x[i] + d[i] * step;
            }
            if potential(s, &trial, gravity) <= u0 - 1e-4 * step * slope || step < 1e-8 {
                break;
            }
            step *= 0.5;
        }
        x.copy_from_slice(&trial);
    }
    (x, residual)
}
