//! Pair passes on the pool's threads without atomics (the spring forces, implicit Euler's
//! K u): each pair is evaluated once, and its contributions are scattered to its two ends.
//!
//! The packed pairs are split into one contiguous part per thread; a part writes its own slice
//! of the output, the particles no other part touches, and records its contributions to the
//! rest, which are added after (see [`scatter_from`]).

use super::pool::Threads;
use crate::solver::packed::PackedSpring;
use glam::DVec2;
use std::ops::Range;

/// How a pair pass splits its work, cached until the pairs or the thread count change.
#[derive(Debug, Clone, PartialEq)]
struct Layout {
    springs: usize,
    threads: usize,
    parts: Vec<Part>,
}

/// One thread's share of a pair pass.
#[derive(Debug, Clone, PartialEq)]
struct Part {
    /// The particles no other part touches: this part adds into them directly.
    exclusive: Range<usize>,
    /// The part's springs, a contiguous range of the packed springs, cut into segments.
    segments: Vec<Segment>,
}

/// A run of a part's springs.
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    springs: Range<usize>,
    /// Both ends of every spring lie in the part's exclusive range: the plain kernel runs on
    /// it. Otherwise forces on particles outside the range are recorded and added after.
    inner: bool,
}

/// Runs of inner springs shorter than this join the recording segments around them: a segment
/// boundary splits a particle's register run in two.
const MIN_INNER_SEGMENT: usize = 64;

impl Layout {
    fn new(springs: &[impl Pair], threads: usize) -> Layout {
        let chunk = springs.len().div_ceil(threads).max(1);
        let chunks: Vec<Range<usize>> = (0..springs.len())
            .step_by(chunk)
            .map(|start| start..(start + chunk).min(springs.len()))
            .collect();
        let touched: Vec<(usize, usize)> = chunks
            .iter()
            .map(|c| {
                springs[c.clone()]
                    .iter()
                    .fold((usize::MAX, 0), |(lo, hi), s| {
                        let (a, b) = s.ends();
                        (lo.min(a).min(b), hi.max(a + 1).max(b + 1))
                    })
            })
            .collect();
        let parts = chunks
            .into_iter()
            .enumerate()
            .map(|(t, chunk)| {
                let exclusive = exclusive_range(&touched, t);
                let segments = segments(springs, chunk, &exclusive);
                Part {
                    exclusive,
                    segments,
                }
            })
            .collect();
        Layout {
            springs: springs.len(),
            threads,
            parts,
        }
    }
}

/// The part of chunk `t`'s touched particle range that no other chunk touches (when another
/// chunk's range lies inside it, the larger side is kept).
fn exclusive_range(touched: &[(usize, usize)], t: usize) -> Range<usize> {
    let (mut lo, mut hi) = touched[t];
    for (j, &(lj, hj)) in touched.iter().enumerate() {
        if j == t || lj >= hi || hj <= lo {
            continue; // no overlap with what is left
        }
        if lj <= lo {
            lo = hj.min(hi);
        } else if hj >= hi {
            hi = lj.max(lo);
        } else if lj - lo >= hi - hj {
            hi = lj; // the other lies inside: keep the larger side
        } else {
            lo = hj;
        }
    }
    lo..hi.max(lo)
}

/// Cuts `chunk` into alternating inner and recording segments.
fn segments<P: Pair>(springs: &[P], chunk: Range<usize>, exclusive: &Range<usize>) -> Vec<Segment> {
    let inner = |s: &P| {
        let (a, b) = s.ends();
        exclusive.contains(&a) && exclusive.contains(&b)
    };
    let mut out: Vec<Segment> = Vec::new();
    let mut i = chunk.start;
    while i < chunk.end {
        let kind = inner(&springs[i]);
        let len = springs[i..chunk.end]
            .iter()
            .take_while(|s| inner(s) == kind)
            .count();
        let seg = i..i + len;
        i += len;
        let kind = kind && len >= MIN_INNER_SEGMENT;
        match out.last_mut() {
            Some(last) if !last.inner && !kind => last.springs.end = seg.end,
            _ => out.push(Segment {
                springs: seg,
                inner: kind,
            }),
        }
    }
    out
}

/// A pair pass's per-thread state, reused from step to step.
#[derive(Debug, Default, Clone)]
pub struct SpringBuffers {
    layout: Option<Layout>,
    /// Per part, the forces on particles outside its exclusive range, applied after.
    boundary: Vec<Recorded>,
}

