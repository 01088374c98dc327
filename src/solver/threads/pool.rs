//! The kernels' thread pool ([`Threads`]) and its per-particle passes.
//!
//! Per-particle passes split the particle arrays into chunks ([`Threads::chunked`]). Inside
//! [`Threads::run`] (the tick's step loop) the passes fork to the pool's threads held ready
//! ([`Crew`]), elsewhere through rayon, cutting and combining their work the same way. Small
//! scenes run serially: below [`PARALLEL_MIN_SPRINGS`] sharing the work costs more than it
//! saves. The pair passes' split of the springs is [`super::scatter`]'s.

use super::crew::Crew;
use super::team::{Barrier, Team};
use rayon::prelude::*;
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
        Self::new(n).unwrap_or_else(|_| Threads::serial())
    }
}

impl Threads {
    /// One thread: everything on the calling thread.
    pub fn serial() -> Self {
        Threads {
            threads: 1,
            pool: None,
            holder: Arc::default(),
        }
    }

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
    pub(crate) fn map_items<T: Send, R: Send>(
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

    /// `f(first, block)` of each block of `block` items of `data` (`first`: the block's index in
    /// `data`), in order: on the pool's threads when a scene of `springs` springs is worth
    /// sharing, else on this one. The blocks are the same whatever the thread count, so a sum of
    /// the results taken in order has the same bits on one thread or many.
    pub(crate) fn blocks<T: Sync, R: Send>(
        &self,
        springs: usize,
        data: &[T],
        block: usize,
        f: impl Fn(usize, &[T]) -> R + Sync,
    ) -> Vec<R> {
        let block = block.max(1);
        let blocks: Vec<(usize, &[T])> = data.chunks(block).enumerate().collect();
        let f = |(i, b): (usize, &[T])| f(i * block, b);
        match self.pool_for(springs) {
            Some(pool) if blocks.len() > 1 => self.map_items(pool, blocks, f),
            _ => blocks.into_iter().map(f).collect(),
        }
    }

    /// Whether this thread holds this pool's crew (inside [`Self::run`]), for the tests that
    /// compare the held passes with rayon's.
    #[cfg(test)]
    pub(crate) fn holds_crew(&self) -> bool {
        self.crew(|c| c.is_some())
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
    pub(crate) fn pool_for(&self, springs: usize) -> Option<&rayon::ThreadPool> {
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
        self.chunked_by(PARTICLE_CHUNK, springs, data, pass, join)
    }

    /// [`Self::chunked`] in chunks of at least `least` items: for passes whose items each
    /// carry many particles' work (the pair contact's particles, each with its neighbour list).
    pub(crate) fn chunked_by<S: Split, R: Send>(
        &self,
        least: usize,
        springs: usize,
        data: S,
        pass: impl Fn(S) -> R + Sync,
        join: impl Fn(R, R) -> R + Sync,
    ) -> R {
        let n = data.len();
        match self.pool_for(springs) {
            Some(pool) if n >= 2 * least => {
                let chunk = n.div_ceil(self.threads).max(least);
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

/// The particles' indices, cut with their arrays: a pass that must name a particle by its
/// index in the whole state (to note it) reads it from here.
impl Split for std::ops::Range<usize> {
    fn len(&self) -> usize {
        self.end - self.start
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let cut = self.start + mid;
        (self.start..cut, cut..self.end)
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
