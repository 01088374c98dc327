//! Benchmarks and reports (`hooke bench ...`): measured figures, never test assertions.

pub mod perf;
pub mod plot;
pub mod stability;
pub mod traffic;
pub mod trajectory;
pub mod work_precision;