/// One part's recorded forces, on a cache line (pair) of its own: the parts push to their
/// lists at the same time, and two list headers sharing a line would bounce it between cores.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
struct Recorded(Vec<(u32, DVec2)>);

/// Splits `f` into one mutable slice per range; the ranges are disjoint, in any order.
fn carve<'f>(
    mut f: &'f mut [DVec2],
    ranges: impl Iterator<Item = Range<usize>>,
) -> Vec<&'f mut [DVec2]> {
    let mut order: Vec<(usize, Range<usize>)> = ranges.enumerate().collect();
    order.sort_by_key(|(_, r)| r.start);
    let mut slices: Vec<(usize, &'f mut [DVec2])> = Vec::with_capacity(order.len());
    let mut at = 0;
    for (t, r) in order {
        let rest = std::mem::take(&mut f);
        let (_, tail) = rest.split_at_mut(r.start - at);
        let (mine, tail) = tail.split_at_mut(r.len());
        slices.push((t, mine));
        f = tail;
        at = r.end;
    }
    slices.sort_by_key(|(t, _)| *t);
    slices.into_iter().map(|(_, s)| s).collect()
}

/// Something joining two particles, in the packed order: a spring, or its stiffness block.
pub trait Pair {
    /// The two particles' dense indices.
    fn ends(&self) -> (usize, usize);
}

impl Pair for PackedSpring {
    fn ends(&self) -> (usize, usize) {
        (self.a as usize, self.b as usize)
    }
}

/// A pass that adds a contribution of each pair to its ends (the spring forces, K u).
pub trait PairPass: Sync {
    type Pair: Pair + Sync;
    /// Calls `add(i, v)` for every contribution of `pairs`, in order.
    fn run(&self, pairs: &[Self::Pair], add: impl FnMut(usize, DVec2));
}

/// out = init + every contribution of `pass` over `pairs`, on the pool's threads when
/// worthwhile: `init(start, slice)` writes each particle's starting value into `slice`, the
/// particles from `start` on (see [`spring_forces_from`]).
///
/// The pairs are split into one contiguous part per thread, and each part's particles into
/// those no other part touches (its exclusive range, a slice of `out` of its own) and the rest.
/// Within a part, runs of pairs with both ends in the exclusive range (for a row-major cloth,
/// all but about one row's springs at each end of the part) go through the serial kernel
/// unchanged; the others record their contributions to outside particles, which are added
/// after the parallel part. No atomics, no unsafe, no full-size buffers: one parallel region.
/// `buffers` caches the split for these pairs; it is redone when their number or the thread
/// count changes, and the solver starts new buffers whenever it repacks the springs.
pub fn scatter_from<P: PairPass>(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    out: &mut [DVec2],
    pairs: &[P::Pair],
    pass: &P,
    init: &(impl Fn(usize, &mut [DVec2]) + Sync),
) {
    scatter_parts(threads, buffers, out, pairs, pass, Some(init));
}

/// out += every contribution of `pass` over `pairs` ([`scatter_from`] without a start).
#[cfg(test)]
pub fn scatter<P: PairPass>(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    out: &mut [DVec2],
    pairs: &[P::Pair],
    pass: &P,
) {
    scatter_parts(
        threads,
        buffers,
        out,
        pairs,
        pass,
        None::<&fn(usize, &mut [DVec2])>,
    );
}

/// `out[i] += v`, in the serial pair pass.
///
/// Every pass gathers its pairs' ends, with bounds checks, from a per-particle array of `out`'s
/// length (x, the iterate z, the direction u), so an end outside `out` has already panicked
/// there. This check cannot fail; it skips the add instead of panicking because that runs
/// fewer instructions than indexing: the 256² cloth's spring pass on one thread 9 % fewer
/// (instruction counts under callgrind, 30 steps) and 6–10 % faster (8 alternating rounds on an
/// AMD EPYC); a cold panic function in place of the skip gained nothing. The threaded parts'
/// inner runs keep indexing: there the same change added 6 % to the count. Debug builds, which
/// the tests run, still stop on it.
#[inline(always)]
fn add_at(out: &mut [DVec2], i: usize, v: DVec2) {
    match out.get_mut(i) {
        Some(o) => *o += v,
        None => debug_assert!(false, "pair end {i} outside the {} particles", out.len()),
    }
}

