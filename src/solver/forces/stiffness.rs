//! The springs' stiffness matrix K = −∂f/∂x, applied matrix-free: used by implicit Euler's
//! linear solve and by the ω_max estimate.
//!
//! Spring (a, b) contributes the 2×2 block k [α (I − d̂d̂ᵀ) + d̂d̂ᵀ] = k α I + k (1 − α) d̂d̂ᵀ to
//! the (a, a) and (b, b) positions and its negative to (a, b) and (b, a), with d̂ the unit
//! direction a − b and α = 1 − L/l the transverse coefficient, clamped at 0 for compressed
//! springs so that K stays positive semi-definite. Springs shorter than
//! [`super::spring::MIN_SPRING_LENGTH`] contribute nothing.

use super::spring::{self, MIN_SPRING_LENGTH};
use crate::solver::packed::PackedSpring;
use crate::solver::threads::{Pair, PairPass, SpringBuffers, Threads, scatter_from};
use glam::DVec2;

/// One spring's block k α I + k (1 − α) d̂d̂ᵀ, with the spring's ends: all that applying K
/// reads (32 bytes a spring, so that a 64×64 cloth's blocks stay in a core's L2 cache).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Block {
    pub a: u32,
    pub b: u32,
    pub m: Sym2,
}

impl Block {
    pub fn of(spring: &PackedSpring, x: &[DVec2]) -> Block {
        let (a, b) = (spring.a, spring.b);
        let d = x[a as usize] - x[b as usize];
        let l = d.length();
        if l < MIN_SPRING_LENGTH {
            return Block {
                a,
                b,
                m: Sym2::default(),
            };
        }
        let alpha = (1.0 - spring.rest / l).max(0.0);
        let (dir, k_iso, k_axial) = (d / l, spring.k * alpha, spring.k * (1.0 - alpha));
        let m = Sym2 {
            xx: k_iso + k_axial * dir.x * dir.x,
            xy: k_axial * dir.x * dir.y,
            yy: k_iso + k_axial * dir.y * dir.y,
        };
        Block { a, b, m }
    }
}

/// A symmetric 2×2 matrix.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sym2 {
    pub xx: f64,
    pub xy: f64,
    pub yy: f64,
}

impl Sym2 {
    pub fn scaled_identity(s: f64) -> Sym2 {
        Sym2 {
            xx: s,
            xy: 0.0,
            yy: s,
        }
    }

    pub fn add_scaled(&mut self, other: Sym2, s: f64) {
        self.xx += s * other.xx;
        self.xy += s * other.xy;
        self.yy += s * other.yy;
    }

    /// The inverse, or zero when there is none (a singular or non-finite block: only a
    /// blown-up state makes one, since a free particle's block is its mass plus a positive
    /// semi-definite part; pinned rows are zeroed by the caller).
    pub fn inverse_or_zero(&self) -> Sym2 {
        let det = self.xx * self.yy - self.xy * self.xy;
        if det.is_normal() {
            Sym2 {
                xx: self.yy / det,
                xy: -self.xy / det,
                yy: self.xx / det,
            }
        } else {
            Sym2::default()
        }
    }

    pub fn times(&self, u: DVec2) -> DVec2 {
        DVec2::new(self.xx * u.x + self.xy * u.y, self.xy * u.x + self.yy * u.y)
    }
}

/// The blocks of every spring at positions `x`.
pub fn blocks(springs: &[PackedSpring], x: &[DVec2], out: &mut Vec<Block>) {
    out.clear();
    out.extend(springs.iter().map(|s| Block::of(s, x)));
}

/// [`blocks`] on the pool's threads when worthwhile.
pub fn blocks_threaded(
    threads: &Threads,
    springs: &[PackedSpring],
    x: &[DVec2],
    out: &mut Vec<Block>,
) {
    out.resize(springs.len(), Block::default());
    threads.each(springs.len(), (&mut out[..], springs), |(out, springs)| {
        for (o, s) in out.iter_mut().zip(springs) {
            *o = Block::of(s, x);
        }
    });
}

impl Pair for Block {
    fn ends(&self) -> (usize, usize) {
        (self.a as usize, self.b as usize)
    }
}

/// K u, block by block: each block adds m (u_a − u_b) to a and its negative to b.
struct KTimes<'u>(&'u [DVec2]);

impl PairPass for KTimes<'_> {
    type Pair = Block;
    #[inline(always)]
    fn run(&self, blocks: &[Block], mut add: impl FnMut(usize, DVec2)) {
        let u = self.0;
        let mut run = spring::Run::new(blocks.first().map(|b| b.a));
        for block in blocks {
            let g = block.m.times(u[block.a as usize] - u[block.b as usize]);
            run.push((block.a, block.b), Some(g), &mut add);
        }
        run.finish(add);
    }
}

/// out = K u.
pub fn apply(out: &mut [DVec2], u: &[DVec2], blocks: &[Block]) {
    out.fill(DVec2::ZERO);
    KTimes(u).run(blocks, |i, g| out[i] += g);
}

/// out = K u on the pool's threads when worthwhile (see [`scatter_from`]); `buffers`
/// caches the split of these blocks.
pub fn apply_threaded(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    out: &mut [DVec2],
    u: &[DVec2],
    blocks: &[Block],
) {
    let zero = |_: usize, out: &mut [DVec2]| out.fill(DVec2::ZERO);
    scatter_from(threads, buffers, out, blocks, &KTimes(u), &zero);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::{assert_round_off, grid, positions};

    /// K u through the threaded pair scatter gives the serial product up to round-off.
    #[test]
    fn threaded_stiffness_product_matches_the_serial_one() {
        let (n, springs) = (160 * 160, grid(160, 160));
        let x = positions(n);
        let mut blocks = vec![];
        super::blocks(&springs, &x, &mut blocks);
        let u: Vec<DVec2> = (0..n)
            .map(|i| DVec2::new((i % 13) as f64, -((i % 7) as f64)))
            .collect();
        let mut serial = vec![DVec2::ZERO; n as usize];
        super::apply(&mut serial, &u, &blocks);
        let threads = Threads::new(2).unwrap();
        let (mut buffers, mut threaded_blocks) = (SpringBuffers::default(), vec![]);
        super::blocks_threaded(&threads, &springs, &x, &mut threaded_blocks);
        assert_eq!(threaded_blocks, blocks);
        let mut threaded = vec![DVec2::splat(f64::NAN); n as usize]; // overwritten, not added to
        super::apply_threaded(&threads, &mut buffers, &mut threaded, &u, &blocks);
        assert_round_off(&serial, &threaded, "K u, 2 threads");
    }
}
