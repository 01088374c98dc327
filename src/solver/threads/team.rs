//! The pool's threads as one team: every thread runs the same work at once and they meet at
//! barriers, instead of a fork and a join per pass.
//!
//! XPBD sweeps its constraints colour by colour, and each colour must see the last one's
//! positions: at 64² that is 80 passes a step of 2,000 constraints each, a few microseconds of
//! work apiece, where a fork and a join cost about as much as the work. A team forks once a
//! step and meets at a spinning barrier (a few hundred nanoseconds) after each pass.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// One member of a team: which one, of how many, and the barrier they share.
pub struct Team<'a> {
    index: usize,
    size: usize,
    barrier: &'a Barrier,
}

impl<'a> Team<'a> {
    /// Member `index` of `size`.
    pub(super) fn member(index: usize, size: usize, barrier: &'a Barrier) -> Self {
        debug_assert!(index < size && size == barrier.size);
        Team {
            index,
            size,
            barrier,
        }
    }

    /// Which member this is, from 0, and how many the team has.
    pub fn index(&self) -> usize {
        self.index
    }
    pub fn size(&self) -> usize {
        self.size
    }

    /// This member's contiguous share of `range`: the members' shares cover it in order,
    /// each within one of the others' lengths.
    pub fn share(&self, range: Range<usize>) -> Range<usize> {
        let n = range.len();
        let at = |k: usize| range.start + n * k / self.size;
        at(self.index)..at(self.index + 1)
    }

    /// Waits until every member has arrived here; what each wrote before it is then visible
    /// to all. If a member panicked, the others panic here instead of waiting for it forever.
    pub fn wait(&self) {
        self.barrier.wait();
    }
}

/// A barrier for the members of one team that spins (the members run on cores of their
/// own; a sleeping wait costs a wake-up of tens of microseconds) and yields the core after a
/// while, in case a member's core was taken by something else.
pub(super) struct Barrier {
    size: usize,
    arrived: AtomicUsize,
    /// Bumped by the last member to arrive, which releases the others.
    generation: AtomicUsize,
    poisoned: AtomicBool,
}

/// Spins before a waiting member starts to yield its core.
const SPINS_BEFORE_YIELDING: u32 = 4096;

impl Barrier {
    pub(super) fn new(size: usize) -> Self {
        Barrier {
            size,
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            poisoned: AtomicBool::new(false),
        }
    }

    fn wait(&self) {
        if self.size == 1 {
            return;
        }
        let generation = self.generation.load(Ordering::Acquire);
        // AcqRel: the last to arrive acquires every member's writes before the barrier, and
        // its release of the generation hands them on to the members it wakes.
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.size {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::AcqRel);
            return;
        }
        let mut spins = 0u32;
        while self.generation.load(Ordering::Acquire) == generation {
            assert!(
                !self.poisoned.load(Ordering::Relaxed),
                "another member of the team panicked"
            );
            if spins < SPINS_BEFORE_YIELDING {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }

    /// Marks the barrier poisoned if dropped while its member unwinds (see [`Team::wait`]).
    pub(super) fn guard(&self) -> PoisonOnPanic<'_> {
        PoisonOnPanic(self)
    }
}

/// See [`Barrier::guard`].
pub(super) struct PoisonOnPanic<'a>(&'a Barrier);

impl Drop for PoisonOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.poisoned.store(true, Ordering::Relaxed);
        }
    }
}

/// A slice the members of a team write in disjoint parts. The pass that uses it says why its
/// parts are disjoint.
#[derive(Clone, Copy)]
pub struct Shared<T> {
    ptr: *mut T,
    len: usize,
}

// SAFETY: the members access disjoint elements between barriers (the users' obligation, stated
// on `part`); `T: Send` is what moving access to those elements between threads needs.
unsafe impl<T: Send> Send for Shared<T> {}
// SAFETY: as above.
unsafe impl<T: Send> Sync for Shared<T> {}

impl<T> Shared<T> {
    /// Shares `slice` for as long as the borrow lasts.
    pub fn new(slice: &mut [T]) -> Self {
        Shared {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
        }
    }

