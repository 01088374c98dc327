//! How far the step is from the memory-bandwidth bound: the bytes a symplectic-Euler step moves
//! (a model, counted pass by pass) against the read-modify-write bandwidth this machine has at
//! the step's working-set size (measured). `hooke bench perf` prints both under its table.

use rayon::prelude::*;
use std::time::Instant;

/// Bytes a packed spring moves per step: its record (a, b: u32; rest, k: f64), read once.
pub const SPRING_BYTES: f64 = 24.0;

/// Bytes a particle moves per step (f64 vectors of 16 bytes, scalars of 8), with the passes as
/// the schedule runs them by default: the force region (m read and f written as each thread
/// starts its particles: 24; the spring sweep's x read, f read and written: 48) and the fused
/// particle sweep (x and v read and written, f and 1/m read: 88). Positions of a spring's far
/// end are taken as cache hits: the springs are sorted by their near end, and the far end is at
/// most a row away. The separate passes moved 248 (kick 56, damping 32, ground 40, advance 48,
/// gravity 24, springs 48).
pub const PARTICLE_BYTES: f64 = 160.0;

/// Bytes one step moves.
pub fn bytes_per_step(particles: usize, springs: usize) -> f64 {
    PARTICLE_BYTES * particles as f64 + SPRING_BYTES * springs as f64
}

/// The arrays a symplectic step touches: springs, and x, v, f, m, 1/m per particle (the fused
/// sweep needs no drift array).
pub fn working_set(particles: usize, springs: usize) -> usize {
    24 * springs + 64 * particles
}

/// Best read-modify-write bandwidth over `bytes` of f64, split over `threads` threads, in bytes
/// per second (each element read and written once per sweep).
pub fn bandwidth(bytes: usize, threads: usize) -> Result<f64, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} threads: {e}"))?;
    let n = (bytes / 8).max(1024);
    // On huge pages where the system has them, as the step's own arrays are.
    let mut a: Vec<f64> = crate::solver::threads::pages::with_capacity(n);
    a.extend((0..n).map(|i| i as f64));
    let chunk = n.div_ceil(threads);
    // Several sweeps per timing on small arrays, so that starting the threads does not count.
    let sweeps = (4_000_000 / (8 * n)).max(1);
    let mut best = f64::INFINITY;
    for _ in 0..30 {
        let start = Instant::now();
        pool.install(|| {
            a.par_chunks_mut(chunk).for_each(|c| {
                for _ in 0..sweeps {
                    for x in c.iter_mut() {
                        *x = *x * 1.000_000_1 + 1.0;
                    }
                    std::hint::black_box(&mut *c);
                }
            })
        });
        best = best.min(start.elapsed().as_secs_f64());
    }
    std::hint::black_box(&a);
    Ok(16.0 * (n * sweeps) as f64 / best)
}
