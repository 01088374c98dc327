//! Threads for the step's kernels.
//!
//! Pair passes (the spring forces, implicit Euler's K u) evaluate each spring once and scatter
//! without atomics: the packed springs are split into one contiguous part per thread; a part
//! writes its own slice of the output, the particles no other part touches, and records its
//! contributions to the rest, which are added after (see [`scatter_from`]). Per-particle passes
//! split the particle arrays into chunks ([`Threads::chunked`]). Inside [`Threads::run`] (the
//! tick's step loop) the passes fork to the pool's threads held ready ([`Crew`]), elsewhere
//! through rayon, cutting and combining their work the same way. Small scenes run serially:
//! below [`PARALLEL_MIN_SPRINGS`] sharing the work costs more than it saves.

use super::crew::Crew;
use super::kernels;
use super::state::PackedSpring;
use super::team::{Barrier, Team};
use glam::DVec2;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::{Arc, Mutex};

/// Scenes with fewer springs than this step on one thread (10,100 springs gained nothing from a
/// second thread, 16,002 gained 1.44x).
pub const PARALLEL_MIN_SPRINGS: usize = 12_000;
/// Particle passes split into chunks of at least this many particles.
const PARTICLE_CHUNK: usize = 8192;

/// The most solver threads a pool may have. The passes hand work to every thread and wait for
/// all of them, so threads beyond the cores only wait on each other (on a 2-core machine, 64
/// threads stepped the 256² cloth 5× slower than 2), and starting them is not free either:
/// 4,000 took 7.6 s to start and a 100,000-thread request ran for over a minute without
/// stepping.
pub const MAX_THREADS: usize = 256;

/// The kernels' thread pool. `threads == 1` runs everything on the calling thread.
///
/// ```
/// # use hooke::solver::{MAX_THREADS, Threads};
/// let two = Threads::new(2).unwrap();
/// assert_eq!(two.threads(), 2);
/// assert!(Threads::new(0).is_err());
/// assert!(Threads::new(MAX_THREADS + 1).is_err());
/// ```
#[derive(Clone)]
pub struct Threads {
    threads: usize,
    pool: Option<Arc<rayon::ThreadPool>>,
    /// Taken while a [`Threads::run`] holds the pool, shared by the clones: one run at a time
    /// holds a pool (two crews on one pool's threads would wait on each other).
    holder: Arc<Mutex<()>>,
}

impl std::fmt::Debug for Threads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Threads({})", self.threads)
    }
}

impl Default for Threads {
    /// All cores.
    fn default() -> Self {
        let n = std::thread::available_parallelism().map_or(1, |n| n.get());
        Self::new(n).unwrap_or_else(|_| Threads {
            threads: 1,
            pool: None,
            holder: Arc::default(),
        })
    }
}

