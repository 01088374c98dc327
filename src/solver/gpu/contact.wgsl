// The contact pass of one particle on the card (src/solver/contact/pass.rs, `collide`): after
// the step, a free particle that ended within its radius of an obstacle (or of the ground,
// when contact is set) is put back on the surface, after a swept test of its path so that it
// cannot pass through a thin one, and its velocity relative to the surface loses its approach
// (keeping the restitution's share) and up to μ times that of its sliding. The obstacles'
// shapes, distances and swept tests are src/solver/contact/obstacle.rs's, line for line.
//
// `real` is f32, or f64 where the adapter has it (the host rewrites the alias).

alias real = f32;

// A segment's least thickness, and how far from a surface a particle still touches it. In f32
// these are wider than the CPU's (1e-6 and 1e-9 m, which the host writes here for f64): f32
// resolves 6e-8 m at 1 m, so a particle the last step left on a surface sits a few units of
// that off it, and a slop under that lets it miss the touch that stops it (a box held by
// friction on a slope then crept down it).
const MIN_THICKNESS: real = 1e-5;
const SLOP: real = 1e-6;
const NONE: real = -1.0;

struct Params {
    n: u32,
    obstacles: u32,
    // Bit 0: the ground is this pass's (contact is set and the scene has a ground). Bit 1:
    // the particles moved with their start-of-step velocity (explicit Euler).
    flags: u32,
    // The pair contact's hash slots, a power of two (pairs.wgsl).
    table: u32,
    dt: real,
    radius: real,
    friction: real,
    restitution: real,
    // Below this approach speed an impact keeps nothing.
    rest_speed: real,
    ground: real,
    // The pair contact's cell width, and the overlap under which its iterations stop.
    reach: real,
    tolerance: real,
}

// kind: 0 a circle (size: its radius), 1 a box (a: its half-extents), 2 a segment from a to b
// (size: its thickness, at least MIN_THICKNESS). It moves by its velocities a `span` at a time:
// a step's dt, or under XPBD a substep's. Its rotation is kept as (cos, sin), and turned each
// span by (cos, sin) of ω span, both from the host: Vulkan's sine and cosine take no f64.
struct Obstacle {
    center: vec2<real>,
    velocity: vec2<real>,
    a: vec2<real>,
    b: vec2<real>,
    rotation: vec2<real>,
    turn: vec2<real>,
    angular_velocity: real,
    size: real,
    kind: real,
    span: real,
}

@group(0) @binding(0) var<uniform> p: Params;
// The velocities the step began with: explicit Euler moved with them.
@group(0) @binding(1) var<storage, read> v_start: array<vec2<real>>;
@group(0) @binding(2) var<storage, read_write> x_end: array<vec2<real>>;
@group(0) @binding(3) var<storage, read_write> v: array<vec2<real>>;
@group(0) @binding(4) var<storage, read> inv_mass: array<real>;
@group(0) @binding(5) var<storage, read_write> obstacles: array<Obstacle>;
// [0]: surface contacts this step so far; [1]: the last step's; [2]: the last step's touching
// particle pairs.
@group(0) @binding(6) var<storage, read_write> counter: array<atomic<u32>, 4>;

// A thread's index in a dispatch of work groups of 256, rows of at most 65535 groups.
fn thread(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 256u;
}

fn is_circle(o: Obstacle) -> bool { return o.kind < 0.5; }
fn is_box(o: Obstacle) -> bool { return o.kind > 0.5 && o.kind < 1.5; }
fn is_segment(o: Obstacle) -> bool { return o.kind > 1.5; }

fn perp(v: vec2<real>) -> vec2<real> { return vec2<real>(-v.y, v.x); }

// glam's signum: 1 for +0.
fn signum(x: real) -> real { return select(real(-1.0), real(1.0), x >= real(0.0)); }

// d turned by the rotation (c, s).
fn rotate(d: vec2<real>, cs: vec2<real>) -> vec2<real> {
    return vec2<real>(cs.x * d.x - cs.y * d.y, cs.y * d.x + cs.x * d.y);
}

fn unturned(o: Obstacle) -> bool {
    return (o.rotation.x == real(1.0) && o.rotation.y == real(0.0)) || is_circle(o);
}

