//! The spring force pass four springs at a time, and the particle sweep two particles at a
//! time, with AVX.
//!
//! Per spring the pass needs a square root and a division, and their latency, not memory, is
//! what bounds the scalar loop (measured with `perf annotate`: the loop waits on `divsd`). One
//! `vsqrtpd` and one `vdivpd` serve four springs, and two such quads are in flight at once.
//! The operations are the scalar kernel's, in the same order ([`super::spring::spring_force`]:
//! d = x_a − x_b, l = √(d·d), d · (−k (l − L) / l)), and IEEE square root and division are
//! correctly rounded, so the forces are bit for bit the scalar ones. The gather of positions and the scatter of forces stay scalar.
//! On big scenes the pass prefetches what it will read a few hundred springs on.

#![cfg(target_arch = "x86_64")]

use super::spring::{MIN_SPRING_LENGTH, Run, projection_residual, spring_force};
use super::sweep::{Contact, SweepArrays};
use crate::solver::packed::PackedSpring;
use glam::DVec2;
use std::arch::x86_64::*;

pub(crate) use crate::solver::threads::machine::avx as available;

/// [`super::kernels::for_each_spring_force`], four springs at a time.
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[target_feature(enable = "avx")]
pub unsafe fn for_each_spring_force(
    x: &[DVec2],
    springs: &[PackedSpring],
    mut add: impl FnMut(usize, DVec2),
) {
    let mut run = Run::new(springs.first().map(|s| s.a));
    // Two quads per iteration: the loop waits on the latency of the square root and the
    // division, and the second quad's overlap the first's (measured: 196 -> 220 M springs/s
    // at 256², one thread).
    let mut octs = springs.chunks_exact(8);
    let (mut f0, mut f1) = ([0.0f64; 8], [0.0f64; 8]);
    let prefetch = x.len() >= PREFETCH_FROM_PARTICLES;
    for (o, oct) in (&mut octs).enumerate() {
        if prefetch {
            prefetch_ahead(x, springs, 8 * o);
        }
        let (q0, q1) = oct.split_at(4);
        // SAFETY: this function's caller guarantees AVX.
        let short = unsafe { four_forces(x, q0, &mut f0) | (four_forces(x, q1, &mut f1) << 4) };
        for (i, s) in oct.iter().enumerate() {
            let (q, j) = (if i < 4 { &f0 } else { &f1 }, 2 * (i % 4));
            let force = (short & (1 << i) == 0).then_some(DVec2::new(q[j], q[j + 1]));
            run.push((s.a, s.b), force, &mut add);
        }
    }
    for s in octs.remainder() {
        run.push((s.a, s.b), spring_force(s, x), &mut add);
    }
    run.finish(add);
}

/// From this many particles (4 MB of positions) the force pass asks for its data ahead of
/// use. Measured on an Intel Xeon (2026-12-03, `docs/performance.md`): on the 707² cloth (2 M springs) the
/// pass ran 35–43 % faster with it, on 1000² and 2000² 8–15 %; on 500² it gained 2–8 % and on
/// the cached 256² and 350² cloths it lost up to 7 %.
const PREFETCH_FROM_PARTICLES: usize = 1 << 18;

/// How far ahead, in springs, the far ends' positions are asked for; the spring records
/// themselves twice as far.
const PREFETCH_AHEAD: usize = 256;

/// Asks for the cache lines the pass will need [`PREFETCH_AHEAD`] springs on: the position of
/// that spring's far end b (its near end a is the current run's, in order; b lies a cloth's
/// width away), and the spring record [`PREFETCH_AHEAD`] further, so that reading a record to
/// find its b never waits on memory. Hints only: the results are the same bits.
#[inline(always)]
fn prefetch_ahead(x: &[DVec2], springs: &[PackedSpring], at: usize) {
    if let Some(p) = springs
        .get(at + PREFETCH_AHEAD)
        .and_then(|s| x.get(s.b as usize))
    {
        // SAFETY: a prefetch reads nothing the program sees; the address is an element of x.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(p).cast()) };
    }
    if let Some(s) = springs.get(at + 2 * PREFETCH_AHEAD) {
        // SAFETY: as above; the address is an element of springs.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(s).cast()) };
    }
}