    /// Element `i`.
    ///
    /// # Safety
    /// As for [`Shared::part`], for the one element `i` (in bounds: checked in debug builds
    /// only, for the hot loops that read elements one by one).
    #[inline(always)]
    pub unsafe fn get(&self, i: usize) -> T
    where
        T: Copy,
    {
        debug_assert!(i < self.len);
        // SAFETY: in bounds and unshared by the caller's promise.
        unsafe { *self.ptr.add(i) }
    }

    /// Writes element `i`.
    ///
    /// # Safety
    /// As for [`Shared::get`].
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, value: T) {
        debug_assert!(i < self.len);
        // SAFETY: as above.
        unsafe { *self.ptr.add(i) = value }
    }

    /// The whole slice, to read.
    ///
    /// # Safety
    /// No member writes any of it while the borrow lasts (between two barriers).
    pub unsafe fn read(&self) -> &[T] {
        // SAFETY: unwritten by the caller's promise.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }

    /// Where element `i` is, for a store of its own kind (a vector store of a point).
    ///
    /// # Safety
    /// As for [`Shared::get`].
    #[inline(always)]
    pub unsafe fn ptr(&self, i: usize) -> *mut T {
        debug_assert!(i < self.len);
        // SAFETY: as above.
        unsafe { self.ptr.add(i) }
    }

    /// The elements in `range`.
    ///
    /// # Safety
    /// The slice this was made from must still be borrowed for it, and until the next barrier
    /// no other member may touch the elements of `range`.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn part(&self, range: Range<usize>) -> &mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (asserted), and unshared by the caller's promise.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::threads::Threads;

    /// The shares of any range cover it in order, without overlap, for teams of 1 to 5.
    #[test]
    fn shares_cover_the_range() {
        for size in 1..=5 {
            let barrier = Barrier::new(size);
            for range in [0..0, 3..4, 7..107, 10..13] {
                let mut next = range.start;
                for index in 0..size {
                    let share = Team::member(index, size, &barrier).share(range.clone());
                    assert_eq!(share.start, next);
                    next = share.end;
                }
                assert_eq!(next, range.end);
            }
        }
    }

    /// Two members meet at the barrier: each round, each reads what the other wrote before
    /// it, a thousand rounds in a row.
    #[test]
    fn members_see_each_others_writes_after_the_barrier() {
        let threads = Threads::new(2).unwrap();
        let mut cells = vec![0u64; 2];
        let shared = Shared::new(&mut cells);
        let seen = AtomicUsize::new(0);
        threads.team(usize::MAX, |team| {
            assert_eq!(team.share(0..2).len(), 1, "a team of two");
            let me = team.share(0..2).start;
            let other = 1 - me;
            for round in 1..=1000u64 {
                // SAFETY: each member writes its own cell, then reads the other's only
                // after a barrier, and before the next write.
                unsafe { shared.part(me..me + 1)[0] = round };
                team.wait();
                let theirs = unsafe { shared.part(other..other + 1)[0] };
                assert_eq!(theirs, round);
                team.wait();
            }
            seen.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(seen.into_inner(), 2, "both members ran");
    }
}

/// What a barrier and a team's start cost here, printed beside the machine:
/// `cargo test --release --lib what_a_team_costs -- --ignored --nocapture`.
#[cfg(test)]
mod measurement {
    use crate::solver::threads::Threads;
    use std::time::Instant;

    #[test]
    #[ignore = "a measurement: prints figures, asserts nothing"]
    fn what_a_team_costs() {
        let threads = Threads::new(2).unwrap();
        println!("on {}", crate::solver::threads::machine());
        for _ in 0..3 {
            let clock = Instant::now();
            threads.team(usize::MAX, |team| (0..100_000).for_each(|_| team.wait()));
            let barrier = clock.elapsed().as_secs_f64() / 1e5;
            let clock = Instant::now();
            (0..1000).for_each(|_| threads.team(usize::MAX, |_| {}));
            let start = clock.elapsed().as_secs_f64() / 1e3;
            println!(
                "two threads: a barrier {:.0} ns, a team started and ended from outside the \
                 pool {:.1} µs",
                barrier * 1e9,
                start * 1e6
            );
        }
    }
}