fn local(o: Obstacle, q: vec2<real>) -> vec2<real> {
    let d = q - o.center;
    if (unturned(o)) { return d; }
    return rotate(d, vec2<real>(o.rotation.x, -o.rotation.y));
}

fn world_direction(o: Obstacle, d: vec2<real>) -> vec2<real> {
    if (unturned(o)) { return d; }
    return rotate(d, o.rotation);
}

fn bound(o: Obstacle) -> real {
    if (is_circle(o)) { return o.size; }
    if (is_box(o)) { return length(o.a); }
    return max(length(o.a), length(o.b)) + o.size;
}

struct Distance {
    d: real,
    n: vec2<real>,
}

fn box_distance(q: vec2<real>, half: vec2<real>) -> Distance {
    let d = abs(q) - half;
    let outside = max(d, vec2<real>(0.0, 0.0));
    if (dot(outside, outside) > real(0.0)) {
        let n = normalize(outside * vec2<real>(signum(q.x), signum(q.y)));
        return Distance(length(outside), n);
    }
    if (d.x > d.y) {
        return Distance(d.x, vec2<real>(signum(q.x), 0.0));
    }
    return Distance(d.y, vec2<real>(0.0, signum(q.y)));
}

fn distance_to(o: Obstacle, at: vec2<real>) -> Distance {
    let q = local(o, at);
    var r: Distance;
    if (is_circle(o)) {
        let l = length(q);
        var n = vec2<real>(0.0, 1.0);
        if (l > real(0.0)) { n = q / l; }
        r = Distance(l - o.size, n);
    } else if (is_box(o)) {
        r = box_distance(q, o.a);
    } else {
        let ab = o.b - o.a;
        let len2 = dot(ab, ab);
        var t = real(0.0);
        if (len2 > real(0.0)) { t = clamp(dot(q - o.a, ab) / len2, real(0.0), real(1.0)); }
        let d = q - (o.a + ab * t);
        let l = length(d);
        var n = vec2<real>(0.0, 1.0);
        if (l > real(1e-9)) {
            n = d / l;
        } else if (dot(ab, ab) > real(0.0)) {
            n = normalize(perp(ab));
        }
        r = Distance(l - o.size, n);
    }
    r.n = world_direction(o, r.n);
    return r;
}

struct Touch {
    hit: bool,
    depth: real,
    normal: vec2<real>,
}

fn touch(o: Obstacle, at: vec2<real>, start: vec2<real>, heading: vec2<real>, r: real) -> Touch {
    let dn = distance_to(o, at);
    if (dn.d >= r + SLOP) {
        return Touch(false, 0.0, vec2<real>(0.0, 0.0));
    }
    var depth = max(r - dn.d, real(0.0));
    var normal = dn.n;
    if (is_segment(o)) {
        let core = at - normal * (dn.d + o.size);
        let side_from = dot(start - core, normal);
        let off_line = length(at - core);
        var flip = false;
        if (abs(side_from) > real(0.5) * MIN_THICKNESS) {
            flip = side_from < real(0.0);
        } else {
            flip = off_line < real(0.5) * MIN_THICKNESS && dot(heading, normal) > real(0.0);
        }
        if (flip) {
            normal = -normal;
            depth = r + real(2.0) * o.size + dn.d;
        }
    } else if (dn.d < real(0.0)) {
        // Past a closed shape's middle from a start outside it: out on the start's side, to
        // the tangent at the surface point nearest the start (`Placed::touch`).
        let back = distance_to(o, start);
        if (back.d >= real(0.0) && dot(back.n, normal) < real(0.0)) {
            let surface = start - back.n * back.d;
            normal = back.n;
            depth = r - dot(at - surface, back.n);
        }
    }
    return Touch(true, depth, normal);
}

fn hit_normal(o: Obstacle, at: vec2<real>, step: vec2<real>) -> vec2<real> {
    let n = distance_to(o, at).n;
    if (dot(n, step) > real(0.0)) { return -n; }
    return n;
}

fn velocity_at(o: Obstacle, at: vec2<real>) -> vec2<real> {
    return o.velocity + o.angular_velocity * perp(at - o.center);
}

