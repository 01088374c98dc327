//! Threads for the step's kernels.
//!
//! The spring pass evaluates each spring once and scatters without atomics: the packed springs
//! are split into one contiguous chunk per thread; a thread writes f directly for the particles
//! no other chunk touches and records the rest, which are added after (see
//! [`accumulate_spring_forces`]).
//! Per-particle passes split the particle arrays into chunks. Small scenes run serially: below
//! [`PARALLEL_MIN_SPRINGS`] the cost of waking a thread exceeds the work.

use super::kernels;
use super::solver::PackedSpring;
use bevy::math::DVec2;
use bevy::prelude::*;
use rayon::prelude::*;
use std::sync::Arc;

/// Scenes with fewer springs than this step on one thread.
pub const PARALLEL_MIN_SPRINGS: usize = 20_000;
/// Particle passes split into chunks of at least this many particles.
const PARTICLE_CHUNK: usize = 8192;

/// The kernels' thread pool. `threads == 1` runs everything on the calling thread.
#[derive(Resource, Clone)]
pub struct SolverThreads {
    threads: usize,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl std::fmt::Debug for SolverThreads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SolverThreads({})", self.threads)
    }
}

impl Default for SolverThreads {
    /// All cores.
    fn default() -> Self {
        let n = std::thread::available_parallelism().map_or(1, |n| n.get());
        Self::new(n).unwrap_or_else(|_| SolverThreads {
            threads: 1,
            pool: None,
        })
    }
}

impl SolverThreads {
    pub fn new(threads: usize) -> Result<Self, String> {
        if threads == 0 {
            return Err("the thread count must be at least 1".into());
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
        Ok(SolverThreads { threads, pool })
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    /// The pool, when the work is big enough to share.
    fn pool_for(&self, springs: usize) -> Option<&rayon::ThreadPool> {
        self.pool
            .as_deref()
            .filter(|_| springs >= PARALLEL_MIN_SPRINGS)
    }

    /// The pool and a chunk length for the particle passes of a scene of `n` particles and
    /// `springs` springs, when it is worth sharing.
    pub fn chunking(&self, springs: usize, n: usize) -> Option<(&rayon::ThreadPool, usize)> {
        let pool = self.pool_for(springs)?;
        (n >= 2 * PARTICLE_CHUNK).then(|| (pool, n.div_ceil(self.threads).max(PARTICLE_CHUNK)))
    }
}

/// How the spring pass splits its work, cached until the springs or the thread count change.
#[derive(Debug, Clone, PartialEq)]
struct Layout {
    springs: usize,
    threads: usize,
    chunk: usize,
    /// Per chunk, the half-open particle range that no other chunk touches.
    exclusive: Vec<(usize, usize)>,
}

impl Layout {
    fn new(springs: &[PackedSpring], threads: usize) -> Layout {
        let chunk = springs.len().div_ceil(threads).max(1);
        let touched: Vec<(usize, usize)> = springs
            .chunks(chunk)
            .map(|c| {
                c.iter().fold((usize::MAX, 0), |(lo, hi), s| {
                    let (a, b) = (s.a as usize, s.b as usize);
                    (lo.min(a).min(b), hi.max(a + 1).max(b + 1))
                })
            })
            .collect();
        let exclusive = touched
            .iter()
            .enumerate()
            .map(|(t, &(mut lo, mut hi))| {
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
                (lo, hi.max(lo))
            })
            .collect();
        Layout {
            springs: springs.len(),
            threads,
            chunk,
            exclusive,
        }
    }
}

/// The spring pass's per-thread state, reused from step to step.
#[derive(Debug, Default, Clone)]
pub struct SpringBuffers {
    layout: Option<Layout>,
    /// Per chunk, the forces on particles outside its exclusive range, applied after.
    boundary: Vec<Vec<(u32, DVec2)>>,
}

/// The force array, shared by the threads of the spring pass, each of which writes only the
/// particles of its own exclusive range.
struct SharedForces(*mut DVec2);
// SAFETY: the spring pass hands each thread a disjoint range of indices to write through this
// pointer; nothing else touches the array until the pass returns.
unsafe impl Send for SharedForces {}
unsafe impl Sync for SharedForces {}

impl SharedForces {
    /// Adds `v` to element `i`.
    ///
    /// # Safety
    /// `i` is in bounds and in the calling thread's exclusive range.
    unsafe fn add(&self, i: usize, v: DVec2) {
        // SAFETY: guaranteed by the caller.
        unsafe { *self.0.add(i) += v };
    }
}

/// f += Σ spring forces, each spring evaluated once, on the pool's threads when worthwhile.
///
/// The springs are split into one contiguous chunk per thread. A thread adds its forces
/// straight into f for the particles no other chunk touches (for a row-major cloth, all but
/// about one row at each end of its chunk) and records the others; the recorded forces are
/// added after the parallel part. No atomics and no full-size buffers: one parallel region.
pub fn accumulate_spring_forces(
    threads: &SolverThreads,
    buffers: &mut SpringBuffers,
    f: &mut [DVec2],
    x: &[DVec2],
    springs: &[PackedSpring],
) {
    let Some(pool) = threads.pool_for(springs.len()) else {
        kernels::accumulate_spring_forces(f, x, springs);
        return;
    };
    let stale = buffers
        .layout
        .as_ref()
        .is_none_or(|l| l.springs != springs.len() || l.threads != threads.threads);
    if stale {
        buffers.layout = Some(Layout::new(springs, threads.threads));
    }
    let Some(layout) = buffers.layout.as_ref() else {
        return;
    };
    buffers
        .boundary
        .resize_with(layout.exclusive.len(), Vec::new);
    let n = f.len();
    let out = SharedForces(f.as_mut_ptr());
    pool.install(|| {
        springs
            .par_chunks(layout.chunk)
            .zip(layout.exclusive.par_iter())
            .zip(buffers.boundary.par_iter_mut())
            .for_each(|((chunk, &(lo, hi)), boundary)| {
                boundary.clear();
                let add = |i: usize, v: DVec2| {
                    if i >= lo && i < hi && i < n {
                        // SAFETY: i < n, and [lo, hi) is this chunk's exclusive range: no other
                        // thread writes or reads f[i] during this pass.
                        unsafe { out.add(i, v) };
                    } else {
                        boundary.push((i as u32, v));
                    }
                };
                kernels::for_each_spring_force(x, chunk, add);
            });
    });
    for boundary in &buffers.boundary {
        for &(i, v) in boundary {
            f[i as usize] += v;
        }
    }
}
