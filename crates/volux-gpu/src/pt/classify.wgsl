// Projected Tetrahedra, first pass (seed 000 section 4.1, seed 002 section 4.1): the kept
// set under the TF and the isovalues (`keep`, run when they change), the mesh vertices
// projected and snapped to the 1/256 pixel grid (`project`), then per kept tetrahedron
// (`classify`) the culling by the clipping planes, the four exact orientation tests, the
// ternary truth table, the thick vertex with its front and back depth, scalar and gradient
// (perspective-correct, as volux_render::pt::project), and the centroid's sort key.

struct View {
    eye: vec4f,
    right: vec4f,
    up: vec4f,
    forward: vec4f,
    // width, height, tetrahedra, vertices
    size: vec4u,
    // perspective (1) or orthographic (0), TF breakpoints, classifier entries, rule
    mode: vec4u,
    // tan(fov/2) or half the height, aspect, near distance, classifier lo
    lens: vec4f,
    // classifier entries per value unit, last entry, psi nodes per axis, unused
    table: vec4f,
    // isovalues, clipping planes, headlight (1) or directional light (0), unused
    extra: vec4u,
    // ambient, diffuse, specular, shininess
    shade: vec4f,
    // unit direction towards the light, minimum gradient
    light: vec4f,
    // per isovalue (value, 0, 0, 0) and its RGBA, sorted by value
    isos: array<vec4f, 32>,
    // per plane (normal, distance of the eye) and (normal . right, . up, . forward, 0)
    planes: array<vec4f, 16>,
}

// One classified tetrahedron: v[0..4] the thin vertices (x, y, depth, scalar), v[4] the thick
// vertex (x, y, z_f, s_f), v[5] (z_b, s_b, linear piece, table code or NONE), v[6] and v[7]
// the thick vertex's front and back gradients (with isosurfaces only).
struct Cell {
    v: array<vec4f, 8>,
}

const NONE: u32 = 0xffffffffu;
const SUBPIXEL: f32 = 256.0;
const GUARD_BAND: f32 = 1.0e6;

@group(0) @binding(0) var<uniform> view: View;
// (x, y, z, scalar) per vertex.
@group(0) @binding(1) var<storage, read> positions: array<vec4f>;
@group(0) @binding(2) var<storage, read_write> screen: array<vec4f>;
@group(0) @binding(3) var<storage, read> tets: array<vec4u>;
// Vertex gradients (read with isosurfaces only).
@group(0) @binding(4) var<storage, read> gradients: array<vec4f>;
// Per entry: kind | fan length << 8, topology vertices (bytes), fan indices 0-3, 4-5.
@group(0) @binding(5) var<storage, read> table: array<vec4u, 81>;
// Per TF piece k: (breakpoint k, extinction non-zero on piece k, 0, 0); K + 1 entries.
@group(0) @binding(6) var<storage, read> pieces: array<vec4f>;
@group(0) @binding(7) var<storage, read_write> cells: array<Cell>;
@group(0) @binding(8) var<storage, read_write> items: array<vec2u>;
// Per tetrahedron: 1 kept (finite values, non-zero extinction or an isovalue in its range).
@group(0) @binding(9) var<storage, read_write> kept: array<u32>;
// Kept tetrahedra (written by `keep`).
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;

fn index(id: vec3u, groups: vec3u) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn snap(x: f32) -> f32 {
    return floor(x * SUBPIXEL + 0.5) / SUBPIXEL;
}

@compute @workgroup_size(64)
fn project(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = index(id, groups);
    if i >= view.size.w {
        return;
    }
    let d = positions[i].xyz - view.eye.xyz;
    let depth = dot(d, view.forward.xyz);
    var div = view.lens.x;
    if view.mode.x == 1u {
        if !(depth > view.lens.z) {
            screen[i] = vec4f(0.0, 0.0, depth, 0.0);
            return;
        }
        div = depth * view.lens.x;
    }
    let x = dot(d, view.right.xyz) / div;
    let y = dot(d, view.up.xyz) / div;
    let px = (x / view.lens.y + 1.0) * 0.5 * f32(view.size.x);
    let py = (1.0 - y) * 0.5 * f32(view.size.y);
    let inside = abs(px) <= GUARD_BAND && abs(py) <= GUARD_BAND;
    screen[i] = vec4f(snap(px), snap(py), depth, select(0.0, 1.0, inside));
}

