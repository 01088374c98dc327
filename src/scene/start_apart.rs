//! With particle pairs colliding, particles not joined by a spring must start at least 2r
//! apart: the check, and the search for the closest pair that names the radius that would do.

use super::format::Scene;
use std::collections::{BTreeSet, HashMap, HashSet};

/// How far inside 2r a pair may start: a contact that a step left. A scene saved from a running
/// simulation holds its resting contacts a little inside 2r (the contact report's pile at 1/60
/// s ends with its closest pair at 82 to 99 % of 2r, by method), and such a file was refused
/// when opened again; a start that far in is what every step of that run began from.
const LEFT_BY_A_STEP: f64 = 0.8;

/// With particle pairs colliding, every pair not joined by a spring must start at least 2r
/// apart, or at least [`LEFT_BY_A_STEP`] of it: one closer is pushed apart at the first step,
/// with all the energy that takes (a 32² cloth at r = 0.05, 1.6 of its spacing, 0.3 of 2r, went
/// from 5,000 J to 150,000 J in a second). Names the closest such pair and the largest radius
/// that leaves every one apart.
pub(super) fn pairs_start_apart(scene: &Scene, radius: f64) -> Option<String> {
    let e = scene.expand();
    let joined: HashSet<(usize, usize)> = e
        .springs
        .iter()
        .map(|s| (s.a.min(s.b), s.a.max(s.b)))
        .collect();
    let positions: Vec<(f64, f64)> = e.particles.iter().map(|p| p.pos).collect();
    let reach = 2.0 * radius * LEFT_BY_A_STEP;
    // Most scenes pass: a grid of cells 2r wide finds whether any pair is too close, and only
    // then does the sweep find the closest.
    let mut visits = 0;
    any_unjoined(&positions, &joined, reach, &mut visits)?;
    let (d, i, j) = closest_unjoined(&positions, &joined, reach, &mut visits)?;
    // Four decimals, or four figures below a millimetre, where four decimals would read 0.
    let metres = |m: f64| match m {
        m if m >= 1e-3 => format!("{m:.4}"),
        m => format!("{m:.3e}"),
    };
    Some(format!(
        "contact.radius: particles {i} and {j} start {} m apart with no spring between them, \
         within 80 % of 2 × radius ({} m), and contact would push them apart at the first step; \
         with particles: true the radius must be under half the distance of every such pair: at \
         most {} here",
        metres(d),
        metres(2.0 * radius),
        metres(0.5 * d)
    ))
}

/// Whether any pair of particles is closer than `within` and not joined by a spring, from a
/// grid of cells `within` wide, so that every such pair is in neighbouring cells. It stops at
/// the first, so a crowd is visited only as far as its first pair. `visits` counts the pairs
/// looked at, for the test that bounds them.
fn any_unjoined(
    positions: &[(f64, f64)],
    joined: &HashSet<(usize, usize)>,
    within: f64,
    visits: &mut usize,
) -> Option<()> {
    // Far from the origin the cells saturate at i64's ends, and their neighbours with them.
    let cell = |p: (f64, f64)| ((p.0 / within).floor() as i64, (p.1 / within).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, &p) in positions.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i);
    }
    for (i, &p) in positions.iter().enumerate() {
        let (cx, cy) = cell(p);
        for (dx, dy) in (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))) {
            for &j in grid
                .get(&(cx.saturating_add(dx), cy.saturating_add(dy)))
                .into_iter()
                .flatten()
            {
                *visits += 1;
                let q = positions[j];
                if j > i && (p.0 - q.0).hypot(p.1 - q.1) < within && !joined.contains(&(i, j)) {
                    return Some(());
                }
            }
        }
    }
    None
}

