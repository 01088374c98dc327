// Tearing on the card (src/sim/tear.rs): at the end of each of the CPU's ticks, every spring
// stretched past (1 + strain) times its rest length breaks. Each particle's thread looks at its
// own links; a spring's two links compute the same length (|a − b| and |b − a| are the same
// bits), so both ends agree on whether it broke. A broken link's record is zeroed (no force,
// no dashpot, and a rest length of 0 never tears again) and flagged for the host, which
// removes the spring's entity.
//
// `real` and `Link` as in explicit.wgsl (the host rewrites the aliases).

alias real = f32;
alias Link = vec2<real>;

struct Params {
    n: u32,
    row: u32,
    pad0: u32,
    pad1: u32,
    // 1 + strain.
    limit: real,
    spare: real,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x: array<vec2<real>>;
@group(0) @binding(2) var<storage, read> links: array<u32>;
@group(0) @binding(3) var<storage, read_write> spring: array<Link>;
// 1 for each link that broke since the host last cleared it.
@group(0) @binding(4) var<storage, read_write> torn: array<u32>;

@compute @workgroup_size(256)
fn tear(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * p.row;
    if (i >= p.n) {
        return;
    }
    let others = p.n + 1u;
    for (var e = links[i]; e < links[i + 1u]; e++) {
        let s = spring[e];
        if (s.y > real(0.0) && length(x[i] - x[links[others + e]]) > p.limit * s.y) {
            spring[e] = Link();
            torn[e] = 1u;
        }
    }
}
