// XPBD on the card (src/solver/methods/xpbd.rs, line for line): a step of n substeps, each a
// prediction of every particle, then Gauss-Seidel sweeps over the constraints colour by
// colour (no two constraints of a colour share a particle, so a colour is one dispatch and the
// sweep is the CPU's, in the CPU's colour order), then the step's end: the last substep's
// velocity, the drift (x_end − x0)/dt, and the schedule's damping, ground and position update.
//
// `real` is f32, or f64 where the adapter has it (the host rewrites the alias).

alias real = f32;

struct Params {
    n: u32,
    row: u32,
    // Bit 0: a ground. Bit 1: external forces. Bit 2: dashpots.
    flags: u32,
    pad: u32,
    gravity: vec2<real>,
    hs: real,
    inv_hs: real,
    floor: real,
    dt: real,
    inv_dt: real,
    // exp(-mu dt), 1 without damping.
    decay: real,
}

// What differs from dispatch to dispatch: a colour's constraints [start, end), and whether
// this is the substep's first sweep (λ starts at 0) or, for the prediction, whether a
// substep came before.
struct Slot {
    start: u32,
    end: u32,
    first: u32,
    pad: u32,
}

// rest, c_a, c_b, α̃, 1/den; the damped γ, c_a, c_b, 1/den; and λ.
struct Coefficients {
    rest: real,
    ca: real,
    cb: real,
    alpha: real,
    inv_den: real,
    gamma: real,
    dca: real,
    dcb: real,
    dinv_den: real,
    lambda: real,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<uniform> slot: Slot;
// Positions during the step, and at each substep's start.
@group(0) @binding(2) var<storage, read_write> pos: array<vec2<real>>;
@group(0) @binding(3) var<storage, read_write> prev: array<vec2<real>>;
@group(0) @binding(4) var<storage, read_write> v: array<vec2<real>>;
// The state's positions: the step's start, then its end.
@group(0) @binding(5) var<storage, read_write> x: array<vec2<real>>;
@group(0) @binding(6) var<storage, read> inv_mass: array<real>;
@group(0) @binding(7) var<storage, read> applied: array<vec2<real>>;
@group(0) @binding(8) var<storage, read> ends: array<vec2<u32>>;
@group(0) @binding(9) var<storage, read_write> coef: array<Coefficients>;
// Each particle's velocity before contact: its start velocity and a step of its body forces'
// acceleration (where it heads, which tells a thin segment's side; contact.wgsl reads it).
@group(0) @binding(10) var<storage, read_write> heading: array<vec2<real>>;

fn particle(id: vec3<u32>) -> u32 {
    return id.x + id.y * p.row;
}

fn on_ground(at: vec2<real>, w: real) -> vec2<real> {
    var r = at;
    if ((p.flags & 1u) != 0u && r.y < p.floor && w != real(0.0)) {
        r.y = p.floor;
    }
    return r;
}

// The step's start: the work positions are the state's, and the heading before contact.
@compute @workgroup_size(256)
fn begin(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = particle(id);
    if (i >= p.n) { return; }
    pos[i] = x[i];
    let w = inv_mass[i];
    var a = vec2<real>(0.0, 0.0);
    if (w != real(0.0)) {
        a = p.gravity;
        if ((p.flags & 2u) != 0u) {
            a += applied[i] * w;
        }
    }
    heading[i] = v[i] + a * p.dt;
}

// v += hₛ f/m, p = x, x += hₛ v, from where the last sweeps left x, put on the ground (the
// ground as a position constraint after the sweeps); after the first substep fused with the
// previous one's velocity, v = (x − p)/hₛ.
@compute @workgroup_size(256)
fn predict(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = particle(id);
    if (i >= p.n) { return; }
    let w = inv_mass[i];
    let end = on_ground(pos[i], w);
    var vi = v[i];
    if (slot.first == 0u && w != real(0.0)) {
        vi = (end - prev[i]) * p.inv_hs;
    }
    if (w != real(0.0)) {
        var a = p.gravity;
        if ((p.flags & 2u) != 0u) {
            a += applied[i] * w;
        }
        vi += a * p.hs;
    }
    v[i] = vi;
    prev[i] = end;
    pos[i] = end + vi * p.hs;
}

// One constraint of the slot's colour.
@compute @workgroup_size(256)
fn project(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = slot.start + particle(id);
    if (k >= slot.end) { return; }
    let e = ends[k];
    let c = coef[k];
    let xa = pos[e.x];
    let xb = pos[e.y];
    let l = xa - xb;
    let len = length(l);
    if (len == real(0.0)) { return; }
    var lambda = c.lambda;
    if (slot.first != 0u) {
        lambda = real(0.0);
    }
    if ((p.flags & 4u) != 0u) {
        let n = l / len;
        let moved = dot(n, (xa - prev[e.x]) - (xb - prev[e.y]));
        let g = c.rest - len - c.gamma * moved - c.alpha * lambda;
        coef[k].lambda = lambda + g * c.dinv_den;
        pos[e.x] = xa + n * (c.dca * g);
        pos[e.y] = xb - n * (c.dcb * g);
    } else {
        let g = (c.rest - len) - c.alpha * lambda;
        coef[k].lambda = lambda + g * c.inv_den;
        let s = g / len;
        pos[e.x] = xa + l * (c.ca * s);
        pos[e.y] = xb - l * (c.cb * s);
    }
}

// The step's end: the last substep's velocity and the drift, then the schedule's damping, the
// ground's clamp on the start-of-step position, and x = x0 + dt u.
@compute @workgroup_size(256)
fn finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = particle(id);
    if (i >= p.n) { return; }
    let w = inv_mass[i];
    let end = on_ground(pos[i], w);
    var vi = v[i];
    if (w != real(0.0)) {
        vi = (end - prev[i]) * p.inv_hs;
    }
    var x0 = x[i];
    let u = (end - x0) * p.inv_dt;
    vi *= p.decay;
    if ((p.flags & 1u) != 0u && w != real(0.0) && x0.y < p.floor) {
        x0.y = p.floor;
        vi.y = real(0.0);
    }
    v[i] = vi;
    x[i] = x0 + u * p.dt;
}