// --- exact orientation on the 1/256 grid: products of differences below 2^29 -----------

// The 64-bit product of a and b as (high, low).
fn mul_wide(a: u32, b: u32) -> vec2u {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let lo1 = p00 + (p01 << 16u);
    let c1 = select(0u, 1u, lo1 < p00);
    let lo = lo1 + (p10 << 16u);
    let c2 = select(0u, 1u, lo < lo1);
    return vec2u(a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + c1 + c2, lo);
}

fn compare_wide(x: vec2u, y: vec2u) -> i32 {
    if x.x != y.x {
        return select(-1, 1, x.x > y.x);
    }
    if x.y != y.y {
        return select(-1, 1, x.y > y.y);
    }
    return 0;
}

// sign(a b - c d), exactly.
fn sign_of_difference(a: i32, b: i32, c: i32, d: i32) -> i32 {
    let s1 = sign(a) * sign(b);
    let s2 = sign(c) * sign(d);
    if s1 != s2 {
        return sign(s1 - s2);
    }
    if s1 == 0 {
        return 0;
    }
    let m1 = mul_wide(u32(abs(a)), u32(abs(b)));
    let m2 = mul_wide(u32(abs(c)), u32(abs(d)));
    return s1 * compare_wide(m1, m2);
}

fn orient(a: vec2i, b: vec2i, c: vec2i) -> i32 {
    return sign_of_difference(b.x - a.x, c.y - a.y, b.y - a.y, c.x - a.x);
}

// --- the discard (seed 002 section 4.5): zero extinction over the cell's value range ---

fn visible(lo: f32, hi: f32) -> bool {
    if crossed(lo, hi) {
        return true;
    }
    let k = view.mode.y;
    var a = 0u;
    var b = 0u;
    for (var j = 0u; j < k; j++) {
        let knot = pieces[j].x;
        a += select(0u, 1u, knot < lo);
        b += select(0u, 1u, knot <= hi);
    }
    for (var j = a; j <= b; j++) {
        if pieces[j].y > 0.0 {
            return true;
        }
    }
    return false;
}

// Whether an isovalue lies in [lo, hi] (the CPU keeps such cells and draws them by the fan).
fn crossed(lo: f32, hi: f32) -> bool {
    for (var j = 0u; j < view.extra.x; j++) {
        let v = view.isos[2u * j].x;
        if lo <= v && v <= hi {
            return true;
        }
    }
    return false;
}

// Whether the four vertices (relative to the eye) are all strictly outside one clipping plane.
fn outside_a_plane(p: array<vec3f, 4>) -> bool {
    for (var j = 0u; j < view.extra.y; j++) {
        let a = view.planes[2u * j];
        var out = true;
        for (var k = 0u; k < 4u; k++) {
            out = out && dot(a.xyz, p[k]) + a.w < 0.0;
        }
        if out {
            return true;
        }
    }
    return false;
}

// --- the thick vertex --------------------------------------------------------------------

struct Tet {
    xy: array<vec2f, 4>,
    z: vec4f,
    s: vec4f,
    g: array<vec3f, 4>,
}

struct Point {
    z: f32,
    s: f32,
    g: vec3f,
}

fn gradient_at(t: Tet, k: vec4f) -> vec3f {
    return t.g[0] * k.x + t.g[1] * k.y + t.g[2] * k.z + t.g[3] * k.w;
}

// The point at screen-space weights w of the four vertices (perspective-correct).
fn point(t: Tet, w: vec4f) -> Point {
    if view.mode.x == 1u {
        let k = w / t.z;
        var inv = k.x + k.y + k.z + k.w;
        if !(inv > 0.0) {
            inv = 1.17549435e-38;
        }
        let z = 1.0 / inv;
        return Point(z, dot(k, t.s) * z, gradient_at(t, k) * z);
    }
    return Point(dot(w, t.z), dot(w, t.s), gradient_at(t, w));
}

