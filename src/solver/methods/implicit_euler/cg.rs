//! The linear solve of each Newton step: (M − h² K) dv = b by block-Jacobi-preconditioned
//! conjugate gradients, with some rows filtered out (Baraff and Witkin 1998, §5.3): a pinned
//! particle's two, and the vertical one of a particle the ground holds ([`super::ground`]).
//! A filtered component of dv keeps the value it starts with; the residual and the search
//! directions are zero there, so CG solves the system of the other components.

use crate::solver::forces::material::GasJacobian;
use crate::solver::forces::stiffness::{self, Block, Sym2};
use crate::solver::methods::scratch::Scratch;
use crate::solver::state::State;
use crate::solver::threads::{SpringBuffers, Threads};
use glam::DVec2;

/// Settings of the implicit Euler solve (the Bevy layer's resource is
/// [`crate::sim::CgSettings`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgSettings {
    /// Stop when |r| <= tolerance · |b| (relative residual of the linear system).
    pub tolerance: f64,
    /// Stop after this many iterations whatever the residual.
    pub max_iterations: u32,
}

impl Default for CgSettings {
    fn default() -> Self {
        CgSettings {
            tolerance: 1e-8,
            max_iterations: 500,
        }
    }
}

/// A row filter's value for a particle that moves freely: both components solved.
pub(super) const FREE: DVec2 = DVec2::ONE;
/// For a particle the ground holds: its horizontal component solved, its vertical one kept.
pub(super) const HELD: DVec2 = DVec2::X;
/// For a pinned particle: neither (its Δv stays 0).
pub(super) const PINNED: DVec2 = DVec2::ZERO;

/// The row filter without held particles: every free particle [`FREE`], every pinned one
/// [`PINNED`].
pub(super) fn unfiltered(filter: &mut Vec<DVec2>, inv_mass: &[f64]) {
    filter.clear();
    filter.extend(
        inv_mass
            .iter()
            .map(|&w| if w != 0.0 { FREE } else { PINNED }),
    );
}

