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

/// The median of repeated measurements (the upper middle one of an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The machine a figure was measured on: the CPU model with its family and model numbers and
/// its widest vector extension (the AVX-512 machines and the AVX2 ones differ), and the cores
/// this process may use (from /proc/cpuinfo; "unknown CPU" elsewhere).
pub fn machine() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        info.lines()
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let Some(model) = field("model name") else {
        return format!("unknown CPU, {cores} cores");
    };
    let flags = field("flags").unwrap_or_default();
    let has = |f: &str| flags.split_whitespace().any(|x| x == f);
    let simd = if has("avx512f") {
        "AVX-512"
    } else if has("avx2") {
        "AVX2"
    } else {
        "no AVX2"
    };
    let (family, number) = (field("cpu family"), field("model"));
    let (family, number) = (
        family.as_deref().unwrap_or("?"),
        number.as_deref().unwrap_or("?"),
    );
    format!("{model} (family {family}, model {number}, {simd}), {cores} cores")
}