fn unit(i: u32) -> vec4f {
    return vec4f(f32(i == 0u), f32(i == 1u), f32(i == 2u), f32(i == 3u));
}

fn area2(a: vec2f, b: vec2f, c: vec2f) -> f32 {
    let u = b - a;
    let v = c - a;
    return u.x * v.y - u.y * v.x;
}

fn unit_or_half(x: f32) -> f32 {
    if finite(x) {
        return clamp(x, 0.0, 1.0);
    }
    return 0.5;
}

fn crossing(a: vec2f, b: vec2f, c: vec2f, d: vec2f) -> f32 {
    let na = area2(c, d, a);
    let nb = area2(c, d, b);
    return unit_or_half(na / (na - nb));
}

fn byte(x: u32, i: u32) -> u32 {
    return (x >> (8u * i)) & 0xffu;
}

struct Thick {
    xy: vec2f,
    a: Point,
    b: Point,
}

fn thick(t: Tet, e: vec4u, tests: vec4i) -> Thick {
    let kind = e.x & 0xffu;
    let i0 = byte(e.y, 0u);
    let i1 = byte(e.y, 1u);
    let i2 = byte(e.y, 2u);
    let i3 = byte(e.y, 3u);
    let p = t.xy;
    switch kind {
        case 1u: {
            // Interior: vertex i0 inside the face (i1, i2, i3), which is test 3 - i0.
            let s = f32(tests[3u - i0]);
            let raw = max(vec3f(
                s * area2(p[i0], p[i2], p[i3]),
                s * area2(p[i1], p[i0], p[i3]),
                s * area2(p[i1], p[i2], p[i0]),
            ), vec3f(0.0));
            let sum = raw.x + raw.y + raw.z;
            var w = vec3f(1.0 / 3.0);
            if sum > 0.0 && finite(sum) {
                w = raw / sum;
            }
            let face = unit(i1) * w.x + unit(i2) * w.y + unit(i3) * w.z;
            return Thick(p[i0], point(t, unit(i0)), point(t, face));
        }
        case 2u: {
            // Crossing edges (i0, i1) and (i2, i3).
            let u = crossing(p[i0], p[i1], p[i2], p[i3]);
            let v = crossing(p[i2], p[i3], p[i0], p[i1]);
            let lo = min(min(p[0], p[1]), min(p[2], p[3]));
            let hi = max(max(p[0], p[1]), max(p[2], p[3]));
            let at = clamp(p[i0] * (1.0 - u) + p[i1] * u, lo, hi);
            let a = point(t, unit(i0) * (1.0 - u) + unit(i1) * u);
            let b = point(t, unit(i2) * (1.0 - v) + unit(i3) * v);
            return Thick(vec2f(snap(at.x), snap(at.y)), a, b);
        }
        case 3u: {
            // On edge: vertex i0 on the edge (i1, i2).
            let d = p[i2] - p[i1];
            let u = unit_or_half(dot(p[i0] - p[i1], d) / dot(d, d));
            let b = point(t, unit(i1) * (1.0 - u) + unit(i2) * u);
            return Thick(p[i0], point(t, unit(i0)), b);
        }
        default: {
            // Coincident pair (i0, i1).
            return Thick(p[i0], point(t, unit(i0)), point(t, unit(i1)));
        }
    }
}

// The sort key of a depth: unsigned order is numeric order (volux_render::pt::sort::depth_key).
fn depth_key(d: f32) -> u32 {
    if d != d {
        return NONE;
    }
    let bits = select(bitcast<u32>(d), 0u, d == 0.0);
    if (bits & 0x80000000u) != 0u {
        return ~bits;
    }
    return bits | 0x80000000u;
}

fn centroid_depth(ids: vec4u) -> f32 {
    let c = 0.25 * (positions[ids.x].xyz + positions[ids.y].xyz + positions[ids.z].xyz
        + positions[ids.w].xyz) - view.eye.xyz;
    if view.mode.x == 1u {
        return length(c);
    }
    return dot(c, view.forward.xyz);
}

