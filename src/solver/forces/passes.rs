//! The spring force pass on the pool's threads: f = body forces + Σ spring forces (with their
//! dashpots where the scene has them), one parallel region a step, through the pair scatter
//! ([`scatter_from`]).

use super::kernels;
use super::spring::{damped_spring_force, scatter_pairs};
use crate::solver::packed::PackedSpring;
#[cfg(test)]
use crate::solver::threads::scatter::scatter;
use crate::solver::threads::{PairPass, SpringBuffers, Threads, scatter_from};
use glam::DVec2;

/// The spring forces at positions `x`.
struct SpringForces<'x>(&'x [DVec2]);

impl PairPass for SpringForces<'_> {
    type Pair = PackedSpring;
    #[inline(always)]
    fn run(&self, springs: &[PackedSpring], add: impl FnMut(usize, DVec2)) {
        kernels::for_each_spring_force(self.0, springs, add);
    }
}

/// The spring forces at positions `x` with each spring's dashpot (`dashpot[i]` for spring i of
/// `springs`, the whole packed list) at velocities `v`: one pass, one length and direction a
/// spring, where a separate dashpot pass would gather and scatter again (and serially).
struct DampedSpringForces<'x> {
    x: &'x [DVec2],
    v: &'x [DVec2],
    springs: &'x [PackedSpring],
    dashpot: &'x [f64],
}

impl PairPass for DampedSpringForces<'_> {
    type Pair = PackedSpring;
    #[inline(always)]
    fn run(&self, springs: &[PackedSpring], add: impl FnMut(usize, DVec2)) {
        // `springs` is a run of `self.springs` (the scatter hands out parts of the list it was
        // given): its first spring's index there.
        let first = (springs.as_ptr() as usize - self.springs.as_ptr() as usize)
            / std::mem::size_of::<PackedSpring>();
        let dashpot = &self.dashpot[first..first + springs.len()];
        let mut i = 0;
        scatter_pairs(
            springs,
            |s| {
                let c = dashpot[i];
                i += 1;
                damped_spring_force(s, c, self.x, self.v)
            },
            add,
        );
    }
}

/// f = init + Σ spring forces with their dashpots (see [`spring_forces_from`]): `dashpot`
/// holds each spring's c, in the packed order.
pub fn damped_spring_forces_from(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    f: &mut [DVec2],
    (x, v): (&[DVec2], &[DVec2]),
    (springs, dashpot): (&[PackedSpring], &[f64]),
    init: &(impl Fn(usize, &mut [DVec2]) + Sync),
) {
    let pass = DampedSpringForces {
        x,
        v,
        springs,
        dashpot,
    };
    scatter_from(threads, buffers, f, springs, &pass, init);
}

/// f += Σ spring forces, each spring evaluated once, on the pool's threads when worthwhile
/// (the tests' reference for [`spring_forces_from`]).
#[cfg(test)]
pub fn accumulate_spring_forces(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    f: &mut [DVec2],
    x: &[DVec2],
    springs: &[PackedSpring],
) {
    scatter(threads, buffers, f, springs, &SpringForces(x));
}

/// f = init + Σ spring forces: `init(start, slice)` writes each particle's starting value (the
/// body forces) into `slice`, the particles from `start` on. On threads each part starts its
/// own particles inside the same parallel region as its springs, so the forces take one
/// region a step, not two.
pub fn spring_forces_from(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    f: &mut [DVec2],
    x: &[DVec2],
    springs: &[PackedSpring],
    init: &(impl Fn(usize, &mut [DVec2]) + Sync),
) {
    scatter_from(threads, buffers, f, springs, &SpringForces(x), init);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::{assert_round_off, bits, grid, positions, tangle};

    /// Inside a held run ([`Threads::run`]) the passes fork to the crew; outside it, through
    /// rayon. Both cut the work the same way and combine it in the same order, so a sum
    /// reduction, the spring forces and a join give the same bits, for 2 and 3 threads.
    #[test]
    fn held_passes_give_the_rayon_passes_bits() {
        let (w, h) = (90, 70);
        let springs = grid(w, h);
        let x = positions(w * h);
        let n = x.len();
        let src: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin()).collect();
        for t in [2, 3] {
            let threads = Threads::new(t).unwrap();
            let passes = || {
                let sum = threads.chunked(
                    springs.len(),
                    &src[..],
                    |s| s.iter().sum::<f64>(),
                    |a, b| a + b,
                );
                let mut f = vec![DVec2::ZERO; n];
                let mut buffers = SpringBuffers::default();
                let init = |start: usize, f: &mut [DVec2]| {
                    f.iter_mut()
                        .enumerate()
                        .for_each(|(i, f)| *f = DVec2::new(0.0, -9.8 * (start + i) as f64))
                };
                spring_forces_from(&threads, &mut buffers, &mut f, &x, &springs, &init);
                let (a, b) = threads.join(true, || src[..n].iter().sum::<f64>(), || src[n].sqrt());
                (sum.to_bits(), f, a.to_bits(), b.to_bits())
            };
            let outside = passes();
            let held = threads.run(springs.len(), || {
                assert!(threads.holds_crew(), "the run holds the pool");
                passes()
            });
            assert_eq!(held.0, outside.0, "{t} threads: the sum");
            assert!(bits(&held.1) == bits(&outside.1), "{t} threads: the forces");
            assert_eq!(
                (held.2, held.3),
                (outside.2, outside.3),
                "{t} threads: the join"
            );
        }
    }

    /// Forces started from body forces inside the region equal the body forces plus the
    /// threaded accumulation, bit for bit: every particle is started once, in or between the
    /// parts.
    #[test]
    fn forces_started_in_the_region_equal_body_forces_plus_springs() {
        for (n, springs) in [(160 * 160, grid(160, 160)), (5000, tangle(5000, 30_000))] {
            let x = positions(n);
            let body = |i: usize| DVec2::new(i as f64 * 1e-3, -9.8);
            for count in [1, 2, 3] {
                let threads = Threads::new(count).unwrap();
                let (mut b1, mut b2) = (SpringBuffers::default(), SpringBuffers::default());
                let mut apart: Vec<DVec2> = (0..n as usize).map(body).collect();
                accumulate_spring_forces(&threads, &mut b1, &mut apart, &x, &springs);
                let mut together = vec![DVec2::splat(f64::NAN); n as usize];
                let init = |start: usize, f: &mut [DVec2]| {
                    for (k, f) in f.iter_mut().enumerate() {
                        *f = body(start + k);
                    }
                };
                spring_forces_from(&threads, &mut b2, &mut together, &x, &springs, &init);
                assert!(bits(&apart) == bits(&together), "{count} threads");
            }
        }
    }

    /// The threaded pass gives the serial forces up to the order of summation.
    #[test]
    fn threaded_forces_match_the_serial_ones() {
        for (n, springs) in [(160 * 160, grid(160, 160)), (5000, tangle(5000, 30_000))] {
            let x = positions(n);
            let mut serial = vec![DVec2::ZERO; n as usize];
            kernels::for_each_spring_force(&x, &springs, |i, v| serial[i] += v);
            for count in [2, 3] {
                let threads = Threads::new(count).unwrap();
                let mut buffers = SpringBuffers::default();
                let mut threaded = vec![DVec2::ZERO; n as usize];
                accumulate_spring_forces(&threads, &mut buffers, &mut threaded, &x, &springs);
                assert_round_off(&serial, &threaded, &format!("forces, {count} threads"));
            }
        }
    }
}
