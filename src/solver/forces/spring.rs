//! One spring's force, its energy and its projective dynamics projection, and the scatter's
//! running sum: what the scalar and the AVX spring passes
//! ([`super::kernels::for_each_spring_force`], [`super::wide`]), the stiffness product
//! ([`super::stiffness`]) and projective dynamics' local step share.

use crate::solver::packed::PackedSpring;
use glam::DVec2;

/// Springs shorter than this exert no force: their direction is undefined.
pub const MIN_SPRING_LENGTH: f64 = 1e-12;

/// The force on a spring's end a, -k (l - L) d / l with d = x_a - x_b and l = |d| (end b gets
/// its negative); `None` for a spring of (near) zero length, whose direction is undefined.
/// A non-finite length still yields a (non-finite) force, so that a blow-up is seen.
#[inline]
pub fn spring_force(s: &PackedSpring, x: &[DVec2]) -> Option<DVec2> {
    let d = x[s.a as usize] - x[s.b as usize];
    let l = d.length();
    if l < MIN_SPRING_LENGTH {
        return None;
    }
    Some(d * (-s.k * (l - s.rest) / l))
}

/// ½k(|x_a − x_b| − L)².
#[inline(always)]
pub(crate) fn one_spring_energy(s: &PackedSpring, x: &[DVec2]) -> f64 {
    let stretch = (x[s.a as usize] - x[s.b as usize]).length() - s.rest;
    0.5 * s.k * stretch * stretch
}

/// [`super::kernels::spring_energy`]'s eight running sums and the springs past the last
/// eight, added in one order for both of its forms.
#[inline(always)]
pub(crate) fn energy_total(sums: [f64; 8], tail: &[PackedSpring], x: &[DVec2]) -> f64 {
    let s: [f64; 4] = std::array::from_fn(|i| sums[i] + sums[i + 4]);
    let tail: f64 = tail.iter().map(|s| one_spring_energy(s, x)).sum();
    ((s[0] + s[1]) + (s[2] + s[3])) + tail
}

/// The force on end a of a spring with a dashpot `c` (N·s/m) along it: the spring's force
/// ([`spring_force`]) and −c ((v_a − v_b)·n) n, n = d/l, from one length and one direction.
#[inline]
pub fn damped_spring_force(s: &PackedSpring, c: f64, x: &[DVec2], v: &[DVec2]) -> Option<DVec2> {
    let (a, b) = (s.a as usize, s.b as usize);
    let d = x[a] - x[b];
    let l = d.length();
    if l < MIN_SPRING_LENGTH {
        return None;
    }
    let n = d / l;
    Some(n * (-s.k * (l - s.rest) - c * (v[a] - v[b]).dot(n)))
}

/// One spring's share of projective dynamics' residual at its end a: h²k (d − l) with
/// l = x_a − x_b and d = l (L / |l|) its local step's projection, computed as
/// l · (L / |l| − 1) · h²k; 0 where |l| is 0 or not a number (the ends coincide: no direction
/// to project on, d = l).
#[inline]
pub fn projection_residual(s: &PackedSpring, x: &[DVec2], h2: f64) -> DVec2 {
    let l = x[s.a as usize] - x[s.b as usize];
    let len = l.length();
    let q = if len > 0.0 { s.rest / len } else { 1.0 };
    l * (q - 1.0) * (h2 * s.k)
}

/// For each spring, `add(a, g)` and `add(b, -g)` with `g = force(spring)` (nothing for `None`),
/// one spring at a time: the scalar spring pass.
#[inline(always)]
pub fn scatter_pairs(
    springs: &[PackedSpring],
    mut force: impl FnMut(&PackedSpring) -> Option<DVec2>,
    mut add: impl FnMut(usize, DVec2),
) {
    let mut run = Run::new(springs.first().map(|s| s.a));
    for s in springs {
        run.push((s.a, s.b), force(s), &mut add);
    }
    run.finish(add);
}

/// The scatter's running sum on a pair's end a (spring forces, and K times a vector in
/// [`super::stiffness::apply`]).
///
/// Consecutive springs that share their end a (the packed springs are sorted by it, see
/// the Bevy layer's sync) sum their contributions to a in a register and hand them over once. Adding
/// each to memory, spring after spring, makes every update wait for the previous one's store.
pub struct Run {
    a: usize,
    on_a: DVec2,
}

impl Run {
    #[inline(always)]
    pub fn new(first_a: Option<u32>) -> Run {
        Run {
            a: first_a.map_or(0, |a| a as usize),
            on_a: DVec2::ZERO,
        }
    }

    /// Scatters a pair's contribution `g` on a (and −g on b).
    #[inline(always)]
    pub fn push(
        &mut self,
        (a, b): (u32, u32),
        g: Option<DVec2>,
        add: &mut impl FnMut(usize, DVec2),
    ) {
        if a as usize != self.a {
            add(self.a, self.on_a);
            (self.a, self.on_a) = (a as usize, DVec2::ZERO);
        }
        if let Some(g) = g {
            self.on_a += g;
            add(b as usize, -g);
        }
    }

    #[inline(always)]
    pub fn finish(self, mut add: impl FnMut(usize, DVec2)) {
        if self.on_a != DVec2::ZERO {
            add(self.a, self.on_a);
        }
    }
}
