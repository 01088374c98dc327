//! The machine the threads run on: whether it has the vector extension that the AVX kernels
//! need, and its name as the figures give it (the benchmarks' reports and the core's own
//! measurements print it beside every figure).

/// Does this CPU have AVX? (Detected once; later calls read a cached flag.) The force kernels
/// and the Cholesky factor's dense kernels choose their AVX forms by it.
#[inline]
pub fn avx() -> bool {
    std::is_x86_feature_detected!("avx")
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