/// The closest pair of particles closer than `within` and not joined by a spring, as
/// (distance, lower index, higher index): Shamos's sweep in x, with the particles of the last
/// `best` in x kept in order of y.
///
/// A crowd costs no more than its springs: the particles in a `best` × 2`best` box are
/// pairwise joined or at least `best` apart, so there are few unless springs join them. (A
/// grid of cells 2r wide, searched for the closest pair, visited every pair of a
/// million-segment ring, all of it within a few cells: minutes.) `visits` counts the pairs
/// looked at.
fn closest_unjoined(
    positions: &[(f64, f64)],
    joined: &HashSet<(usize, usize)>,
    within: f64,
    visits: &mut usize,
) -> Option<(f64, usize, usize)> {
    // f64 in the order of its bits as u64, for the ordered set (positions are finite here).
    let ordered = |y: f64| {
        let bits = y.to_bits();
        if bits >> 63 == 1 {
            !bits
        } else {
            bits | 1 << 63
        }
    };
    let mut by_x: Vec<usize> = (0..positions.len()).collect();
    by_x.sort_by(|&a, &b| positions[a].0.total_cmp(&positions[b].0));
    let mut window = BTreeSet::new();
    let mut oldest = 0;
    let mut best = within;
    let mut closest = None;
    for (k, &i) in by_x.iter().enumerate() {
        let (x, y) = positions[i];
        // By the difference, not `x - best`: far from 0 that rounds to x itself.
        while oldest < k && x - positions[by_x[oldest]].0 >= best {
            window.remove(&(ordered(positions[by_x[oldest]].1), by_x[oldest]));
            oldest += 1;
        }
        let band = (ordered(y - best), 0)..=(ordered(y + best), usize::MAX);
        for &(_, j) in window.range(band) {
            *visits += 1;
            let q = positions[j];
            let d = (x - q.0).hypot(y - q.1);
            let pair = (i.min(j), i.max(j));
            if d < best && !joined.contains(&pair) {
                best = d;
                closest = Some((d, pair.0, pair.1));
            }
        }
        if best == 0.0 {
            break;
        }
        window.insert((ordered(y), i));
    }
    closest
}

#[cfg(test)]
mod tests {
    use super::{HashSet, any_unjoined, closest_unjoined};

    /// A small generator of numbers in [0, 1), so that the clouds below are the same each run.
    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The sweep finds the closest pair without a spring, as every pair compared finds it: on
    /// clouds with springs among the close pairs, particles on one vertical or horizontal
    /// line (the sweep's ties in x and y), coincident ones and ones at x = 1e300.
    #[test]
    fn the_closest_pair_without_a_spring_is_the_closest() {
        let mut seed = 7;
        for cloud in 0..300 {
            let n = 2 + cloud % 60;
            let positions: Vec<(f64, f64)> = (0..n)
                .map(|k| match cloud % 6 {
                    0 => (0.5, lcg(&mut seed)),
                    1 => (lcg(&mut seed), 0.25),
                    2 if k % 7 == 3 => (0.5, 0.5),
                    // Far from the origin, where x - within rounds to x.
                    3 if k % 5 == 1 => (1e300, lcg(&mut seed)),
                    _ => (lcg(&mut seed), lcg(&mut seed)),
                })
                .collect();
            let mut joined = HashSet::new();
            let mut expected: Option<(f64, usize, usize)> = None;
            let within = 0.05 + 0.3 * lcg(&mut seed);
            for i in 0..n {
                for j in i + 1..n {
                    let d =
                        (positions[i].0 - positions[j].0).hypot(positions[i].1 - positions[j].1);
                    if d < 2.0 * within && lcg(&mut seed) < 0.5 {
                        joined.insert((i, j));
                    } else if d < within && expected.is_none_or(|e| d < e.0) {
                        expected = Some((d, i, j));
                    }
                }
            }
            let mut visits = 0;
            let found = closest_unjoined(&positions, &joined, within, &mut visits);
            assert_eq!(
                found.map(|f| f.0),
                expected.map(|e| e.0),
                "cloud {cloud}: {positions:?}"
            );
            assert_eq!(
                any_unjoined(&positions, &joined, within, &mut visits).is_some(),
                expected.is_some(),
                "cloud {cloud}"
            );
        }
    }

    /// A crowd costs no more than its particles and springs: a ring of 100,000 segments at
    /// r = 0.005, every particle within 2r of thousands of others, is refused after a few
    /// pairs a particle (the closest pair searched on a grid of 2r looked at 7e8).
    #[test]
    fn a_crowd_within_the_contact_radius_is_searched_in_linear_work() {
        let n = 100_000;
        let positions: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                (0.5 + 0.07 * a.cos(), 0.5 + 0.07 * a.sin())
            })
            .collect();
        let joined: HashSet<(usize, usize)> = (0..n)
            .map(|k| (k.min((k + 1) % n), k.max((k + 1) % n)))
            .collect();
        let mut visits = 0;
        assert!(any_unjoined(&positions, &joined, 0.01, &mut visits).is_some());
        let (d, ..) = closest_unjoined(&positions, &joined, 0.01, &mut visits).unwrap();
        let two_segments = 2.0 * 0.07 * (std::f64::consts::TAU / n as f64);
        assert!((d - two_segments).abs() < 1e-3 * two_segments, "{d}");
        assert!(
            visits < 20 * 2 * n,
            "{visits} pairs looked at for {n} particles"
        );
    }
}