impl Threads {
    /// A pool of `threads` solver threads (1: no pool, everything on the calling thread).
    pub fn new(threads: usize) -> Result<Self, String> {
        if !(1..=MAX_THREADS).contains(&threads) {
            return Err(format!(
                "the thread count must be between 1 and {MAX_THREADS}, got {threads}"
            ));
        }
        let pool = if threads > 1 {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("hooke-solver-{i}"))
                .build()
                .map_err(|e| format!("cannot start {threads} solver threads: {e}"))?;
            Some(Arc::new(pool))
        } else {
            None
        };
        Ok(Threads {
            threads,
            pool,
            holder: Arc::default(),
        })
    }

    /// How many threads the passes use.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Runs `work` on one of the pool's threads when a scene of `springs` springs is worth
    /// sharing (else on the calling thread), with the pool's other threads held ready for it
    /// (a crew, `src/solver/crew.rs`): the parallel passes inside fork to them with two atomic
    /// operations, where a fork through rayon had to wake a sleeping worker. Called on one of
    /// the pool's own threads (inside a held run, or inside a pass), it just runs `work`
    /// there. Runs on one pool from several threads at once (clones of one `Threads` in two
    /// apps) take turns.
    pub fn run<R: Send>(&self, springs: usize, work: impl FnOnce() -> R + Send) -> R {
        match self.pool_for(springs) {
            Some(pool) if pool.current_thread_index().is_none() => {
                // A panic in an earlier run leaves nothing behind the lock to mend.
                let _turn = self.holder.lock().unwrap_or_else(|e| e.into_inner());
                Crew::hold(pool, self.key(), work)
            }
            _ => work(),
        }
    }

    /// Runs `a` and `b` at once on the pool if there is one and the caller says the work is
    /// worth `sharing`, else one after the other.
    pub fn join<A: Send, B: Send>(
        &self,
        sharing: bool,
        a: impl FnOnce() -> A + Send,
        b: impl FnOnce() -> B + Send,
    ) -> (A, B) {
        let Some(pool) = self.pool.as_deref().filter(|_| sharing) else {
            return (a(), b());
        };
        self.crew(|crew| match crew {
            Some(crew) if crew.size() >= 2 => {
                let (a, b) = (Slot::full(a), Slot::full(b));
                let (ra, rb) = (Slot::empty(), Slot::empty());
                crew.fork(&|i| match i {
                    0 => ra.fill(a.take().map(|a| a())),
                    1 => rb.fill(b.take().map(|b| b())),
                    _ => {}
                });
                let done = "both members ran";
                (ra.into_inner().expect(done), rb.into_inner().expect(done))
            }
            _ => pool.install(|| rayon::join(a, b)),
        })
    }

    /// Runs `work` on every thread of the pool at once, as one [`Team`] whose members meet at
    /// [`Team::wait`], when a scene of `springs` springs is worth sharing; else once, on the
    /// calling thread, as a team of one. For a step made of many passes too short to pay for a
    /// fork and a join each (XPBD's colours).
    pub(crate) fn team(&self, springs: usize, work: impl Fn(&Team) + Sync) {
        let Some(pool) = self.pool_for(springs) else {
            return work(&Team::member(0, 1, &Barrier::new(1)));
        };
        self.crew(|crew| match crew {
            Some(crew) => {
                let barrier = Barrier::new(crew.size());
                crew.fork(&|i| {
                    let _poison = barrier.guard();
                    work(&Team::member(i, crew.size(), &barrier));
                });
            }
            None => {
                let barrier = Barrier::new(pool.current_num_threads());
                pool.broadcast(|ctx| {
                    let _poison = barrier.guard();
                    work(&Team::member(ctx.index(), ctx.num_threads(), &barrier));
                });
            }
        })
    }

    /// `f` of each of `items`, in order, run on the pool's threads: item i on member i mod
    /// threads when the pool is held ([`Threads::run`]), else as rayon schedules them.
    fn map_items<T: Send, R: Send>(
        &self,
        pool: &rayon::ThreadPool,
        items: Vec<T>,
        f: impl Fn(T) -> R + Sync,
    ) -> Vec<R> {
        self.crew(|crew| match crew {
            Some(crew) => {
                let items: Vec<Slot<T>> = items.into_iter().map(Slot::full).collect();
                let results: Vec<Slot<R>> = items.iter().map(|_| Slot::empty()).collect();
                crew.fork(&|i| {
                    let mine = items.iter().zip(&results).skip(i);
                    for (item, out) in mine.step_by(crew.size()) {
                        out.fill(item.take().map(&f));
                    }
                });
                let ran = "every member ran its items";
                results
                    .into_iter()
                    .map(|r| r.into_inner().expect(ran))
                    .collect()
            }
            None => pool.install(|| items.into_par_iter().map(&f).collect()),
        })
    }

    /// This pool's crew, when this thread holds it and is free to fork ([`Crew`]).
    fn crew<R>(&self, f: impl FnOnce(Option<&Crew>) -> R) -> R {
        Crew::with_current(self.key(), f)
    }

    /// What identifies this pool to a [`Crew`]: its address (0 without a pool).
    fn key(&self) -> usize {
        self.pool.as_ref().map_or(0, |p| Arc::as_ptr(p) as usize)
    }

    /// The pool, when the work is big enough to share.
    fn pool_for(&self, springs: usize) -> Option<&rayon::ThreadPool> {
        self.pool
            .as_deref()
            .filter(|_| springs >= PARALLEL_MIN_SPRINGS)
    }

    /// Runs `pass` over `data` (particle arrays of equal length, see `Split`), in chunks on
    /// the pool when a scene of `springs` springs is worth sharing, and combines the chunks'
    /// results with `join`; else runs it once over everything.
    pub fn chunked<S: Split, R: Send>(
        &self,
        springs: usize,
        data: S,
        pass: impl Fn(S) -> R + Sync,
        join: impl Fn(R, R) -> R + Sync,
    ) -> R {
        let n = data.len();
        match self.pool_for(springs) {
            Some(pool) if n >= 2 * PARTICLE_CHUNK => {
                let chunk = n.div_ceil(self.threads).max(PARTICLE_CHUNK);
                let mut pieces = Vec::new();
                halve(data, chunk, &mut pieces);
                let results = self.map_items(pool, pieces, &pass);
                combine(n, chunk, &mut results.into_iter(), &join)
            }
            _ => pass(data),
        }
    }

    /// [`Self::chunked`] for passes without a result.
    pub fn each<S: Split>(&self, springs: usize, data: S, pass: impl Fn(S) + Sync) {
        self.chunked(springs, data, pass, |(), ()| ());
    }
}

