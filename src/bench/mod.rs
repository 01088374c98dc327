//! Benchmarks and reports (`hooke bench ...`): measured figures, never test assertions.

pub mod contact;
pub mod equilibrium;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod large_steps;
pub mod perf;
pub mod plot;
pub mod scale;
pub mod stability;
pub mod traffic;
pub mod trajectory;
pub mod work_precision;

/// The median of repeated measurements (the upper middle one of an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The machine a figure was measured on (the solver core's own measurements name it too).
pub use crate::solver::threads::machine;
