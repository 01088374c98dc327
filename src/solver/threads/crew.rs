//! The pool's threads held ready for the length of a tick, so that a pass forks to them with
//! two atomic operations instead of waking rayon's sleeping workers.
//!
//! A step at the app's dt is a few hundred microseconds of work in two to dozens of parallel
//! passes (the forces and the particle sweep; implicit Euler's CG, four or five a CG
//! iteration). Between two passes a rayon worker that has run out of work yields its core a
//! few dozen times and then sleeps; waking it costs tens of microseconds on a VM, and a pass
//! waits for its slowest part. Measured on the 256² cloth at two threads (symplectic Euler,
//! the binaries before and after alternating): about a tenth more spring updates a second.
//!
//! [`Crew::hold`] runs a tick's work on one of the pool's threads (member 0) while the others
//! wait in [`Crew::serve`] on a generation counter. A pass posts itself with [`Crew::fork`]:
//! every member runs it with its own index, and the poster returns once all have. A waiting
//! thread spins for [`SPIN`], the gap between two passes, then yields its core for [`YIELD`],
//! running pending rayon work meanwhile (so that rayon code inside the tick, the
//! factorisation's parallel loops, still finds a second thread), then parks until woken: in
//! the app a software renderer needs the cores the tick is not using.

use std::any::Any;
use std::cell::{Cell, UnsafeCell};
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};
use std::thread::Thread;
use std::time::{Duration, Instant};

/// A job: what each member runs, given its index.
type Job<'a> = &'a (dyn Fn(usize) + Sync);

/// How long a waiting thread spins before it starts yielding its core: about the gap between
/// two passes of a step, so that a pass following another finds the members still spinning.
const SPIN: Duration = Duration::from_micros(2);
/// How long a waiting thread then yields its core (to whatever else wants it: a software
/// renderer's threads, in the app) before it parks until woken. Waiting longer starved the
/// app's renderer and, with it, the tick: the 64² cloth under Xvfb ran at 0.3–0.4× real time
/// with 4096 spins and no parking, a median 0.70× with 500 µs of yielding, 0.92× with 50 µs
/// (through rayon: 0.92×; ten alternating runs each for the last two).
const YIELD: Duration = Duration::from_micros(50);
/// A parked member looks again this often, in case a wake-up was lost to a race.
const PARK: Duration = Duration::from_millis(1);

/// The pool's threads, held for one tick (see the module docs).
pub(super) struct Crew {
    size: usize,
    /// Which pool this crew holds (its address): a pass on another pool does not use it.
    pool: usize,
    /// Bumped by each fork, after `job` is written (SeqCst: see `Crew::park`).
    generation: AtomicUsize,
    /// Members other than 0 that have finished the current job.
    done: AtomicUsize,
    job: UnsafeCell<Option<Job<'static>>>,
    quit: AtomicBool,
    /// Threads parked until the next job or the end of one (see [`YIELD`]), and each
    /// member's thread, to wake.
    parked: AtomicUsize,
    threads: Vec<OnceLock<Thread>>,
    /// The first panic of a member's job, handed to the poster.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

// SAFETY: `job` is written only by member 0, before its (SeqCst, so releasing) bump of
// `generation`, and read by the other members only after their (SeqCst, so acquiring) load
// sees that bump and before they report `done`; member 0 writes it again only after every
// member has reported. The job itself is `Sync`. Everything else is atomic or behind a mutex.
unsafe impl Sync for Crew {}

thread_local! {
    /// The crew whose member 0 runs on this thread, while it is free to fork.
    static CURRENT: Cell<*const Crew> = const { Cell::new(std::ptr::null()) };
}

impl Crew {
    /// Runs `work` on one of `pool`'s threads with the others held ready: passes inside it
    /// fork through [`Crew::with_current`] instead of rayon. `key` identifies the pool.
    pub(super) fn hold<R: Send>(
        pool: &rayon::ThreadPool,
        key: usize,
        work: impl FnOnce() -> R + Send,
    ) -> R {
        let size = pool.current_num_threads();
        let crew = Crew {
            size,
            pool: key,
            generation: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            job: UnsafeCell::new(None),
            quit: AtomicBool::new(false),
            parked: AtomicUsize::new(0),
            threads: (0..size).map(|_| OnceLock::new()).collect(),
            panic: Mutex::new(None),
        };
        let work = Mutex::new(Some(work));
        let result = Mutex::new(None);
        pool.broadcast(|ctx| {
            let _ = crew.threads[ctx.index()].set(std::thread::current());
            if ctx.index() != 0 {
                crew.serve(ctx.index());
                return;
            }
            // The members are released however member 0's work ends, a panic included.
            let _release = Release(&crew);
            let _current = Current::set(&crew);
            let work = work.lock().ok().and_then(|mut w| w.take());
            if let Some(work) = work {
                *result.lock().unwrap_or_else(|e| e.into_inner()) = Some(work());
            }
        });
        let result = result.into_inner().unwrap_or_else(|e| e.into_inner());
        result.expect("member 0 ran the work")
    }

