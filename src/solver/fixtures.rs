//! What the core's unit tests share: small networks in the packed order, their positions, and
//! comparisons of two results bit for bit or to round-off. Compiled for tests only; it sits
//! below every room, so that a test of a low room need not reach up for its fixtures.

use super::packed::PackedSpring;
use glam::DVec2;

/// Each vector's two coordinates as bits, for the tests that ask two ways of computing the same
/// thing for the same bits.
pub(crate) fn bits(v: &[glam::DVec2]) -> Vec<(u64, u64)> {
    v.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect()
}

/// A `w`×`h` block of 20 g particles a centimetre apart at rest (rows listed bottom first, its
/// bottom row at height `bottom`), joined by [`grid`]'s springs.
pub(crate) fn block(w: u32, h: u32, bottom: f64) -> super::state::State {
    let mut s = super::state::State::default();
    for r in 0..h {
        for c in 0..w {
            s.x.push(DVec2::new(0.01 * c as f64, bottom + 0.01 * r as f64));
            s.v.push(DVec2::ZERO);
            s.mass.push(0.02);
            s.inv_mass.push(50.0);
            s.f.push(DVec2::ZERO);
        }
    }
    s.springs = grid(w, h);
    s
}

/// The springs of a row-major `w`×`h` grid, structural and both diagonals, sorted as the
/// solver packs them.
pub(crate) fn grid(w: u32, h: u32) -> Vec<PackedSpring> {
    let mut springs = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let mut link = |j: u32| {
                springs.push(PackedSpring {
                    a: i,
                    b: j,
                    rest: 0.01,
                    k: 1e4,
                })
            };
            if x + 1 < w {
                link(i + 1);
            }
            if y + 1 < h {
                link(i + w);
                if x + 1 < w {
                    link(i + w + 1);
                }
                if x > 0 {
                    link(i + w - 1);
                }
            }
        }
    }
    springs.sort_by_key(|s| (s.a, s.b));
    springs
}

/// A scrambled network: ends in any order, far apart, shared by many springs.
pub(crate) fn tangle(n: u32, count: usize) -> Vec<PackedSpring> {
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let mut springs: Vec<PackedSpring> = (0..count)
        .map(|_| PackedSpring {
            a: (next() % n as u64) as u32,
            b: (next() % n as u64) as u32,
            rest: 0.1,
            k: 1e3,
        })
        .collect();
    springs.sort_by_key(|s| (s.a, s.b));
    springs
}

pub(crate) fn positions(n: u32) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            DVec2::new(
                (i % 97) as f64 * 0.013,
                (i / 97) as f64 * 0.011 + (i % 7) as f64 * 1e-3,
            )
        })
        .collect()
}

/// Each element of `threaded` within 1e-12 of the largest of `serial` from its own.
pub(crate) fn assert_round_off(serial: &[DVec2], threaded: &[DVec2], what: &str) {
    let scale = serial
        .iter()
        .map(|f| f.abs().max_element())
        .fold(0.0, f64::max);
    for (i, (a, b)) in serial.iter().zip(threaded).enumerate() {
        assert!(
            (*a - *b).abs().max_element() <= 1e-12 * scale,
            "{what}, particle {i}: {a} vs {b}"
        );
    }
}