/// Four springs' d = x_a − x_b, two springs per register ([d0, d1], [d2, d3]), and their
/// lengths √(d·d) in the lane order [0, 2, 1, 3] (`_mm256_hadd_pd` works within 128-bit lanes).
///
/// # Safety
/// The CPU must support AVX ([`available`]); always inlined, it inherits AVX from its caller.
#[inline(always)]
unsafe fn four_differences(x: &[DVec2], s: &[PackedSpring]) -> (__m256d, __m256d, __m256d) {
    let (s0, s1, s2, s3) = (&s[0], &s[1], &s[2], &s[3]);
    let a = [
        x[s0.a as usize],
        x[s1.a as usize],
        x[s2.a as usize],
        x[s3.a as usize],
    ];
    let b = [
        x[s0.b as usize],
        x[s1.b as usize],
        x[s2.b as usize],
        x[s3.b as usize],
    ];
    // SAFETY: the caller guarantees AVX.
    let q = unsafe { Quad::of(a, b) };
    (q.d01, q.d23, q.l)
}

/// Four springs' ends in registers, two points to a register ([p0, p1] as x0, y0, x1, y1),
/// with d = a − b and √(d·d) in the lane order [0, 2, 1, 3]: what the force pass, the
/// projective local step and the XPBD sweep all start from.
pub(crate) struct Quad {
    pub a01: __m256d,
    pub a23: __m256d,
    pub b01: __m256d,
    pub b23: __m256d,
    pub d01: __m256d,
    pub d23: __m256d,
    pub l: __m256d,
}

impl Quad {
    /// # Safety
    /// The CPU must support AVX ([`available`]); always inlined, it inherits AVX from its
    /// caller.
    #[inline(always)]
    pub(crate) unsafe fn of(a: [DVec2; 4], b: [DVec2; 4]) -> Quad {
        // SAFETY: the caller guarantees AVX.
        unsafe {
            // No closure here: closures do not inherit AVX.
            let a01 = _mm256_set_pd(a[1].y, a[1].x, a[0].y, a[0].x);
            let a23 = _mm256_set_pd(a[3].y, a[3].x, a[2].y, a[2].x);
            let b01 = _mm256_set_pd(b[1].y, b[1].x, b[0].y, b[0].x);
            let b23 = _mm256_set_pd(b[3].y, b[3].x, b[2].y, b[2].x);
            let d01 = _mm256_sub_pd(a01, b01);
            let d23 = _mm256_sub_pd(a23, b23);
            let l = _mm256_sqrt_pd(_mm256_hadd_pd(
                _mm256_mul_pd(d01, d01),
                _mm256_mul_pd(d23, d23),
            ));
            Quad {
                a01,
                a23,
                b01,
                b23,
                d01,
                d23,
                l,
            }
        }
    }
}

/// Four per-spring numbers in [`Quad`]'s lane order [0, 2, 1, 3].
///
/// # Safety
/// The CPU must support AVX ([`available`]); always inlined, it inherits AVX from its caller.
#[inline(always)]
pub(crate) unsafe fn lanes(v: [f64; 4]) -> __m256d {
    // SAFETY: the caller guarantees AVX. `_mm256_set_pd` takes the lanes high to low.
    unsafe { _mm256_set_pd(v[3], v[1], v[2], v[0]) }
}

/// A mask in [`Quad`]'s lane order [0, 2, 1, 3] (bit i for lane i) in spring order.
pub(crate) fn spring_order(mask: i32) -> i32 {
    (mask & 0b1001) | ((mask & 0b0010) << 1) | ((mask & 0b0100) >> 1)
}

