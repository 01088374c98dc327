//! Benchmarks and reports (`hooke bench ...`): measured figures, never test assertions.

pub mod equilibrium;
pub mod large_steps;
pub mod perf;
pub mod plot;
pub mod scale;
pub mod stability;
pub mod traffic;
pub mod trajectory;
pub mod work_precision;

/// The machine a figure was measured on: the CPU model and the cores this process may use
/// (from /proc/cpuinfo; "unknown CPU" elsewhere).
pub fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {cores} cores")
}
