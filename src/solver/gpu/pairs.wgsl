// Contact between particles on the card (src/solver/contact/pairs.rs): two particles closer
// than 2r, not joined by a spring, are pushed apart by Jacobi iterations on positions until
// the deepest overlap is under 1 % of 2r (at most MAX_ITERATIONS), each moved particle held
// out of the obstacles and the ground; then one velocity pass takes each touching pair's
// approach (and, by friction, sliding) as the obstacles' `respond` does.
//
// The neighbours come from a spatial hash rebuilt every step, as in Ten Minute Physics'
// self-collision: cells `reach` = 3r wide (2r and the CPU's skin of r), each particle counted
// into its cell's slot (`pair_count`, which keeps its rank within the slot), a prefix sum of
// the counts (`scan_groups`, `scan_sums`, `scan_add`: each slot's start), and the particles
// placed in slot order (`pair_fill`). An iteration looks through the 3 × 3 cells around the
// cell each particle was counted in, so a pair that was within `reach` when the grid was
// built is seen by every iteration, as the CPU's lists of 2r + skin are.
//
// This file is appended to contact.wgsl, whose `Params`, `respond`, `distance_to`, the
// obstacles and the inverse masses it uses.

const MAX_ITERATIONS: u32 = 32u;
// Jacobi's over-relaxation (pairs.rs: RELAXATION).
const RELAXATION: real = 1.5;
// The control words: [0, 32) the deepest overlap each iteration saw, as f32 bits (a positive
// f32's bits order as its value); then the first iteration's touching entries, the velocity
// pass's, and the iterations run.
const FIRST: u32 = 32u;
const TOUCHING: u32 = 33u;
const RAN: u32 = 34u;

// Which iteration this dispatch is; with `push` set, one of the Jacobi passes inside XPBD's
// substeps (the iterate pushed apart as `Pairs::push_apart` does: no tolerance, no surfaces).
struct Round {
    k: u32,
    push: u32,
    pad1: u32,
    pad2: u32,
}

// A pass's positions in, and out (an iteration reads one buffer and writes the other).
@group(0) @binding(10) var<storage, read> x_from: array<vec2<real>>;
@group(0) @binding(11) var<storage, read_write> x_to: array<vec2<real>>;
// The grid: slot starts (table + 1 values), then the particles in slot order. Counting sees
// the slot starts as atomics.
@group(0) @binding(12) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(13) var<storage, read_write> grid: array<u32>;
// Each block's total, then its start (the prefix sum's second level).
@group(0) @binding(14) var<storage, read_write> sums: array<u32>;
// Each particle's cell when the grid was built, and its rank within its slot.
@group(0) @binding(16) var<storage, read_write> homes: array<vec2<i32>>;
@group(0) @binding(17) var<storage, read_write> ranks: array<u32>;
// The step's links (explicit.wgsl's `links`): where each particle's start, then the other ends.
@group(0) @binding(18) var<storage, read> joins: array<u32>;
@group(0) @binding(19) var<storage, read_write> control: array<atomic<u32>, 40>;
@group(0) @binding(20) var<uniform> round: Round;
@group(0) @binding(21) var<storage, read> v_pair: array<vec2<real>>;
@group(0) @binding(22) var<storage, read_write> v_next: array<vec2<real>>;
// The positions before the iterations, for the methods whose velocity takes the push.
@group(0) @binding(26) var<storage, read_write> x_before: array<vec2<real>>;

var<workgroup> part: array<u32, 256>;