/// Writes the forces on the a ends of four springs to `out` (x0, y0, x1, y1, ...) and returns a
/// mask of the springs shorter than [`MIN_SPRING_LENGTH`] (bit i for spring i), whose forces
/// are to be skipped, as in the scalar kernel.
///
/// Always inlined into the AVX loop (a call per quad cost ~5 % of the pass); a function with
/// `target_feature` cannot be, so this one has none and inherits AVX from its caller.
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[inline(always)]
unsafe fn four_forces(x: &[DVec2], s: &[PackedSpring], out: &mut [f64; 8]) -> i32 {
    // SAFETY: the caller guarantees AVX; the stores write the eight f64 of `out`.
    unsafe {
        let (s0, s1, s2, s3) = (&s[0], &s[1], &s[2], &s[3]);
        let (d01, d23, l) = four_differences(x, s);
        let neg_k = lanes([-s0.k, -s1.k, -s2.k, -s3.k]);
        let rest = lanes([s0.rest, s1.rest, s2.rest, s3.rest]);
        let c = _mm256_div_pd(_mm256_mul_pd(neg_k, _mm256_sub_pd(l, rest)), l);
        // Each coefficient twice, back in spring order: [c0, c0, c1, c1] and [c2, c2, c3, c3].
        let f01 = _mm256_mul_pd(d01, _mm256_unpacklo_pd(c, c));
        let f23 = _mm256_mul_pd(d23, _mm256_unpackhi_pd(c, c));
        // out holds eight f64: two unaligned 256-bit stores of four each.
        _mm256_storeu_pd(out.as_mut_ptr(), f01);
        _mm256_storeu_pd(out.as_mut_ptr().add(4), f23);
        let short = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(
            l,
            _mm256_set1_pd(MIN_SPRING_LENGTH),
        ));
        spring_order(short)
    }
}

