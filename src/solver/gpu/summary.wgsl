// What the host needs of the state every tick, without reading the state: its energy by kind and
// the links torn since the host last cleared them, reduced on the card into one vector.
//
// `partials` sums each work group's particles (a tree in workgroup memory, the same order every
// time, so the sums repeat bit for bit); `total` sums the partials in one work group into the
// slot after them, which the host copies back (32 bytes in f32).
//
// The card's particles only: a fixed particle (inverse mass 0: pinned, or held by a drag) moves
// on the CPU, which adds its share. A spring's link appears at both ends, so each link carries
// half of the spring's energy. A non-finite state makes the sums non-finite, which the host reads
// as a blow-up.
//
// `real` and `Link` as in explicit.wgsl (the host rewrites the aliases).

alias real = f32;
alias Link = vec2<real>;

const GROUP: u32 = 256u;

struct Params {
    n: u32,
    row: u32,
    // Work groups of `partials`: the partials `total` sums.
    groups: u32,
    pad: u32,
    gravity: vec2<real>,
    spare: vec2<real>,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x: array<vec2<real>>;
@group(0) @binding(2) var<storage, read> v: array<vec2<real>>;
@group(0) @binding(3) var<storage, read> w: array<real>;
@group(0) @binding(4) var<storage, read> links: array<u32>;
@group(0) @binding(5) var<storage, read> spring: array<Link>;
// 1 for each link torn since the host last cleared it (one zero word without tearing).
@group(0) @binding(6) var<storage, read> torn: array<u32>;
// (kinetic, gravity's potential, the springs', torn links) per work group, then the total.
@group(0) @binding(7) var<storage, read_write> sums: array<vec4<real>>;

var<workgroup> shared_sums: array<vec4<real>, GROUP>;

// Sums `shared_sums` into its first element, the same pairs in the same order every time.
fn reduce(local: u32) {
    for (var stride = GROUP / 2u; stride > 0u; stride = stride / 2u) {
        workgroupBarrier();
        if (local < stride) {
            shared_sums[local] = shared_sums[local] + shared_sums[local + stride];
        }
    }
    workgroupBarrier();
}

// The half of each of particle `i`'s springs' energy, and its links torn.
fn springs_of(i: u32) -> vec2<real> {
    let others = p.n + 1u;
    var energy = real(0.0);
    var broken = 0u;
    for (var e = links[i]; e < links[i + 1u]; e++) {
        let s = spring[e];
        let stretch = length(x[i] - x[links[others + e]]) - s.y;
        energy += real(0.25) * s.x * stretch * stretch;
        broken += torn[e];
    }
    return vec2<real>(energy, real(broken));
}

@compute @workgroup_size(256)
fn partials(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = id.x + id.y * p.row;
    var mine = vec4<real>();
    if (i < p.n) {
        // A fixed particle's springs hold energy too; its motion is the host's.
        var motion = vec2<real>();
        if (w[i] > real(0.0)) {
            let m = real(1.0) / w[i];
            motion = vec2<real>(real(0.5) * m * dot(v[i], v[i]), -m * dot(p.gravity, x[i]));
        }
        mine = vec4<real>(motion, springs_of(i));
    }
    shared_sums[local] = mine;
    reduce(local);
    if (local == 0u) {
        sums[group.x + group.y * groups.x] = shared_sums[0];
    }
}

@compute @workgroup_size(256)
fn total(@builtin(local_invocation_index) local: u32) {
    var mine = vec4<real>();
    for (var g = local; g < p.groups; g += GROUP) {
        mine += sums[g];
    }
    shared_sums[local] = mine;
    reduce(local);
    if (local == 0u) {
        sums[p.groups] = shared_sums[0];
    }
}