fn group_index(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

fn cell_of(at: vec2<real>) -> vec2<i32> {
    // A conversion out of i32's range saturates: a particle flung far has its cell at the end.
    return vec2<i32>(floor(at / p.reach));
}

fn slot(c: vec2<i32>) -> u32 {
    // Wrapping products, as the CPU's hash (its constants; i32 wraps where i64 did not, so
    // the slots differ, which changes which particles share a slot but not which pairs are
    // found).
    let h = (c.x * 92837111) ^ (c.y * 689287499);
    return u32(h) & (p.table - 1u);
}

// Whether a spring joins i and j.
fn joined(i: u32, j: u32) -> bool {
    let others = p.n + 1u;
    for (var l = joins[i]; l < joins[i + 1u]; l++) {
        if (joins[others + l] == j) { return true; }
    }
    return false;
}

// `at`, pushed there from `start`, put back out of the obstacles and (when contact is set)
// the ground by the radius, positions only: by the nearest surface on `start`'s side (a start
// inside a closed shape on its nearest surface's), a push across the shape itself back to
// where it crossed first (`Surroundings::keep_out`).
fn keep_out(at: vec2<real>, start: vec2<real>) -> vec2<real> {
    var q = at;
    let r = p.radius;
    let push = at - start;
    for (var k = 0u; k < p.obstacles; k++) {
        let o = obstacles[k];
        let side = out_by_nearest(o, start);
        let t = crossing(o, side, q);
        if (t >= real(0.0)) { q = side + (q - side) * t; }
        let touched = touch(o, q, side, push, r);
        if (touched.hit) { q += touched.normal * touched.depth; }
    }
    if ((p.flags & 1u) != 0u) { q.y = max(q.y, p.ground + r); }
    return q;
}

// Zeroes the slot counts and the control words.
@compute @workgroup_size(256)
fn pair_clear(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = thread(id, groups);
    if (e <= p.table) { grid[e] = 0u; }
    if (e < 40u) { atomicStore(&control[e], 0u); }
}

// Each particle into its cell's slot: slot h's count at h + 1, so that the prefix sum gives
// each slot's start.
@compute @workgroup_size(256)
fn pair_count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    let c = cell_of(x_from[i]);
    homes[i] = c;
    ranks[i] = atomicAdd(&counts[slot(c) + 1u], 1u);
}

// The inclusive scan of one work group's values in `part`.
fn scan_part(lid: u32) {
    for (var d = 1u; d < 256u; d = d << 1u) {
        workgroupBarrier();
        var add = 0u;
        if (lid >= d) { add = part[lid - d]; }
        workgroupBarrier();
        part[lid] += add;
    }
    workgroupBarrier();
}

// The prefix sum's first level: each block of 256 counts scanned, its total kept.
@compute @workgroup_size(256)
fn scan_groups(
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let block = group_index(wid, groups);
    let e = block * 256u + lid.x;
    var value = 0u;
    if (e <= p.table) { value = grid[e]; }
    part[lid.x] = value;
    scan_part(lid.x);
    if (e <= p.table) { grid[e] = part[lid.x]; }
    if (lid.x == 255u) { sums[block] = part[255]; }
}

// The second level, in one work group: each block's start (the totals before it), each
// thread taking a run of blocks.
@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_id) lid: vec3<u32>) {
    let blocks = (p.table + 1u + 255u) / 256u;
    let run = (blocks + 255u) / 256u;
    let first = lid.x * run;
    var total = 0u;
    for (var b = first; b < min(first + run, blocks); b++) { total += sums[b]; }
    part[lid.x] = total;
    scan_part(lid.x);
    var start = part[lid.x] - total;
    for (var b = first; b < min(first + run, blocks); b++) {
        let s = sums[b];
        sums[b] = start;
        start += s;
    }
}

// The third level: each block's start added to its values.
@compute @workgroup_size(256)
fn scan_add(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = thread(id, groups);
    if (e <= p.table) { grid[e] += sums[e / 256u]; }
}

// Each particle to its place in its slot.
@compute @workgroup_size(256)
fn pair_fill(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    grid[p.table + 1u + grid[slot(homes[i])] + ranks[i]] = i;
}