/// [`super::kernels::spring_energy`], four springs at a time: the same eight running sums, held
/// in two registers.
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[target_feature(enable = "avx")]
pub unsafe fn spring_energy(x: &[DVec2], springs: &[PackedSpring]) -> f64 {
    let mut octs = springs.chunks_exact(8);
    let (mut e0, mut e1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    for oct in &mut octs {
        let (q0, q1) = oct.split_at(4);
        // SAFETY: this function's caller guarantees AVX.
        unsafe {
            e0 = _mm256_add_pd(e0, four_energies(x, q0));
            e1 = _mm256_add_pd(e1, four_energies(x, q1));
        }
    }
    let mut held = [0.0f64; 8];
    // SAFETY: two unaligned stores of four f64 each into `held`'s eight.
    unsafe {
        _mm256_storeu_pd(held.as_mut_ptr(), e0);
        _mm256_storeu_pd(held.as_mut_ptr().add(4), e1);
    }
    // The registers hold their springs in the lane order [0, 2, 1, 3].
    let order = [0, 2, 1, 3, 4, 6, 5, 7];
    let sums = std::array::from_fn(|i| held[order[i]]);
    super::spring::energy_total(sums, octs.remainder(), x)
}

/// Four springs' ½k(|x_a − x_b| − L)², in [`Quad`]'s lane order [0, 2, 1, 3].
///
/// # Safety
/// The CPU must support AVX ([`available`]); always inlined, it inherits AVX from its caller.
#[inline(always)]
unsafe fn four_energies(x: &[DVec2], s: &[PackedSpring]) -> __m256d {
    // SAFETY: the caller guarantees AVX.
    unsafe {
        let (_, _, l) = four_differences(x, s);
        let half_k = lanes([0.5 * s[0].k, 0.5 * s[1].k, 0.5 * s[2].k, 0.5 * s[3].k]);
        let rest = lanes([s[0].rest, s[1].rest, s[2].rest, s[3].rest]);
        let stretch = _mm256_sub_pd(l, rest);
        _mm256_mul_pd(_mm256_mul_pd(half_k, stretch), stretch)
    }
}

/// Projective dynamics' local step ([`crate::solver::methods::projective`]) four springs at a time: for each
/// spring, `add(a, c)` and `add(b, −c)` with c = l · (L / |l| − 1) · h²k, l = x_a − x_b
/// (c = 0 where |l| is 0 or not a number). The operations are [`projection_residual`]'s, in
/// its order, so the bits are the scalar step's.
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[target_feature(enable = "avx")]
pub unsafe fn for_each_projection(
    x: &[DVec2],
    springs: &[PackedSpring],
    h2: f64,
    mut add: impl FnMut(usize, DVec2),
) {
    let mut run = Run::new(springs.first().map(|s| s.a));
    let mut octs = springs.chunks_exact(8);
    let (mut c0, mut c1) = ([0.0f64; 8], [0.0f64; 8]);
    for oct in &mut octs {
        let (q0, q1) = oct.split_at(4);
        // SAFETY: this function's caller guarantees AVX.
        unsafe {
            four_projections(x, q0, h2, &mut c0);
            four_projections(x, q1, h2, &mut c1);
        }
        for (i, s) in oct.iter().enumerate() {
            let (q, j) = (if i < 4 { &c0 } else { &c1 }, 2 * (i % 4));
            run.push((s.a, s.b), Some(DVec2::new(q[j], q[j + 1])), &mut add);
        }
    }
    for s in octs.remainder() {
        run.push((s.a, s.b), Some(projection_residual(s, x, h2)), &mut add);
    }
    run.finish(add);
}

/// Writes four springs' [`projection_residual`]s to `out` (x0, y0, x1, y1, ...).
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[inline(always)]
unsafe fn four_projections(x: &[DVec2], s: &[PackedSpring], h2: f64, out: &mut [f64; 8]) {
    // SAFETY: the caller guarantees AVX; the stores write the eight f64 of `out`.
    unsafe {
        let (s0, s1, s2, s3) = (&s[0], &s[1], &s[2], &s[3]);
        let (d01, d23, l) = four_differences(x, s);
        let rest = lanes([s0.rest, s1.rest, s2.rest, s3.rest]);
        // L / |l| where |l| > 0, else 1 (NaN compares false): d = l · 1 = l exactly.
        let positive = _mm256_cmp_pd::<_CMP_GT_OQ>(l, _mm256_setzero_pd());
        let q = _mm256_blendv_pd(_mm256_set1_pd(1.0), _mm256_div_pd(rest, l), positive);
        let q = _mm256_sub_pd(q, _mm256_set1_pd(1.0));
        let hk = lanes([h2 * s0.k, h2 * s1.k, h2 * s2.k, h2 * s3.k]);
        let c01 = _mm256_mul_pd(
            _mm256_mul_pd(d01, _mm256_unpacklo_pd(q, q)),
            _mm256_unpacklo_pd(hk, hk),
        );
        let c23 = _mm256_mul_pd(
            _mm256_mul_pd(d23, _mm256_unpackhi_pd(q, q)),
            _mm256_unpackhi_pd(hk, hk),
        );
        _mm256_storeu_pd(out.as_mut_ptr(), c01);
        _mm256_storeu_pd(out.as_mut_ptr().add(4), c23);
    }
}

/// [`super::kernels::particle_sweep`]'s loop (`MOTION` as there) two particles at a time, each
/// particle's (x, y) a half of a 256-bit register, and the ground contact a blend instead of a
/// branch: on a cloth lying on the ground the branch goes one way and the other from step to
/// step, particle by particle, and mispredicts. The operations are the scalar loop's, lane by
/// lane and in its order (the blend picks the very values the branch assigns), so x and v are
/// its bits; the finiteness probe sums in another order, which changes no answer: its sum is
/// zero while every term is, and NaN once one is.
///
/// # Safety
/// The CPU must support AVX ([`available`]).
#[target_feature(enable = "avx")]
pub unsafe fn particle_sweep<const MOTION: u8, const DAMP: bool, const GROUND: bool>(
    (x, v, f, inv_mass, drift): SweepArrays,
    dt: f64,
    decay: f64,
    (ground, contact): (f64, Contact),
) -> bool {
    let n = x.len();
    assert!(v.len() == n && f.len() == n && inv_mass.len() == n && drift.len() == n);
    let pairs = n / 2;
    let kick = MOTION <= 1;
    // SAFETY: the caller guarantees AVX; every load and store reads or writes particles
    // 2p and 2p + 1 < n of arrays of length n (asserted), a DVec2 being two f64.
    let probe = unsafe {
        let (dtv, decayv) = (_mm256_set1_pd(dt), _mm256_set1_pd(decay));
        let zero = _mm256_setzero_pd();
        // The y lanes, where the contact acts, and the ground's height there.
        let y_lanes = _mm256_castsi256_pd(_mm256_set_epi64x(-1, 0, -1, 0));
        let groundv = _mm256_set1_pd(ground);
        let (xp, vp) = (x.as_mut_ptr() as *mut f64, v.as_mut_ptr() as *mut f64);
        let (fp, dp) = (f.as_ptr() as *const f64, drift.as_ptr() as *const f64);
        let mut probe = zero;
        for p in 0..pairs {
            let at = 4 * p;
            let (w0, w1) = (inv_mass[2 * p], inv_mass[2 * p + 1]);
            let w = _mm256_set_pd(w1, w1, w0, w0);
            let mut xv = _mm256_loadu_pd(xp.add(at));
            let mut vv = _mm256_loadu_pd(vp.add(at));
            let before = vv;
            if kick {
                let fv = _mm256_loadu_pd(fp.add(at));
                vv = _mm256_add_pd(vv, _mm256_mul_pd(_mm256_mul_pd(fv, dtv), w));
            }
            if DAMP {
                vv = _mm256_mul_pd(vv, decayv);
            }
            if GROUND {
                let height = match contact {
                    Contact::Start => xv,
                    Contact::End { dt } => _mm256_add_pd(xv, _mm256_mul_pd(vv, _mm256_set1_pd(dt))),
                };
                let free = _mm256_cmp_pd::<_CMP_NEQ_UQ>(w, zero);
                let mut below = _mm256_cmp_pd::<_CMP_LT_OQ>(height, groundv);
                if let Contact::End { .. } = contact {
                    // Ending on the ground heading into it ([`Contact::apply`]).
                    let on = _mm256_cmp_pd::<_CMP_EQ_OQ>(height, groundv);
                    let into = _mm256_cmp_pd::<_CMP_LT_OQ>(vv, zero);
                    below = _mm256_or_pd(below, _mm256_and_pd(on, into));
                }
                let hit = _mm256_and_pd(_mm256_and_pd(free, below), y_lanes);
                xv = _mm256_blendv_pd(xv, groundv, hit);
                vv = _mm256_blendv_pd(vv, zero, hit);
            }
            let u = match MOTION {
                0 => before,
                1 | 2 => vv,
                _ => _mm256_loadu_pd(dp.add(at)),
            };
            xv = _mm256_add_pd(xv, _mm256_mul_pd(u, dtv));
            _mm256_storeu_pd(xp.add(at), xv);
            _mm256_storeu_pd(vp.add(at), vv);
            probe = _mm256_add_pd(
                probe,
                _mm256_add_pd(_mm256_mul_pd(xv, zero), _mm256_mul_pd(vv, zero)),
            );
        }
        let mut lanes = [0.0f64; 4];
        _mm256_storeu_pd(lanes.as_mut_ptr(), probe);
        lanes.iter().sum::<f64>()
    };
    let tail = 2 * pairs;
    let rest = (
        &mut x[tail..],
        &mut v[tail..],
        &f[tail..],
        &inv_mass[tail..],
        &drift[tail..],
    );
    let rest_finite =
        super::sweep::sweep_portable::<MOTION, DAMP, GROUND>(rest, dt, decay, (ground, contact));
    probe == 0.0 && rest_finite
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::bits;
    use crate::solver::forces::spring::scatter_pairs;

    /// Forces from the AVX pass and the scalar pass, for springs of every kind: runs sharing an
    /// end, a zero-length spring, one with a NaN end, and a tail that is not a whole quad.
    #[test]
    fn four_at_a_time_gives_the_scalar_bits() {
        if !available() {
            return; // nothing to compare on this CPU
        }
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut x: Vec<DVec2> = (0..200).map(|_| DVec2::new(next(), next())).collect();
        x[7] = x[3]; // the spring (3, 7) has zero length
        x[150] = DVec2::new(f64::NAN, 0.5);
        let mut springs = Vec::new();
        for a in 0..199u32 {
            for b in (a + 1..200).step_by(37 + a as usize % 5) {
                let rest = 0.5 * next();
                springs.push(PackedSpring {
                    a,
                    b,
                    rest,
                    k: 1e4 * (0.5 + next()),
                });
            }
        }
        springs.push(PackedSpring {
            a: 3,
            b: 7,
            rest: 0.1,
            k: 1e4,
        });
        springs.sort_by_key(|s| (s.a, s.b));
        assert!(springs.len() % 4 != 0);

        let wide = forces_as_the_scalar_pass(&x, &springs);
        assert!(wide[150].is_nan() && wide[0].is_finite());
    }

    /// A scene big enough for the pass to prefetch (a strip of particles two wide, each joined
    /// to its neighbours along and across): the same forces as the scalar pass.
    #[test]
    fn prefetching_on_a_big_scene_gives_the_scalar_bits() {
        if !available() {
            return;
        }
        let n = PREFETCH_FROM_PARTICLES + 7;
        let x: Vec<DVec2> = (0..n)
            .map(|i| DVec2::new((i / 2) as f64 * 0.01, (i % 2) as f64 * 0.011))
            .collect();
        let mut springs = Vec::new();
        for a in 0..n as u32 {
            for b in [a + 1, a + 2, a + 3] {
                if (b as usize) < n {
                    springs.push(PackedSpring {
                        a,
                        b,
                        rest: 0.0095,
                        k: 1e4,
                    });
                }
            }
        }
        let wide = forces_as_the_scalar_pass(&x, &springs);
        assert!(wide.iter().any(|f| *f != DVec2::ZERO));
    }

    /// The AVX spring energy is the portable sum's bits: on lists of every length from 0 to 40
    /// (no eight, one, some and many eights with every tail) and on a strip of 30,000 springs
    /// with stretched, compressed, zero-length and stiff-and-soft springs.
    #[test]
    fn energy_four_at_a_time_gives_the_portable_bits() {
        if !available() {
            return;
        }
        use crate::solver::forces::kernels::spring_energy_portable;
        let n = 10_000;
        let x: Vec<DVec2> = (0..n)
            .map(|i| {
                let t = i as f64;
                DVec2::new(
                    0.01 * (t / 2.0).floor() + 1e-3 * (t * 0.7).sin(),
                    0.011 * (t % 2.0),
                )
            })
            .collect();
        let springs: Vec<PackedSpring> = (0..n as u32)
            .flat_map(|a| [a + 1, a + 2, a + 3].map(move |b| (a, b.min(n as u32 - 1))))
            .enumerate()
            .map(|(i, (a, b))| PackedSpring {
                a,
                b,
                rest: 0.008 + 1e-3 * (i % 5) as f64,
                k: if i % 3 == 0 { 1e6 } else { 37.5 },
            })
            .collect();
        for len in (0..=40).chain([springs.len()]) {
            let part = &springs[..len];
            // SAFETY: AVX is available, checked above.
            let wide = unsafe { spring_energy(&x, part) };
            let portable = spring_energy_portable(&x, part);
            assert_eq!(wide.to_bits(), portable.to_bits(), "{len} springs");
            assert!(len < 8 || wide > 0.0);
        }
    }

    /// The AVX pass's forces, asserted to be the scalar pass's bits. The CPU must have AVX.
    fn forces_as_the_scalar_pass(x: &[DVec2], springs: &[PackedSpring]) -> Vec<DVec2> {
        let mut wide = vec![DVec2::ZERO; x.len()];
        // SAFETY: the callers check that AVX is available.
        unsafe { for_each_spring_force(x, springs, |i, f| wide[i] += f) };
        let mut scalar = vec![DVec2::ZERO; x.len()];
        scatter_pairs(springs, |s| spring_force(s, x), |i, f| scalar[i] += f);
        assert_eq!(bits(&wide), bits(&scalar));
        wide
    }

    /// The AVX particle sweep and the portable one give the same x and v bits and the same
    /// finiteness answer, for every combination of motion, damping and ground: particles above,
    /// on and under the ground (at the start and, for the end-of-step test, at the end, one
    /// heading into it),
    /// pinned ones, a negative zero, an infinite and a NaN velocity, and an odd count.
    #[test]
    fn sweep_two_at_a_time_gives_the_portable_bits() {
        if !available() {
            return;
        }
        use crate::solver::forces::sweep::sweep_portable;
        let n = 41;
        let start = |bad: bool| {
            let mut x: Vec<DVec2> = (0..n)
                .map(|i| DVec2::new(0.002 * (20.0 - i as f64), 0.003 * (i as f64 - 20.0)))
                .collect();
            let mut v: Vec<DVec2> = (0..n)
                .map(|i| DVec2::new((i as f64 * 0.7).sin(), (i as f64 * 1.3).cos() * 3.0))
                .collect();
            v[5].y = -0.0;
            // On the ground at the end of the step, heading into it by round-off.
            (x[8].y, v[8].y) = (0.001, -1e-20);
            if bad {
                v[11].x = f64::INFINITY;
                v[30].y = f64::NAN;
            }
            let f: Vec<DVec2> = (0..n).map(|i| DVec2::new(0.5, -9.8 + i as f64)).collect();
            let w: Vec<f64> = (0..n)
                .map(|i| {
                    if i % 7 == 3 {
                        0.0
                    } else {
                        1.0 / (1.0 + i as f64)
                    }
                })
                .collect();
            let d: Vec<DVec2> = (0..n)
                .map(|i| DVec2::new(-0.2, 0.1 * i as f64 - 2.0))
                .collect();
            (x, v, f, w, d)
        };
        macro_rules! check {
            ($m:literal, $damp:literal, $ground:literal, $contact:expr) => {
                for bad in [false, true] {
                    let (mut x1, mut v1, f, w, d) = start(bad);
                    let (mut x2, mut v2) = (x1.clone(), v1.clone());
                    let ground = (0.001, $contact);
                    let a = sweep_portable::<$m, $damp, $ground>(
                        (&mut x1, &mut v1, &f, &w, &d),
                        1e-2,
                        0.9,
                        ground,
                    );
                    // SAFETY: AVX is available (checked above).
                    let b = unsafe {
                        particle_sweep::<$m, $damp, $ground>(
                            (&mut x2, &mut v2, &f, &w, &d),
                            1e-2,
                            0.9,
                            ground,
                        )
                    };
                    let what = format!(
                        "motion {} damping {} ground {} bad {bad}",
                        $m, $damp, $ground
                    );
                    assert_eq!((bits(&x1), bits(&v1)), (bits(&x2), bits(&v2)), "{what}");
                    assert_eq!((a, b), (!bad, !bad), "{what}");
                }
            };
        }
        let end = Contact::End { dt: 1e-2 };
        check!(0, false, false, Contact::Start);
        check!(0, true, true, Contact::Start);
        check!(1, false, true, Contact::Start);
        check!(1, true, false, Contact::Start);
        check!(1, true, true, Contact::Start);
        check!(2, false, true, end);
        check!(2, true, true, end);
        check!(2, true, false, end);
        check!(3, false, false, Contact::Start);
        check!(3, true, true, Contact::Start);
    }

    /// The AVX local step and the scalar one give the same bits, coincident and NaN ends too.
    #[test]
    fn projections_four_at_a_time_give_the_scalar_bits() {
        if !available() {
            return;
        }
        let mut x: Vec<DVec2> = (0..60)
            .map(|i| DVec2::new((i as f64 * 0.77).sin(), (i as f64 * 0.31).cos()))
            .collect();
        x[9] = x[4];
        x[40] = DVec2::new(0.2, f64::NAN);
        let mut springs: Vec<PackedSpring> = (0..59u32)
            .flat_map(|a| {
                (a + 1..60).step_by(7).map(move |b| PackedSpring {
                    a,
                    b,
                    rest: 0.01 * (a + b) as f64,
                    k: 1e3 + b as f64,
                })
            })
            .collect();
        springs.push(PackedSpring {
            a: 4,
            b: 9,
            rest: 0.1,
            k: 1e4,
        });
        if springs.len().is_multiple_of(8) {
            springs.pop(); // a tail that is not a whole oct
        }
        springs.sort_by_key(|s| (s.a, s.b));
        let h2 = 1.0 / 3600.0;
        let mut wide = vec![DVec2::ZERO; x.len()];
        // SAFETY: AVX is available (checked above).
        unsafe { for_each_projection(&x, &springs, h2, |i, c| wide[i] += c) };
        let mut scalar = vec![DVec2::ZERO; x.len()];
        scatter_pairs(
            &springs,
            |s| {
                Some(crate::solver::forces::spring::projection_residual(
                    s, &x, h2,
                ))
            },
            |i, c| scalar[i] += c,
        );
        assert_eq!(bits(&wide), bits(&scalar));
        assert!(wide[40].is_nan() && wide[0].is_finite());
    }
}
