// The explicit step of one particle (symplectic or explicit Euler), the passes of
// src/solver/step.rs in one kernel: the spring forces gathered from the particle's own list
// of links (each spring appears in both ends' lists, so no two threads write one value), the
// kick, the damping, the ground, the position update. Positions and velocities ping-pong
// between two buffers each, since a particle's neighbours read its start-of-step position (and,
// through a dashpot, its start-of-step velocity).
//
// `real` is f32, or f64 where the adapter has it, and a link is (k, L), or (k, L, c, 0) where
// some spring has a dashpot c (the host rewrites the aliases and `DASHPOTS`).

alias real = f32;
alias Link = vec2<real>;
const DASHPOTS: bool = false;

// The dashpot's force along a link, c (v_i − v_j)·n, in the variant with dashpots.
fn dashpot(s: Link, dv: vec2<real>, n: vec2<real>) -> real {
    return real(0.0);
}

struct Params {
    n: u32,
    // Threads in one row of the dispatch grid (a dispatch has at most 65535 groups a side).
    row: u32,
    // Bit 0: explicit Euler (move with the start velocity). Bit 1: a ground.
    // Bit 2: external forces.
    flags: u32,
    pad: u32,
    gravity: vec2<real>,
    dt: real,
    // exp(-mu dt), 1 without damping.
    decay: real,
    ground: real,
    spare: real,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x_in: array<vec2<real>>;
@group(0) @binding(2) var<storage, read_write> x_out: array<vec2<real>>;
@group(0) @binding(3) var<storage, read> v_in: array<vec2<real>>;
@group(0) @binding(4) var<storage, read_write> v_out: array<vec2<real>>;
// 1/m, and 0 for a pinned particle.
@group(0) @binding(5) var<storage, read> inv_mass: array<real>;
// The first n + 1 values: where each particle's links start; then each link's other end.
@group(0) @binding(6) var<storage, read> links: array<u32>;
// Each link's (stiffness, rest length[, dashpot, 0]).
@group(0) @binding(7) var<storage, read> spring: array<Link>;
// Each particle's external force (a single zero when none is set).
@group(0) @binding(8) var<storage, read> applied: array<vec2<real>>;

@compute @workgroup_size(256)
fn step(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * p.row;
    if (i >= p.n) {
        return;
    }
    var x = x_in[i];
    let before = v_in[i];
    var f = vec2<real>(0.0, 0.0);
    let first = links[i];
    let last = links[i + 1u];
    let others = p.n + 1u;
    for (var e = first; e < last; e++) {
        let j = links[others + e];
        let d = x - x_in[j];
        let l = length(d);
        // Springs shorter than this exert no force: their direction is undefined.
        if (l >= real(1e-12)) {
            let s = spring[e];
            if (DASHPOTS) {
                let n = d / l;
                f += n * (-s.x * (l - s.y) - dashpot(s, before - v_in[j], n));
            } else {
                f += d * (-s.x * (l - s.y) / l);
            }
        }
    }
    if ((p.flags & 4u) != 0u) {
        f += applied[i];
    }
    let w = inv_mass[i];
    var u = before;
    if (w != real(0.0)) {
        u += (p.gravity + f * w) * p.dt;
    }
    u *= p.decay;
    // The assignment's ground: the start-of-step position is tested.
    if ((p.flags & 2u) != 0u && w != real(0.0) && x.y < p.ground) {
        x.y = p.ground;
        u.y = real(0.0);
    }
    v_out[i] = u;
    if ((p.flags & 1u) != 0u) {
        u = before;
    }
    x_out[i] = x + u * p.dt;
}