fn skip(i: u32) {
    var cell: Cell;
    cell.v[5] = vec4f(0.0);
    cell.v[5].w = bitcast<f32>(NONE);
    cells[i] = cell;
    items[i] = vec2u(NONE, i);
}

@compute @workgroup_size(64)
fn classify(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = index(id, groups);
    if i >= view.size.z {
        return;
    }
    let ids = tets[i];
    let pos = array<vec4f, 4>(positions[ids.x], positions[ids.y], positions[ids.z],
        positions[ids.w]);
    let s = vec4f(pos[0].w, pos[1].w, pos[2].w, pos[3].w);
    let q = array<vec4f, 4>(screen[ids.x], screen[ids.y], screen[ids.z], screen[ids.w]);
    let valid = q[0].w * q[1].w * q[2].w * q[3].w > 0.0;
    if !(kept[i] != 0u && valid) {
        skip(i);
        return;
    }
    let rel = array<vec3f, 4>(pos[0].xyz - view.eye.xyz, pos[1].xyz - view.eye.xyz,
        pos[2].xyz - view.eye.xyz, pos[3].xyz - view.eye.xyz);
    if view.extra.y > 0u && outside_a_plane(rel) {
        skip(i);
        return;
    }
    var f: array<vec2i, 4>;
    for (var k = 0u; k < 4u; k++) {
        f[k] = vec2i(i32(q[k].x * SUBPIXEL), i32(q[k].y * SUBPIXEL));
    }
    let tests = vec4i(orient(f[0], f[1], f[2]), orient(f[0], f[1], f[3]),
        orient(f[0], f[2], f[3]), orient(f[1], f[2], f[3]));
    let code = u32(dot(tests + vec4i(1), vec4i(27, 9, 3, 1)));
    let e = table[code];
    if (e.x & 0xffu) == 0u {
        skip(i);
        return;
    }
    // Coordinates relative to vertex 0: exact differences, smaller products.
    let o = q[0].xy;
    var t: Tet;
    for (var k = 0u; k < 4u; k++) {
        t.xy[k] = q[k].xy - o;
    }
    t.z = vec4f(q[0].z, q[1].z, q[2].z, q[3].z);
    t.s = s;
    let lit = view.extra.x > 0u;
    if lit {
        t.g = array<vec3f, 4>(gradients[ids.x].xyz, gradients[ids.y].xyz, gradients[ids.z].xyz,
            gradients[ids.w].xyz);
    }
    let th = thick(t, e, tests);
    var front = th.a;
    var back = th.b;
    if th.a.z > th.b.z {
        front = th.b;
        back = th.a;
    }
    var cell: Cell;
    for (var k = 0u; k < 4u; k++) {
        cell.v[k] = vec4f(q[k].xy, q[k].z, s[k]);
    }
    cell.v[4] = vec4f(th.xy + o, front.z, front.s);
    cell.v[5] = vec4f(back.z, back.s, 0.0, bitcast<f32>(code));
    cell.v[6] = vec4f(front.g, 0.0);
    cell.v[7] = vec4f(back.g, 0.0);
    cells[i] = cell;
    items[i] = vec2u(depth_key(centroid_depth(ids)), i);
}

// The kept set (seed 002 section 4.5, volux_render::pt::render's `update_kept`): cells with
// finite values whose range has non-zero extinction or holds an isovalue. Non-finite values
// colour nothing on the CPU: such cells are dropped here.
@compute @workgroup_size(64)
fn keep(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let i = index(id, groups);
    if i >= view.size.z {
        return;
    }
    let ids = tets[i];
    let s = vec4f(positions[ids.x].w, positions[ids.y].w, positions[ids.z].w,
        positions[ids.w].w);
    let lo = min(min(s.x, s.y), min(s.z, s.w));
    let hi = max(max(s.x, s.y), max(s.z, s.w));
    let keep = finite(lo) && finite(hi) && visible(lo, hi);
    kept[i] = select(0u, 1u, keep);
    if keep {
        atomicAdd(&counters[0], 1u);
    }
}
