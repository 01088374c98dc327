//! Threads for the step's kernels.
//!
//! The spring pass evaluates each spring once and scatters without atomics: the packed springs
//! are split into one contiguous chunk per thread, each thread accumulates its chunk's forces
//! into a private buffer covering only the particle-index range that chunk touches (for a
//! row-major cloth, about N/T plus one row), and a parallel pass then adds the buffers into f.
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

/// Per-thread force buffers of the spring pass, reused from step to step.
#[derive(Debug, Default, Clone)]
pub struct SpringBuffers {
    /// (first particle index covered, forces)
    parts: Vec<(usize, Vec<DVec2>)>,
}

/// f += Σ spring forces, on the pool's threads when worthwhile.
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
    let chunk = springs.len().div_ceil(threads.threads);
    let chunks: Vec<&[PackedSpring]> = springs.chunks(chunk).collect();
    buffers.parts.resize_with(chunks.len(), Default::default);
    pool.install(|| {
        buffers
            .parts
            .par_iter_mut()
            .zip(chunks.par_iter())
            .for_each(|((first, buf), chunk)| {
                let (lo, hi) = chunk.iter().fold((usize::MAX, 0), |(lo, hi), s| {
                    let (a, b) = (s.a as usize, s.b as usize);
                    (lo.min(a).min(b), hi.max(a).max(b))
                });
                *first = lo;
                buf.clear();
                buf.resize(hi + 1 - lo, DVec2::ZERO);
                for s in *chunk {
                    let (a, b) = (s.a as usize - lo, s.b as usize - lo);
                    let d = x[s.a as usize] - x[s.b as usize];
                    let l = d.length();
                    if l < kernels::MIN_SPRING_LENGTH {
                        continue;
                    }
                    let fa = d * (-s.k * (l - s.rest) / l);
                    buf[a] += fa;
                    buf[b] -= fa;
                }
            });
    });
    // Add the buffers into f, particle chunk by particle chunk (disjoint writes).
    let parts = &buffers.parts;
    let n = f.len();
    let per = n.div_ceil(threads.threads).max(1);
    pool.install(|| {
        f.par_chunks_mut(per).enumerate().for_each(|(c, out)| {
            let base = c * per;
            for (first, buf) in parts {
                let lo = base.max(*first);
                let hi = (base + out.len()).min(first + buf.len());
                for i in lo..hi {
                    out[i - base] += buf[i - first];
                }
            }
        });
    });
}
