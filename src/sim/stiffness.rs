//! The springs' stiffness matrix K = −∂f/∂x, applied matrix-free: used by implicit Euler's
//! linear solve and by the ω_max estimate.
//!
//! Spring (a, b) contributes the 2×2 block k [α (I − d̂d̂ᵀ) + d̂d̂ᵀ] = k α I + k (1 − α) d̂d̂ᵀ to
//! the (a, a) and (b, b) positions and its negative to (a, b) and (b, a), with d̂ the unit
//! direction a − b and α = 1 − L/l the transverse coefficient, clamped at 0 for compressed
//! springs so that K stays positive semi-definite. Springs shorter than
//! [`super::kernels::MIN_SPRING_LENGTH`] contribute nothing.

use super::kernels::MIN_SPRING_LENGTH;
use super::solver::PackedSpring;
use bevy::math::DVec2;

/// One spring's block: direction d̂, k α (isotropic part) and k (1 − α) (along d̂).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Block {
    pub dir: DVec2,
    pub k_iso: f64,
    pub k_axial: f64,
}

impl Block {
    pub fn of(spring: &PackedSpring, x: &[DVec2]) -> Block {
        let d = x[spring.a as usize] - x[spring.b as usize];
        let l = d.length();
        if l < MIN_SPRING_LENGTH {
            return Block::default();
        }
        let alpha = (1.0 - spring.rest / l).max(0.0);
        Block {
            dir: d / l,
            k_iso: spring.k * alpha,
            k_axial: spring.k * (1.0 - alpha),
        }
    }

    /// The block times a relative displacement.
    fn times(&self, du: DVec2) -> DVec2 {
        du * self.k_iso + self.dir * (self.k_axial * self.dir.dot(du))
    }

    /// The block's mean diagonal entry, for a scalar Jacobi preconditioner.
    pub fn mean_diagonal(&self) -> f64 {
        self.k_iso + 0.5 * self.k_axial
    }
}

/// The blocks of every spring at positions `x`.
pub fn blocks(springs: &[PackedSpring], x: &[DVec2], out: &mut Vec<Block>) {
    out.clear();
    out.extend(springs.iter().map(|s| Block::of(s, x)));
}

/// out = K u.
pub fn apply(out: &mut [DVec2], u: &[DVec2], springs: &[PackedSpring], blocks: &[Block]) {
    out.fill(DVec2::ZERO);
    for (s, block) in springs.iter().zip(blocks) {
        let (a, b) = (s.a as usize, s.b as usize);
        let f = block.times(u[a] - u[b]);
        out[a] += f;
        out[b] -= f;
    }
}