    /// The crew held on this thread for the pool `key`, free to fork, if any; `None` inside a
    /// fork's job (a job that forks again runs its passes through rayon instead).
    pub(super) fn with_current<R>(key: usize, f: impl FnOnce(Option<&Crew>) -> R) -> R {
        let crew = CURRENT.with(|c| c.get());
        // SAFETY: `CURRENT` points at a crew only while `hold` keeps it alive on this thread
        // (the `Current` guard clears it before the crew is dropped).
        let crew = unsafe { crew.as_ref() }.filter(|c| c.pool == key);
        f(crew)
    }

    /// How many members run each job.
    pub(super) fn size(&self) -> usize {
        self.size
    }

    /// Runs `job(i)` on every member i at once and returns when all have finished. A panic
    /// in any member's job is raised here, after every member has finished.
    pub(super) fn fork(&self, job: &(dyn Fn(usize) + Sync)) {
        // Forks inside the job go through rayon: the other members are busy with this one.
        let _busy = Current::clear();
        // SAFETY: the lifetime is erased for the members, which run the job only between the
        // generation bump below and their `done` report; `Wait` does not return (nor unwind)
        // before every member has reported, so the job outlives every use.
        let job: Job<'static> = unsafe { std::mem::transmute::<Job<'_>, Job<'static>>(job) };
        // SAFETY: only member 0 writes the job, and no member reads it now (see `Sync`).
        unsafe { *self.job.get() = Some(job) };
        self.done.store(0, Ordering::Relaxed);
        // SeqCst, with the parking member's count and check: either it sees this job or
        // this sees it parked and wakes it.
        self.generation.fetch_add(1, Ordering::SeqCst);
        self.wake();
        let wait = Wait(self);
        job(0);
        drop(wait);
        let panic = self.panic.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(panic) = panic {
            resume_unwind(panic);
        }
    }

    /// Member `index`'s loop: run each job posted, until member 0's work is over.
    fn serve(&self, index: usize) {
        let mut seen = 0;
        loop {
            let posted = || {
                let generation = self.generation.load(Ordering::SeqCst);
                (generation != seen || self.quit.load(Ordering::SeqCst)).then_some(generation)
            };
            let generation = self.wait(posted, true);
            if self.quit.load(Ordering::Acquire) && generation == seen {
                return;
            }
            seen = generation;
            // SAFETY: written before the bump just seen, not rewritten before this member
            // reports `done` (see `Sync`).
            let job = unsafe { *self.job.get() };
            if let Some(job) = job
                && let Err(panic) = catch_unwind(AssertUnwindSafe(|| job(index)))
            {
                let mut first = self.panic.lock().unwrap_or_else(|e| e.into_inner());
                first.get_or_insert(panic);
            }
            self.done.fetch_add(1, Ordering::SeqCst);
            self.wake();
        }
    }

    /// Waits until `ready` has something: spinning, then yielding ([`wait_for`]), then
    /// parked.
    fn wait<T>(&self, ready: impl Fn() -> Option<T>, rayon: bool) -> T {
        wait_for(&ready, rayon).unwrap_or_else(|| self.park(ready))
    }

    /// Parks this thread until `ready` has something. Whoever makes it ready wakes the parked
    /// threads after (SeqCst, with the count and the check here: either this sees it ready,
    /// or that sees this parked).
    fn park<T>(&self, ready: impl Fn() -> Option<T>) -> T {
        loop {
            self.parked.fetch_add(1, Ordering::SeqCst);
            let found = ready();
            if found.is_none() {
                std::thread::park_timeout(PARK);
            }
            self.parked.fetch_sub(1, Ordering::SeqCst);
            if let Some(value) = found.or_else(&ready) {
                return value;
            }
        }
    }