fn in_unit(t: real) -> bool { return t >= real(0.0) && t <= real(1.0); }

fn line_crossing(p0: vec2<real>, p1: vec2<real>, a: vec2<real>, b: vec2<real>) -> real {
    let ab = b - a;
    let len = length(ab);
    if (len == real(0.0)) { return NONE; }
    let n = perp(ab) / len;
    let s0 = dot(p0 - a, n);
    let s1 = dot(p1 - a, n);
    let half = real(0.5) * MIN_THICKNESS;
    var t = real(0.0);
    if (abs(s0) < half) {
        if (abs(s1) < half) { return NONE; }
    } else if ((s0 > real(0.0)) != (s1 > real(0.0))) {
        t = s0 / (s0 - s1);
    } else {
        return NONE;
    }
    let along = dot(p0 + (p1 - p0) * t - a, ab) / (len * len);
    if (in_unit(along)) { return t; }
    return NONE;
}

fn ray_circle(p0: vec2<real>, p1: vec2<real>, c: vec2<real>, radius: real) -> real {
    let d = p1 - p0;
    let m = p0 - c;
    let a = dot(d, d);
    if (a == real(0.0)) { return NONE; }
    let b = dot(m, d);
    let cc = dot(m, m) - radius * radius;
    let disc = b * b - a * cc;
    if (disc < real(0.0)) { return NONE; }
    let t = (-b - sqrt(disc)) / a;
    if (in_unit(t)) { return t; }
    return NONE;
}

fn keep(best: real, t: real) -> real {
    if (t < real(0.0)) { return best; }
    if (best < real(0.0)) { return t; }
    return min(best, t);
}

fn ray_capsule(p0: vec2<real>, p1: vec2<real>, a: vec2<real>, b: vec2<real>, radius: real) -> real {
    let ab = b - a;
    var best = NONE;
    best = keep(best, ray_circle(p0, p1, a, radius));
    best = keep(best, ray_circle(p0, p1, b, radius));
    let len = length(ab);
    if (len > real(0.0)) {
        let n = perp(ab) / len;
        let d = p1 - p0;
        for (var k = 0; k < 2; k++) {
            let side = select(-radius, radius, k == 0);
            let s0 = dot(p0 - a, n) - side;
            let s1 = dot(p1 - a, n) - side;
            if (signum(s0) == signum(s1) || s0 == s1) { continue; }
            let t = s0 / (s0 - s1);
            let hit = p0 + d * t;
            let along = dot(hit - a, ab) / (len * len);
            if (in_unit(along) && in_unit(t)) { best = keep(best, t); }
        }
    }
    return best;
}

fn ray_rounded_box(p0: vec2<real>, p1: vec2<real>, half: vec2<real>, r: real) -> real {
    var corners = array<vec2<real>, 4>(
        vec2<real>(-half.x, -half.y),
        vec2<real>(half.x, -half.y),
        vec2<real>(half.x, half.y),
        vec2<real>(-half.x, half.y),
    );
    var best = NONE;
    for (var k = 0; k < 4; k++) {
        best = keep(best, ray_capsule(p0, p1, corners[k], corners[(k + 1) % 4], r));
    }
    return best;
}

// The first t in [0, 1] at which the path p0 → p1 (in the obstacle's frame) comes within `r`
// of the shape (the shape itself for r = 0), for a start farther out (`Placed::sweep`).
fn sweep(o: Obstacle, p0: vec2<real>, p1: vec2<real>, r: real) -> real {
    if (is_circle(o)) { return ray_circle(p0, p1, vec2<real>(0.0, 0.0), o.size + r); }
    if (is_segment(o)) { return ray_capsule(p0, p1, o.a, o.b, o.size + r); }
    return ray_rounded_box(p0, p1, o.a, r);
}