/// `data` halved until its pieces are at most `chunk` long, the pieces in order.
fn halve<S: Split>(data: S, chunk: usize, pieces: &mut Vec<S>) {
    if data.len() <= chunk {
        pieces.push(data);
        return;
    }
    let mid = data.len().div_ceil(2);
    let (left, right) = data.split_at(mid);
    halve(left, chunk, pieces);
    halve(right, chunk, pieces);
}

/// The results of the pieces [`halve`] cut `n` elements into, joined pair by pair as the
/// halving cut them: the same tree, so the same bits, whoever ran the pieces.
fn combine<R>(
    n: usize,
    chunk: usize,
    results: &mut impl Iterator<Item = R>,
    join: &impl Fn(R, R) -> R,
) -> R {
    if n <= chunk {
        return results.next().expect("a result for every piece");
    }
    let mid = n.div_ceil(2);
    let l = combine(mid, chunk, results, join);
    let r = combine(n - mid, chunk, results, join);
    join(l, r)
}

/// A value handed to a crew member or back: filled once, taken once. (A panic elsewhere does
/// not make the value in it wrong, so a poisoned lock is ignored.)
struct Slot<T>(Mutex<Option<T>>);

impl<T> Slot<T> {
    fn full(value: T) -> Self {
        Slot(Mutex::new(Some(value)))
    }

    fn empty() -> Self {
        Slot(Mutex::new(None))
    }

    fn fill(&self, value: Option<T>) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = value;
    }

    fn take(&self) -> Option<T> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    fn into_inner(self) -> Option<T> {
        self.0.into_inner().unwrap_or_else(|e| e.into_inner())
    }
}

/// Particle arrays cut at the same index: a slice, or a tuple of slices of equal length.
pub trait Split: Send + Sized {
    fn len(&self) -> usize;
    fn split_at(self, mid: usize) -> (Self, Self);
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<T: Sync> Split for &[T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        <[T]>::split_at(self, mid)
    }
}

