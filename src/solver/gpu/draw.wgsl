// The drawing of a state on the card (src/solver/gpu/draw.rs): each spring a quad coloured by
// its strain, each particle a hexagon coloured by its kind, written straight into a mesh's
// vertex buffer, so that a state the card steps is drawn without coming back to the CPU. A
// vertex is (x, y, z) then a linear RGBA colour: seven f32s (a mesh of positions and colours,
// its attributes interleaved in the order of their ids).
//
// `real` is the state's width, f32 or f64 (the host rewrites the alias).

alias real = f32;

struct Params {
    particles: u32,
    springs: u32,
    // The particle drawn as held, or 0xffffffff.
    held: u32,
    // Where the springs' quads and the dots begin in the vertices bound, in f32s.
    springs_at: u32,
    dots_at: u32,
    // Entries of the strain palette, from fully compressed to fully stretched.
    palette_len: u32,
    pad0: u32,
    pad1: u32,
    // Half a spring's width, and a dot's radius, m.
    half_width: f32,
    radius: f32,
    // The strain drawn in full colour.
    full_strain: f32,
    pad2: f32,
    free_colour: vec4<f32>,
    pinned_colour: vec4<f32>,
    held_colour: vec4<f32>,
}

// A spring's ends and its rest length (as f32 bits).
struct Spring {
    a: u32,
    b: u32,
    rest: f32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> x: array<vec2<real>>;
@group(0) @binding(2) var<storage, read> inv_mass: array<real>;
@group(0) @binding(3) var<storage, read> springs: array<Spring>;
@group(0) @binding(4) var<storage, read> palette: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> vertices: array<f32>;

const DOT_SIDES: u32 = 6u;
const TAU: f32 = 6.283185307179586;

fn thread(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

// Vertex `vertex` of the run that begins at f32 `first`.
fn put(first: u32, vertex: u32, at: vec2<f32>, colour: vec4<f32>) {
    let o = first + vertex * 7u;
    vertices[o] = at.x;
    vertices[o + 1u] = at.y;
    vertices[o + 2u] = 0.0;
    vertices[o + 3u] = colour.x;
    vertices[o + 4u] = colour.y;
    vertices[o + 5u] = colour.z;
    vertices[o + 6u] = colour.w;
}

// The palette's colour for a strain: its entries span ±full_strain; NaN (a spring blown up)
// is drawn at rest.
fn strain_colour(strain: f32) -> vec4<f32> {
    let last = p.palette_len - 1u;
    if (strain != strain) { return palette[last / 2u]; }
    let t = clamp(strain / p.full_strain, -1.0, 1.0);
    let i = u32(round((t + 1.0) * 0.5 * f32(last)));
    return palette[min(i, last)];
}

@compute @workgroup_size(64)
fn draw_springs(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = thread(id, groups);
    if (s >= p.springs) { return; }
    let spring = springs[s];
    let a = vec2<f32>(x[spring.a]);
    let b = vec2<f32>(x[spring.b]);
    let d = b - a;
    let l = length(d);
    var strain = 0.0;
    if (spring.rest > 0.0) { strain = l / spring.rest - 1.0; }
    var n = vec2<f32>(0.0, 0.0);
    if (l > 0.0) { n = vec2<f32>(-d.y, d.x) / l * p.half_width; }
    let c = strain_colour(strain);
    let v = 4u * s;
    put(p.springs_at, v, a + n, c);
    put(p.springs_at, v + 1u, a - n, c);
    put(p.springs_at, v + 2u, b - n, c);
    put(p.springs_at, v + 3u, b + n, c);
}

@compute @workgroup_size(64)
fn draw_dots(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread(id, groups);
    if (i >= p.particles) { return; }
    let c = vec2<f32>(x[i]);
    var colour = p.free_colour;
    if (i == p.held) {
        colour = p.held_colour;
    } else if (inv_mass[i] == real(0.0)) {
        colour = p.pinned_colour;
    }
    let v = DOT_SIDES * i;
    for (var k = 0u; k < DOT_SIDES; k++) {
        let angle = f32(k) * TAU / f32(DOT_SIDES);
        put(p.dots_at, v + k, c + vec2<f32>(cos(angle), sin(angle)) * p.radius, colour);
    }
}