// Where a path that starts and ends outside a closed shape passes through it: where it enters,
// in [0, 1] (`Placed::passes_through`), with `back` the shape's distance from `start`; NONE for
// a segment. A path that stops short of the tangent at the surface point nearest its start
// cannot enter (the shape is convex); a start on the surface enters at once if it heads in.
fn passes_through(o: Obstacle, start: vec2<real>, back: Distance, to: vec2<real>) -> real {
    if (is_segment(o)) { return NONE; }
    let toward = -dot(to - start, back.n);
    let half = real(0.5) * MIN_THICKNESS;
    if (back.d < -half || toward < back.d || distance_to(o, to).d < real(0.0)) { return NONE; }
    if (back.d < half) {
        if (toward > real(0.0)) { return real(0.0); }
        return NONE;
    }
    return sweep(o, local(o, start), local(o, to), real(0.0));
}

// Where the path crosses the shape itself: a segment's line, or a closed shape from side to
// side (`Placed::crossing`); NONE when it does not.
fn crossing(o: Obstacle, start: vec2<real>, to: vec2<real>) -> real {
    if (is_segment(o)) {
        let t = line_crossing(local(o, start), local(o, to), o.a, o.b);
        if (t > real(0.0)) { return t; }
        return NONE;
    }
    return passes_through(o, start, distance_to(o, start), to);
}

// `at`, or for a point inside a closed shape, the point just outside it by the nearest surface
// (`Placed::out_by_nearest`).
fn out_by_nearest(o: Obstacle, at: vec2<real>) -> vec2<real> {
    let dn = distance_to(o, at);
    if (dn.d < real(0.0) && !is_segment(o)) {
        return at + dn.n * (real(0.5) * MIN_THICKNESS - dn.d);
    }
    return at;
}

// Whether a path whose start is `back` from the shape is in contact with it already
// (`Placed::first_hit`).
fn in_contact(back: Distance, r: real) -> bool {
    return back.d < r + real(0.5) * MIN_THICKNESS;
}

fn first_hit(o: Obstacle, start: vec2<real>, to: vec2<real>, r: real) -> real {
    let p0 = local(o, start);
    let p1 = local(o, to);
    let back = distance_to(o, start);
    if (in_contact(back, r)) {
        if (is_segment(o)) { return line_crossing(p0, p1, o.a, o.b); }
        return passes_through(o, start, back, to);
    }
    return sweep(o, p0, p1, r);
}

fn respond(vel: vec2<real>, surface_velocity: vec2<real>, normal: vec2<real>) -> vec2<real> {
    let rel = vel - surface_velocity;
    let vn = dot(rel, normal);
    if (vn >= real(0.0)) { return vel; }
    var kept = real(0.0);
    if (-vn > p.rest_speed) { kept = -vn * p.restitution; }
    let dvn = kept - vn;
    var vt = rel - normal * vn;
    let speed_t = length(vt);
    if (speed_t > p.friction * dvn) {
        vt = vt * (real(1.0) - p.friction * dvn / speed_t);
    } else {
        vt = vec2<real>(0.0, 0.0);
    }
    return surface_velocity + normal * kept + vt;
}

fn hold(at: vec2<real>, start: vec2<real>, shift: vec2<real>, n: vec2<real>, depth: real) -> vec2<real> {
    let moved = at - start - shift;
    let sliding = moved - n * dot(moved, n);
    let l = length(sliding);
    let limit = p.friction * depth;
    if (l <= limit) { return at - sliding; }
    if (l > real(0.0)) { return at - sliding * (limit / l); }
    return at;
}

fn near(o: Obstacle, at: vec2<real>, r: real, travel: real) -> bool {
    return length(at - o.center) <= bound(o) + r + travel + real(2.0) * SLOP;
}

// Where a particle that moved from `start` to `at` (heading `heading`) ends once put back out
// of the obstacles and (when this pass has it) the ground by the radius, with friction's hold
// on its slide, and with `vel` through each surface's `respond` when `respond_velocity`
// (pass.rs: `place`, with the contact pass's or the solve's `touched`).
struct Placed {
    x: vec2<real>,
    vel: vec2<real>,
    contacts: u32,
}

// Where the point of a moving obstacle that was at `q` a time `lead` ago is now, the
// obstacle standing where the path ends (obstacle.rs: `Placed::carried`). `lead` is 0 or its
// span, the turn's.
fn carried(o: Obstacle, q: vec2<real>, lead: real) -> vec2<real> {
    if (lead == real(0.0) || !moves(o)) { return q; }
    let start = o.center - o.velocity * lead;
    var arm = q - start;
    if (o.angular_velocity != real(0.0)) { arm = rotate(arm, o.turn); }
    return o.center + arm;
}