/// Solves (M − h² K) dv = b by preconditioned CG, K the blocks in `cg.blocks`, b in `cg.z`
/// (|b|² = `b_norm2`), from the start in `cg.dv` in the rows `cg.filter` lets through (the
/// others keep their values, pinned rows 0), and counts the iterations. The solution is left
/// in `cg.dv`; the caller adds it to the velocities.
pub(super) fn solve(
    s: &State,
    sc: &mut Scratch,
    h2: f64,
    b_norm2: f64,
    settings: CgSettings,
    threads: &Threads,
) {
    let springs = s.springs.len();
    let cg = &mut sc.cg;
    let sum_pairs = |a: (DVec2, DVec2), b: (DVec2, DVec2)| (a.0 + b.0, a.1 + b.1);

    // The preconditioner: the inverse of each particle's 2×2 diagonal block of A = M − h² K
    // (block Jacobi; a particle's springs pull it along their directions, which a scalar
    // diagonal cannot express), of its x entry alone for a particle the ground holds.
    for (d, &m) in cg.diag.iter_mut().zip(&s.mass) {
        *d = Sym2::scaled_identity(m);
    }
    for block in &cg.blocks {
        cg.diag[block.a as usize].add_scaled(block.m, h2);
        cg.diag[block.b as usize].add_scaled(block.m, h2);
    }
    sc.gas.add_diagonal(&mut cg.diag, h2);
    threads.each(
        springs,
        (&mut cg.diag[..], &cg.filter[..]),
        |(diag, filter)| {
            for (d, &f) in diag.iter_mut().zip(filter) {
                *d = if f == FREE {
                    d.inverse_or_zero()
                } else if f == HELD && d.xx.is_normal() {
                    Sym2 {
                        xx: 1.0 / d.xx,
                        ..Sym2::default()
                    }
                } else {
                    Sym2::default()
                };
            }
        },
    );
    // r = b − A dv (warm start), pinned rows held at 0.
    threads.each(springs, (&mut cg.dv[..], &cg.filter[..]), |(dv, filter)| {
        for (dv, &f) in dv.iter_mut().zip(filter) {
            if f == PINNED {
                *dv = DVec2::ZERO;
            }
        }
    });
    let (gas, filter) = (&sc.gas, &cg.filter[..]);
    let a_times = |out: &mut [DVec2], u: &[DVec2], buffers: &mut SpringBuffers, blocks| {
        times_a(threads, (s, gas, blocks), buffers, out, u, filter, h2)
    };
    a_times(&mut cg.ap, &cg.dv, &mut cg.buffers, &cg.blocks);
    let data = (
        &mut cg.r[..],
        &mut cg.z[..],
        &mut cg.p[..],
        &cg.ap[..],
        &cg.diag[..],
        filter,
    );
    let (r2, rz) = threads.chunked(
        springs,
        data,
        |(r, z, p, ap, d, filter)| {
            let (mut r2, mut rz) = (DVec2::ZERO, DVec2::ZERO);
            for i in 0..r.len() {
                r[i] = (z[i] - ap[i]) * filter[i]; // z holds b
                z[i] = d[i].times(r[i]);
                p[i] = z[i];
                r2 += r[i] * r[i];
                rz += r[i] * z[i];
            }
            (r2, rz)
        },
        sum_pairs,
    );
    let tol2 = settings.tolerance * settings.tolerance * b_norm2;
    let (mut r2, mut rz) = (r2.element_sum(), rz.element_sum());
    let mut iterations = 0;
    while r2 > tol2 && iterations < settings.max_iterations {
        let pap = a_times(&mut cg.ap, &cg.p, &mut cg.buffers, &cg.blocks);
        if !pap.is_finite() || pap <= 0.0 {
            break; // not positive definite along p, or non-finite: stop with what we have
        }
        let alpha = rz / pap;
        // Reductions in two lanes (x and y): a scalar sum is one long chain of additions.
        let data = (
            &mut cg.dv[..],
            &mut cg.r[..],
            &mut cg.z[..],
            &cg.p[..],
            &cg.ap[..],
            &cg.diag[..],
        );
        let (r2_lanes, rz_lanes) = threads.chunked(
            springs,
            data,
            |(dv, r, z, p, ap, d)| {
                let (mut r2, mut rz) = (DVec2::ZERO, DVec2::ZERO);
                for i in 0..dv.len() {
                    dv[i] += p[i] * alpha;
                    r[i] -= ap[i] * alpha;
                    z[i] = d[i].times(r[i]);
                    r2 += r[i] * r[i];
                    rz += r[i] * z[i];
                }
                (r2, rz)
            },
            sum_pairs,
        );
        r2 = r2_lanes.element_sum();
        let rz_new = rz_lanes.element_sum();
        let beta = rz_new / rz;
        rz = rz_new;
        threads.each(springs, (&mut cg.p[..], &cg.z[..]), |(p, z)| {
            for (p, z) in p.iter_mut().zip(z) {
                *p = *z + *p * beta;
            }
        });
        iterations += 1;
    }
    cg.iterations += iterations as u64;
    cg.last_iterations = iterations;
    if r2 > tol2 {
        cg.unconverged += 1;
    }
}

/// v += Δv, the solve's result.
pub(super) fn add_to_velocities(s: &mut State, dv: &[DVec2], threads: &Threads) {
    threads.each(s.springs.len(), (&mut s.v[..], dv), |(v, dv)| {
        for (v, dv) in v.iter_mut().zip(dv) {
            *v += *dv;
        }
    });
}

/// out = A u = M u + h² K u, K the springs' blocks and the gas bodies' part, in the rows
/// `filter` lets through (the others 0, so a filtered residual stays filtered); returns
/// u · A u.
pub(super) fn times_a(
    threads: &Threads,
    (s, gas, blocks): (&State, &GasJacobian, &[Block]),
    buffers: &mut SpringBuffers,
    out: &mut [DVec2],
    u: &[DVec2],
    filter: &[DVec2],
    h2: f64,
) -> f64 {
    stiffness::apply_threaded(threads, buffers, out, u, blocks);
    gas.add_product(u, out);
    let dot = threads.chunked(
        s.springs.len(),
        (out, u, &s.mass[..], filter),
        |(ap, u, m, filter)| {
            let mut dot = DVec2::ZERO;
            for i in 0..ap.len() {
                ap[i] = if filter[i] != PINNED {
                    (u[i] * m[i] + ap[i] * h2) * filter[i]
                } else {
                    DVec2::ZERO
                };
                dot += u[i] * ap[i];
            }
            dot
        },
        |a, b| a + b,
    );
    dot.element_sum()
}