impl<T: Send> Split for &mut [T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

macro_rules! split_tuple {
    ($($t:ident $v:ident $l:ident $r:ident),+) => {
        impl<$($t: Split),+> Split for ($($t,)+) {
            fn len(&self) -> usize {
                let ($($v,)+) = self;
                let lens = [$($v.len()),+];
                debug_assert!(lens.iter().all(|&l| l == lens[0]), "arrays of unequal length");
                lens[0]
            }
            fn split_at(self, mid: usize) -> (Self, Self) {
                let ($($v,)+) = self;
                $(let ($l, $r) = $v.split_at(mid);)+
                (($($l,)+), ($($r,)+))
            }
        }
    };
}
split_tuple!(A a la ra, B b lb rb);
split_tuple!(A a la ra, B b lb rb, C c lc rc);
split_tuple!(A a la ra, B b lb rb, C c lc rc, D d ld rd);
split_tuple!(A a la ra, B b lb rb, C c lc rc, D d ld rd, E e le re);
split_tuple!(A a la ra, B b lb rb, C c lc rc, D d ld rd, E e le re, F f lf rf);
split_tuple!(A a la ra, B b lb rb, C c lc rc, D d ld rd, E e le re, F f lf rf, G g lg rg);

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
        super::spring::scatter_pairs(
            springs,
            |s| {
                let c = dashpot[i];
                i += 1;
                super::spring::damped_spring_force(s, c, self.x, self.v)
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
        .is_none_or(|l| l.springs != pairs.len() || l.threads != threads.threads);
    if stale {
        buffers.layout = Some(Layout::new(pairs, threads.threads));
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
    use crate::solver::bits;

    /// The springs of a row-major `w`×`h` grid, structural and both diagonals, sorted as the
    /// solver packs them.
    fn grid(w: u32, h: u32) -> Vec<PackedSpring> {
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
    fn tangle(n: u32, count: usize) -> Vec<PackedSpring> {
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

    fn positions(n: u32) -> Vec<DVec2> {
        (0..n)
            .map(|i| {
                DVec2::new(
                    (i % 97) as f64 * 0.013,
                    (i / 97) as f64 * 0.011 + (i % 7) as f64 * 1e-3,
                )
            })
            .collect()
    }

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

    /// Chunked passes see matching pieces of every array, cover each element once, and combine
    /// their results; small scenes run in one piece.
    #[test]
    fn chunked_passes_cover_the_arrays_in_matching_pieces() {
        let n = 100_003;
        let src: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let threads = Threads::new(2).unwrap();
        for springs in [PARALLEL_MIN_SPRINGS, 10] {
            let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
            let pieces = threads.chunked(
                springs,
                (&mut a[..], &mut b[..], &src[..]),
                |(a, b, src)| {
                    for i in 0..a.len() {
                        a[i] = src[i] + 1.0;
                        b[i] += 2.0 * src[i];
                    }
                    1
                },
                |x, y| x + y,
            );
            assert!(a.iter().enumerate().all(|(i, &v)| v == i as f64 + 1.0));
            assert!(b.iter().enumerate().all(|(i, &v)| v == 2.0 * i as f64));
            let expected = if springs >= PARALLEL_MIN_SPRINGS {
                2
            } else {
                1
            };
            assert_eq!(pieces, expected, "{springs} springs");
        }
    }

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
                assert!(threads.crew(|c| c.is_some()), "the run holds the pool");
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

    /// Two threads running ticks on clones of one pool at once take turns holding it, and
    /// both finish (two crews on the same threads would wait on each other).
    #[test]
    fn runs_on_one_pool_from_two_threads_take_turns() {
        let threads = Threads::new(2).unwrap();
        let data = vec![1.0f64; 1 << 16];
        let tick = |threads: &Threads| {
            threads.run(usize::MAX, || {
                (0..200)
                    .map(|_| {
                        threads.chunked(
                            usize::MAX,
                            &data[..],
                            |d| d.iter().sum::<f64>(),
                            |a, b| a + b,
                        )
                    })
                    .sum::<f64>()
            })
        };
        let other = threads.clone();
        let (a, b) = std::thread::scope(|s| {
            let a = s.spawn(|| tick(&threads));
            let b = s.spawn(|| tick(&other));
            (a.join().unwrap(), b.join().unwrap())
        });
        assert_eq!((a, b), (200.0 * 65536.0, 200.0 * 65536.0));
    }

    /// K u through the threaded pair scatter gives the serial product up to round-off.
    #[test]
    fn threaded_stiffness_product_matches_the_serial_one() {
        use crate::solver::stiffness;
        let (n, springs) = (160 * 160, grid(160, 160));
        let x = positions(n);
        let mut blocks = vec![];
        stiffness::blocks(&springs, &x, &mut blocks);
        let u: Vec<DVec2> = (0..n)
            .map(|i| DVec2::new((i % 13) as f64, -((i % 7) as f64)))
            .collect();
        let mut serial = vec![DVec2::ZERO; n as usize];
        stiffness::apply(&mut serial, &u, &blocks);
        let threads = Threads::new(2).unwrap();
        let (mut buffers, mut threaded_blocks) = (SpringBuffers::default(), vec![]);
        stiffness::blocks_threaded(&threads, &springs, &x, &mut threaded_blocks);
        assert_eq!(threaded_blocks, blocks);
        let mut threaded = vec![DVec2::splat(f64::NAN); n as usize]; // overwritten, not added to
        stiffness::apply_threaded(&threads, &mut buffers, &mut threaded, &u, &blocks);
        assert_round_off(&serial, &threaded, "K u, 2 threads");
    }

    /// Each element of `threaded` within 1e-12 of the largest of `serial` from its own.
    fn assert_round_off(serial: &[DVec2], threaded: &[DVec2], what: &str) {
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