fn moves(o: Obstacle) -> bool {
    return any(o.velocity != vec2<real>(0.0, 0.0)) || o.angular_velocity != real(0.0);
}

// The heading relative to a moving obstacle's surface, where the path is read in its frame.
fn heading_on(o: Obstacle, heading: vec2<real>, at: vec2<real>, lead: real) -> vec2<real> {
    if (lead > real(0.0) && moves(o)) { return heading - velocity_at(o, at); }
    return heading;
}

// With `leads`, each moving obstacle has moved onto the particles over the path (pass.rs:
// `Surroundings::leads`), by its span: a step's after an explicit step, a substep's within
// XPBD's; without, it stands where the path began (XPBD's `enter`, a path of no length). The
// surfaces' slide that friction measures is a span's. `heading` is a velocity: only its
// direction counts.
fn place(at: vec2<real>, start_world: vec2<real>, heading: vec2<real>, v_in: vec2<real>, respond_velocity: bool, leads: bool) -> Placed {
    var x = at;
    var vel = v_in;
    let r = p.radius;
    var contacts = 0u;
    var best_t = real(2.0);
    var best = 0u;
    for (var k = 0u; k < p.obstacles; k++) {
        let o = obstacles[k];
        let lead = select(real(0.0), o.span, leads);
        let start = carried(o, start_world, lead);
        if (!near(o, x, r, length(x - start))) { continue; }
        let t = first_hit(o, start, x, r);
        if (t >= real(0.0) && t < best_t) {
            best_t = t;
            best = k;
        }
    }
    if (best_t <= real(1.0)) {
        let o = obstacles[best];
        let lead = select(real(0.0), o.span, leads);
        let start = carried(o, start_world, lead);
        let step = x - start;
        let hit = start + step * best_t;
        // A path through a closed shape from a start in contact enters where the path says.
        var toward = heading_on(o, heading, x, lead);
        if (!is_segment(o) && in_contact(distance_to(o, start), r)) { toward = step; }
        let n = hit_normal(o, hit, toward);
        let rest = step * (real(1.0) - best_t);
        let into = max(-dot(rest, n), real(0.0));
        x = hit + rest + n * into;
        let sv = velocity_at(o, x);
        x = hold(x, start_world, sv * o.span, n, into);
        if (respond_velocity) { vel = respond(vel, sv, n); }
        contacts++;
    }
    for (var k = 0u; k < p.obstacles; k++) {
        let o = obstacles[k];
        let lead = select(real(0.0), o.span, leads);
        let start = carried(o, start_world, lead);
        if (!near(o, x, r, length(x - start))) { continue; }
        let t = touch(o, x, start, heading_on(o, heading, x, lead), r);
        if (t.hit) {
            x += t.normal * t.depth;
            let sv = velocity_at(o, x);
            x = hold(x, start_world, sv * o.span, t.normal, t.depth);
            if (respond_velocity) { vel = respond(vel, sv, t.normal); }
            contacts++;
        }
    }
    if ((p.flags & 1u) != 0u && x.y < p.ground + r + SLOP) {
        let depth = max(p.ground + r - x.y, real(0.0));
        x.y = max(x.y, p.ground + r);
        let up = vec2<real>(0.0, 1.0);
        x = hold(x, start_world, vec2<real>(0.0, 0.0), up, depth);
        if (respond_velocity) { vel = respond(vel, vec2<real>(0.0, 0.0), up); }
        contacts++;
    }
    return Placed(x, vel, contacts);
}

@compute @workgroup_size(256)
fn collide(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n || inv_mass[i] == real(0.0)) {
        return;
    }
    let x = x_end[i];
    let vel = v[i];
    // Where the step began: back along the velocity the particle moved with (the pair contact
    // may have moved it since, and the path starts that much farther along).
    var moved_with = vel;
    if ((p.flags & 2u) != 0u) { moved_with = v_start[i]; }
    let start = x - moved_with * p.dt;
    var heading = vel;
    if (any(x != start)) { heading = moved_with; }
    let placed = place(x, start, heading, vel, true, true);
    x_end[i] = placed.x;
    v[i] = placed.vel;
    if (placed.contacts > 0u) {
        atomicAdd(&counter[0], placed.contacts);
    }
}