/// [`scatter_from`]; with `init`, each part first starts its own particles, and the particles
/// of no part are started after the region, before the recorded contributions are added.
fn scatter_parts<P: PairPass, I: Fn(usize, &mut [DVec2]) + Sync>(
    threads: &Threads,
    buffers: &mut SpringBuffers,
    out: &mut [DVec2],
    pairs: &[P::Pair],
    pass: &P,
    init: Option<&I>,
) {
    let Some(pool) = threads.pool_for(pairs.len()) else {
        if let Some(init) = init {
            init(0, out);
        }
        pass.run(pairs, |i, v| add_at(out, i, v));
        return;
    };
    let stale = buffers
        .layout
        .as_ref()
        .is_none_or(|l| l.springs != pairs.len() || l.threads != threads.threads());
    if stale {
        buffers.layout = Some(Layout::new(pairs, threads.threads()));
    }
    let Some(layout) = buffers.layout.as_ref() else {
        return;
    };
    buffers
        .boundary
        .resize_with(layout.parts.len(), Default::default);
    let outs = carve(out, layout.parts.iter().map(|p| p.exclusive.clone()));
    let items: Vec<_> = (layout.parts.iter().zip(outs))
        .zip(buffers.boundary.iter_mut())
        .collect();
    threads.map_items(pool, items, |((part, out), boundary)| {
        let boundary = &mut boundary.0;
        boundary.clear();
        let base = part.exclusive.start;
        if let Some(init) = init {
            init(base, out);
        }
        for seg in &part.segments {
            let pairs = &pairs[seg.springs.clone()];
            if seg.inner {
                pass.run(pairs, |i, v| out[i - base] += v);
            } else {
                pass.run(pairs, |i, v| {
                    match i.checked_sub(base).and_then(|j| out.get_mut(j)) {
                        Some(o) => *o += v,
                        None => boundary.push((i as u32, v)),
                    }
                });
            }
        }
    });
    if let Some(init) = init {
        // The particles between the parts' own ranges.
        let mut owned: Vec<Range<usize>> =
            layout.parts.iter().map(|p| p.exclusive.clone()).collect();
        owned.sort_by_key(|r| r.start);
        let mut at = 0;
        for r in owned.iter().chain(std::iter::once(&(out.len()..out.len()))) {
            if r.start > at {
                init(at, &mut out[at..r.start]);
            }
            at = at.max(r.end);
        }
    }
    for boundary in &buffers.boundary {
        for &(i, v) in &boundary.0 {
            out[i as usize] += v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::fixtures::{grid, tangle};

    /// Every part's segments cover its chunk in order, inner segments keep both ends in the
    /// part's exclusive range, and the exclusive ranges do not overlap.
    #[test]
    fn parts_cover_the_springs_and_own_disjoint_particles() {
        for (n, springs) in [(160 * 160, grid(160, 160)), (5000, tangle(5000, 30_000))] {
            for threads in [2, 3, 4] {
                let layout = Layout::new(&springs, threads);
                let mut next = 0;
                for part in &layout.parts {
                    for seg in &part.segments {
                        assert_eq!(seg.springs.start, next);
                        next = seg.springs.end;
                        if seg.inner {
                            assert!(seg.springs.len() >= MIN_INNER_SEGMENT);
                            assert!(springs[seg.springs.clone()].iter().all(|s| {
                                part.exclusive.contains(&(s.a as usize))
                                    && part.exclusive.contains(&(s.b as usize))
                            }));
                        }
                    }
                }
                assert_eq!(next, springs.len());
                let mut ranges: Vec<_> = layout.parts.iter().map(|p| p.exclusive.clone()).collect();
                ranges.sort_by_key(|r| r.start);
                assert!(ranges.windows(2).all(|w| w[0].end <= w[1].start));
                assert!(ranges.last().is_some_and(|r| r.end <= n as usize));
            }
        }
        // A cloth's parts run almost all their springs through the plain kernel.
        let springs = grid(160, 160);
        let layout = Layout::new(&springs, 2);
        let inner: usize = (layout.parts.iter().flat_map(|p| &p.segments))
            .filter(|s| s.inner)
            .map(|s| s.springs.len())
            .sum();
        assert!(
            inner as f64 > 0.97 * springs.len() as f64,
            "{inner} of {}",
            springs.len()
        );
    }
}