// One Jacobi iteration (pairs.rs: `pushed`), the round's k-th: it runs only while the last
// one saw an overlap deeper than the tolerance.
@compute @workgroup_size(256)
fn pair_separate(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    let k = round.k;
    let iterating = round.push == 0u;
    if (i >= p.n) { return; }
    if (iterating && k > 0u && bitcast<f32>(atomicLoad(&control[k - 1u])) <= f32(p.tolerance)) {
        return;
    }
    if (iterating && i == 0u) { atomicMax(&control[RAN], k + 1u); }
    let xi = x_from[i];
    let wi = inv_mass[i];
    let contact = real(2.0) * p.radius;
    var push = vec2<real>(0.0, 0.0);
    var count = 0u;
    var touching = 0u;
    var deepest = real(0.0);
    let home = homes[i];
    for (var dx = -1; dx <= 1; dx++) {
        for (var dy = -1; dy <= 1; dy++) {
            let cell = home + vec2<i32>(dx, dy);
            let h = slot(cell);
            let entries = p.table + 1u;
            for (var e = grid[h]; e < grid[h + 1u]; e++) {
                let j = grid[entries + e];
                // Only the slot's particles of this cell: two cells that share a slot are each
                // visited once, and a far cell's particles in the slot are skipped unread.
                if (j == i || any(homes[j] != cell)) { continue; }
                let d = xi - x_from[j];
                let dist2 = dot(d, d);
                if (dist2 >= contact * contact || joined(i, j)) { continue; }
                let dist = sqrt(dist2);
                deepest = max(deepest, contact - dist);
                touching++;
                let wsum = wi + inv_mass[j];
                if (wi == real(0.0) || wsum == real(0.0)) { continue; }
                var n = vec2<real>(-1.0, 0.0);
                if (dist > real(0.0)) {
                    n = d / dist;
                } else if (i < j) {
                    n = vec2<real>(1.0, 0.0);
                }
                push += n * ((contact - dist) * wi / wsum);
                count++;
            }
        }
    }
    var to = xi;
    if (count > 0u) {
        to = xi + push * min(RELAXATION / real(count), real(1.0));
        // Only a particle the pass moved (the obstacles' own pass, swept, handles the rest).
        if (iterating && any(to != xi)) { to = keep_out(to, xi); }
    }
    x_to[i] = to;
    if (!iterating) { return; }
    if (deepest > real(0.0)) { atomicMax(&control[k], bitcast<u32>(f32(deepest))); }
    if (k == 0u && touching > 0u) { atomicAdd(&control[FIRST], touching); }
}

// The positions before the iterations (for `pair_follow`).
@compute @workgroup_size(256)
fn pair_begin(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    x_before[i] = x_from[i];
}

// The push into the velocity, v += Δx/dt, for the methods whose velocity is where the step
// went (XPBD): a push the velocity did not see would be taken back by the next step.
@compute @workgroup_size(256)
fn pair_follow(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    v[i] += (x_from[i] - x_before[i]) / p.dt;
}

// After the iterations: an odd count of them left the positions in the scratch buffer.
@compute @workgroup_size(256)
fn pair_settle(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n || (atomicLoad(&control[RAN]) & 1u) == 0u) { return; }
    x_to[i] = x_from[i];
}

// The velocity pass (pairs.rs: `respond`): each touching pair's relative velocity through
// `respond`, each particle taking its inverse-mass share, averaged over its contacts. Its walk
// over the grid is `pair_separate`'s: WGSL has no closures, and one function for both would
// bind the velocities to the iterations too, past the 8 storage buffers a stage binds by
// default.
@compute @workgroup_size(256)
fn pair_respond(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    let xi = x_from[i];
    let vi = v_pair[i];
    let wi = inv_mass[i];
    let touching_distance = real(2.0) * p.radius + SLOP;
    var change = vec2<real>(0.0, 0.0);
    var count = 0u;
    var touching = 0u;
    let home = homes[i];
    for (var dx = -1; dx <= 1; dx++) {
        for (var dy = -1; dy <= 1; dy++) {
            let cell = home + vec2<i32>(dx, dy);
            let h = slot(cell);
            let entries = p.table + 1u;
            for (var e = grid[h]; e < grid[h + 1u]; e++) {
                let j = grid[entries + e];
                // Only the slot's particles of this cell: two cells that share a slot are each
                // visited once, and a far cell's particles in the slot are skipped unread.
                if (j == i || any(homes[j] != cell)) { continue; }
                let d = xi - x_from[j];
                let dist = length(d);
                if (dist >= touching_distance || dist == real(0.0) || joined(i, j)) { continue; }
                touching++;
                if (wi == real(0.0)) { continue; }
                let n = d / dist;
                let rel = vi - v_pair[j];
                let after = respond(rel, vec2<real>(0.0, 0.0), n);
                change += (after - rel) * (wi / (wi + inv_mass[j]));
                count++;
            }
        }
    }
    var out = vi;
    if (count > 0u) { out = vi + change / real(count); }
    v_next[i] = out;
    if (touching > 0u) { atomicAdd(&control[TOUCHING], touching); }
}

// The velocity pass's result into the state's velocities.
@compute @workgroup_size(256)
fn pair_take(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n) { return; }
    v[i] = x_from[i];
}