// Contact inside XPBD's substeps (src/solver/contact/inside.rs, `InSolve::keep_out`): the
// iterate of each free particle put back out of the surfaces along its path from where the
// substep began (`enter`, before the first prediction: from where it is), with friction's
// hold, and the heading it had before contact telling a thin segment's side.
@group(0) @binding(23) var<storage, read_write> iterate: array<vec2<real>>;
@group(0) @binding(24) var<storage, read> substep_start: array<vec2<real>>;
@group(0) @binding(25) var<storage, read> heading_before: array<vec2<real>>;

@compute @workgroup_size(256)
fn enter(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n || inv_mass[i] == real(0.0)) { return; }
    let at = iterate[i];
    iterate[i] = place(at, at, heading_before[i], vec2<real>(0.0, 0.0), false, false).x;
}

@compute @workgroup_size(256)
fn hold_out(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n || inv_mass[i] == real(0.0)) { return; }
    iterate[i] = place(iterate[i], substep_start[i], heading_before[i], vec2<real>(0.0, 0.0), false, true).x;
}

// The velocity pass after a solve that kept contact itself (pass.rs: `settle`): a free particle
// touching a surface keeps no approach in its end velocity, and bounces with the restitution's
// share of the approach it had before contact, above the rest speed.
@compute @workgroup_size(256)
fn settle(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.n || inv_mass[i] == real(0.0)) { return; }
    let x = x_end[i];
    let pre = heading_before[i];
    var vel = v[i];
    let r = p.radius;
    var contacts = 0u;
    for (var k = 0u; k < p.obstacles + 1u; k++) {
        var n = vec2<real>(0.0, 1.0);
        var sv = vec2<real>(0.0, 0.0);
        if (k < p.obstacles) {
            let o = obstacles[k];
            if (length(x - o.center) > bound(o) + r + real(2.0) * SLOP) { continue; }
            let dn = distance_to(o, x);
            if (dn.d >= r + SLOP) { continue; }
            n = dn.n;
            sv = velocity_at(o, x);
        } else if ((p.flags & 1u) == 0u || x.y >= p.ground + r + SLOP) {
            continue;
        }
        let end = dot(vel - sv, n);
        let before = dot(pre - sv, n);
        var bounce = real(0.0);
        if (-before > p.rest_speed) { bounce = -before * p.restitution; }
        var normal = max(end, real(0.0));
        if (before < real(0.0)) { normal = bounce; }
        vel += n * (normal - end);
        contacts++;
    }
    v[i] = vel;
    if (contacts > 0u) {
        atomicAdd(&counter[0], contacts);
    }
}

// After each step's contact: the step's contact count is kept as the last step's, and
// (`advance`) the obstacles move by their velocities (kinematic bodies) over a span
// (`ContactPass::place`: to where the next step ends). Under XPBD they move a substep at a
// time inside it (`move_obstacles`), and its step ends with the count alone (`count`).
fn keep_count() {
    // With the pairs touching (each pair once): the first iteration's, or the velocity
    // pass's, whichever saw more.
    let pairs = max(atomicLoad(&control[FIRST]), atomicLoad(&control[TOUCHING])) / 2u;
    atomicStore(&counter[1], atomicLoad(&counter[0]));
    atomicStore(&counter[2], pairs);
    atomicStore(&counter[0], 0u);
}

fn move_obstacle(k: u32) {
    obstacles[k].center += obstacles[k].velocity * obstacles[k].span;
    if (obstacles[k].angular_velocity != real(0.0)) {
        obstacles[k].rotation = rotate(obstacles[k].rotation, obstacles[k].turn);
    }
}

@compute @workgroup_size(64)
fn advance(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k == 0u) { keep_count(); }
    if (k < p.obstacles) { move_obstacle(k); }
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x == 0u) { keep_count(); }
}

@compute @workgroup_size(64)
fn move_obstacles(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < p.obstacles) { move_obstacle(id.x); }
}