    /// Wakes the parked threads (none, mostly: then this is one load).
    fn wake(&self) {
        if self.parked.load(Ordering::SeqCst) > 0 {
            self.threads
                .iter()
                .filter_map(OnceLock::get)
                .for_each(Thread::unpark);
        }
    }
}

/// Waits for `ready` to give a value: spinning for [`SPIN`], then yielding the core for
/// [`YIELD`] (running pending rayon work first, when `rayon` is set); `None` if it has not
/// come by then.
fn wait_for<T>(ready: impl Fn() -> Option<T>, rayon: bool) -> Option<T> {
    let start = Instant::now();
    let mut polls = 0u32;
    loop {
        if let Some(value) = ready() {
            return Some(value);
        }
        polls = polls.wrapping_add(1);
        if !polls.is_multiple_of(16) {
            std::hint::spin_loop();
            continue;
        }
        let waited = start.elapsed();
        if waited < SPIN {
            continue;
        }
        if waited >= YIELD {
            return None;
        }
        if !(rayon && rayon::yield_now() == Some(rayon::Yield::Executed)) {
            std::thread::yield_now();
        }
    }
}

/// Waits, when dropped, until every member other than 0 has finished the current job: on
/// return from [`Crew::fork`], and while member 0's own part unwinds.
struct Wait<'a>(&'a Crew);

impl Drop for Wait<'_> {
    fn drop(&mut self) {
        let crew = self.0;
        let finished = || (crew.done.load(Ordering::SeqCst) + 1 >= crew.size).then_some(());
        crew.wait(finished, false);
    }
}

/// Tells the members to stop serving, when member 0's work is over.
struct Release<'a>(&'a Crew);

impl Drop for Release<'_> {
    fn drop(&mut self) {
        self.0.quit.store(true, Ordering::SeqCst);
        self.0.wake();
    }
}

/// Sets (or clears) this thread's current crew and restores the previous one when dropped.
struct Current(*const Crew);

impl Current {
    fn set(crew: &Crew) -> Current {
        Current(CURRENT.with(|c| c.replace(crew)))
    }

    fn clear() -> Current {
        Current(CURRENT.with(|c| c.replace(std::ptr::null())))
    }
}

impl Drop for Current {
    fn drop(&mut self) {
        CURRENT.with(|c| c.set(self.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    }

    /// Every member runs every job once, and the poster sees all their writes on return.
    #[test]
    fn every_member_runs_every_job() {
        for n in [1, 2, 3] {
            let pool = pool(n);
            let total = Crew::hold(&pool, 7, || {
                Crew::with_current(7, |crew| {
                    let crew = crew.expect("held");
                    assert_eq!(crew.size(), n);
                    let runs: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(0)).collect();
                    for _ in 0..1000 {
                        crew.fork(&|i| {
                            runs[i].fetch_add(1, Ordering::Relaxed);
                        });
                    }
                    runs.iter()
                        .map(|r| r.load(Ordering::Relaxed))
                        .sum::<usize>()
                })
            });
            assert_eq!(total, 1000 * n);
        }
    }

    /// Inside a job, and for another pool's key, there is no crew to fork to.
    #[test]
    fn no_crew_inside_a_job_or_for_another_pool() {
        let pool = pool(2);
        Crew::hold(&pool, 1, || {
            assert!(Crew::with_current(2, |c| c.is_none()));
            Crew::with_current(1, |crew| {
                crew.expect("held")
                    .fork(&|_| assert!(Crew::with_current(1, |c| c.is_none())));
            });
            assert!(Crew::with_current(1, |c| c.is_some()));
        });
        assert!(Crew::with_current(1, |c| c.is_none()));
    }

    /// A panic in a member's job reaches the poster after every member has finished, and the
    /// crew is released: `hold` returns by unwinding instead of hanging.
    #[test]
    fn a_panicking_member_unwinds_the_poster() {
        let pool = pool(2);
        let finished = AtomicUsize::new(0);
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            Crew::hold(&pool, 1, || {
                Crew::with_current(1, |crew| {
                    crew.expect("held").fork(&|i| {
                        if i == 1 {
                            panic!("member 1 fails");
                        }
                        finished.fetch_add(1, Ordering::Relaxed);
                    })
                })
            })
        }));
        assert!(outcome.is_err());
        assert_eq!(finished.load(Ordering::Relaxed), 1);
        // The pool still works.
        assert_eq!(pool.install(|| 1 + 1), 2);
    }

    /// Rayon work started inside the tick runs to completion (the waiting members take part).
    #[test]
    fn rayon_work_inside_the_tick_completes() {
        use rayon::prelude::*;
        let pool = pool(2);
        let sum = Crew::hold(&pool, 1, || (0..100_000u64).into_par_iter().sum::<u64>());
        assert_eq!(sum, 100_000 * 99_999 / 2);
    }
}
