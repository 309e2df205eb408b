// Projected Tetrahedra, second pass (seed 000 section 4.3, seed 002 sections 4.3-4.4): the
// fans drawn front to back (12 vertices a cell: up to 4 triangles around the thick vertex),
// the vertex shader pulling the classified cell, the fragment shader colouring the ray
// segment from (s_f, s_b, l), interpolated perspective-correctly front and back apart, as
// volux_render::pt::render does it; the blend is premultiplied "under" (1 - dst.a, 1).

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

struct Cell {
    v: array<vec4f, 8>,
}

// A linear piece of the TF: colour and extinction at `origin.x` and their slopes.
struct Piece {
    origin: vec4f,
    at: vec4f,
    slope: vec4f,
}

const NONE: u32 = 0xffffffffu;
const THIN: f32 = 0.125;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> cells: array<Cell>;
@group(0) @binding(2) var<storage, read> order: array<vec2u>;
@group(0) @binding(3) var<storage, read> table: array<vec4u, 81>;
@group(0) @binding(4) var<storage, read> knots: array<vec4f>;
@group(0) @binding(5) var<storage, read> pieces: array<Piece>;
@group(0) @binding(6) var<storage, read> entries: array<vec4f>;
@group(0) @binding(7) var psi: texture_2d<f32>;
// The cells' vertices and the vertex gradients (read with isosurfaces only).
@group(0) @binding(8) var<storage, read> tets: array<vec4u>;
@group(0) @binding(9) var<storage, read> gradients: array<vec4f>;

struct Varyings {
    @builtin(position) position: vec4f,
    // (k, k z, k s) front and back, k = 1 / z (perspective) or 1: screen-linear.
    @location(0) @interpolate(linear) front: vec3f,
    @location(1) @interpolate(linear) back: vec3f,
    @location(2) @interpolate(flat) piece: u32,
    // k g front and back (isosurfaces only).
    @location(3) @interpolate(linear) g_front: vec3f,
    @location(4) @interpolate(linear) g_back: vec3f,
}

fn byte(x: u32, i: u32) -> u32 {
    return (x >> (8u * i)) & 0xffu;
}

fn fan_index(e: vec4u, j: u32) -> u32 {
    if j < 4u {
        return byte(e.z, j);
    }
    return byte(e.w, j - 4u);
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Varyings {
    var out: Varyings;
    out.position = vec4f(2.0, 2.0, 0.5, 1.0);
    out.piece = NONE;
    let slot = vi / 12u;
    let n = view.size.z;
    if slot >= n {
        return out;
    }
    let id = order[slot].y;
    let c = cells[id];
    let code = bitcast<u32>(c.v[5].w);
    if code >= 81u {
        return out;
    }
    let e = table[code];
    let triangles = ((e.x >> 8u) & 0xffu) - 2u;
    let tri = (vi % 12u) / 3u;
    let corner = vi % 3u;
    if tri >= triangles {
        return out;
    }
    let p = fan_index(e, select(tri + corner, 0u, corner == 0u));
    var xy = c.v[4].xy;
    var f = c.v[4].zw;
    var b = c.v[5].xy;
    var gf = c.v[6].xyz;
    var gb = c.v[7].xyz;
    if p < 4u {
        xy = c.v[p].xy;
        f = c.v[p].zw;
        b = f;
        if view.extra.x > 0u {
            gf = gradients[tets[id][p]].xyz;
            gb = gf;
        }
    }
    var kf = 1.0;
    var kb = 1.0;
    if view.mode.x == 1u {
        kf = 1.0 / f.x;
        kb = 1.0 / b.x;
    }
    let w = vec2f(view.size.xy);
    out.position = vec4f(2.0 * xy.x / w.x - 1.0, 1.0 - 2.0 * xy.y / w.y, 0.5, 1.0);
    out.front = vec3f(kf, kf * f.x, kf * f.y);
    out.back = vec3f(kb, kb * b.x, kb * b.y);
    out.g_front = kf * gf;
    out.g_back = kb * gb;
    // The cell's linear TF piece (the average rule only; the TF may change without the cells).
    if view.mode.w == 0u {
        let s = vec4f(c.v[0].w, c.v[1].w, c.v[2].w, c.v[3].w);
        out.piece = linear_piece(min(min(s.x, s.y), min(s.z, s.w)),
            max(max(s.x, s.y), max(s.z, s.w)));
    }
    return out;
}

// Whether an isovalue lies in [lo, hi].
fn crossed(lo: f32, hi: f32) -> bool {
    for (var j = 0u; j < view.extra.x; j++) {
        let v = view.isos[2u * j].x;
        if lo <= v && v <= hi {
            return true;
        }
    }
    return false;
}

// The TF piece of the whole range [lo, hi], or NONE when a breakpoint or an isovalue lies
// inside it (the CPU's FragmentShader::linear_on).
fn linear_piece(lo: f32, hi: f32) -> u32 {
    if crossed(lo, hi) {
        return NONE;
    }
    let k = view.mode.y;
    var first = 0u;
    for (var j = 0u; j < k; j++) {
        first += select(0u, 1u, knots[j].x <= lo);
    }
    if first < k && knots[first].x < hi {
        return NONE;
    }
    return first;
}

// --- colour (volux_render::integrate::psi) ---------------------------------------------

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn clamp_or_lo(x: f32, lo: f32, hi: f32) -> f32 {
    if x > lo {
        return min(x, hi);
    }
    return lo;
}

// 1 - exp(-d), range-reduced as on the CPU.
fn opacity(depth: f32) -> f32 {
    let d = clamp_or_lo(depth, 0.0, 87.0);
    let k = i32(d * 1.44269504 + 0.5);
    let kf = f32(k);
    let x = -((d - kf * 0.69314575) - kf * 1.4286068e-6);
    let x2 = x * x;
    let x4 = x2 * x2;
    let p01 = 0.5 + x * (1.0 / 6.0);
    let p23 = 1.0 / 24.0 + x * (1.0 / 120.0);
    let p45 = 1.0 / 720.0 + x * (1.0 / 5040.0);
    let em = x + x2 * (p01 + x2 * p23 + x4 * p45);
    let scale = bitcast<f32>(u32(127 - k) << 23u);
    return (1.0 - scale) - scale * em;
}

fn lookup(s: f32) -> vec4f {
    let last = view.table.y;
    let x = min(max((s - view.lens.w) * view.table.x, 0.0), last);
    let i = min(u32(x), view.mode.z - 2u);
    let f = x - f32(i);
    let a = entries[i];
    return a + (entries[i + 1u] - a) * f;
}

fn piece_at(k: u32, s: f32) -> vec4f {
    let p = pieces[k];
    return p.at + p.slope * (s - p.origin.x);
}

fn average_rgba(front: vec4f, back: vec4f, l: f32) -> vec4f {
    let alpha = opacity(0.5 * l * (front.w + back.w));
    let m = 0.5 * alpha;
    return vec4f((front.xyz + back.xyz) * m, alpha);
}

fn one_minus_psi_series(a: f32, b: f32) -> f32 {
    let k = 0.5 * (b - a);
    let a2 = a * a;
    let k2 = k * k;
    let ak = a * k;
    let i1 = 0.5 * a + k / 3.0;
    let i2 = a2 / 3.0 + 0.5 * ak + 0.2 * k2;
    let i3 = a2 * (0.25 * a + 0.6 * k) + k2 * (0.5 * a + k / 7.0);
    let i4 = a2 * (0.2 * a2 + 2.0 / 3.0 * a * k + 6.0 / 7.0 * k2) + k2 * (0.5 * ak + k2 / 9.0);
    return i1 - 0.5 * i2 + i3 / 6.0 - i4 / 24.0;
}

fn one_minus_psi_table(a: f32, b: f32) -> f32 {
    let tf = clamp_or_lo(a, 0.0, 1e15);
    let tb = clamp_or_lo(b, 0.0, 1e15);
    let rf = sqrt(1.0 + tf);
    let rb = sqrt(1.0 + tb);
    let pf = rf * (rf + 1.0);
    let pb = rb * (rb + 1.0);
    let inv = 1.0 / (pf * pb);
    let n = u32(view.table.z);
    let last = f32(n - 1u);
    let x = clamp(tf * pb * inv, 0.0, 1.0) * last;
    let y = clamp(tb * pf * inv, 0.0, 1.0) * last;
    let i = min(u32(x), n - 2u);
    let j = min(u32(y), n - 2u);
    let fi = x - f32(i);
    let fj = y - f32(j);
    let e00 = textureLoad(psi, vec2u(j, i), 0).x;
    let e01 = textureLoad(psi, vec2u(j + 1u, i), 0).x;
    let e10 = textureLoad(psi, vec2u(j, i + 1u), 0).x;
    let e11 = textureLoad(psi, vec2u(j + 1u, i + 1u), 0).x;
    let r0 = e00 + (e01 - e00) * fj;
    let r1 = e10 + (e11 - e10) * fj;
    return r0 + (r1 - r0) * fi;
}

fn psi_rgba(front: vec4f, back: vec4f, l: f32) -> vec4f {
    let a = max(front.w * l, 0.0);
    let b = max(back.w * l, 0.0);
    let alpha = opacity(0.5 * (a + b));
    var w: f32;
    if a + b < THIN {
        w = one_minus_psi_series(a, b);
    } else {
        w = one_minus_psi_table(a, b);
    }
    w = clamp_or_lo(w, 0.0, alpha);
    return vec4f(front.xyz * w + back.xyz * (alpha - w), alpha);
}

fn under(acc: vec4f, c: vec4f) -> vec4f {
    return acc + (1.0 - acc.w) * c;
}

// The TF piece holding value s (ties at a breakpoint: the piece above it).
fn piece_of(s: f32) -> u32 {
    var k = 0u;
    for (var j = 0u; j < view.mode.y; j++) {
        k += select(0u, 1u, knots[j].x <= s);
    }
    return k;
}

// One ψ piece from s0 to s1 over the length l.
fn psi_piece(s0: f32, s1: f32, l: f32) -> vec4f {
    if !(l > 0.0) {
        return vec4f(0.0);
    }
    let k = piece_of(0.5 * (s0 + s1));
    return psi_rgba(piece_at(k, s0), piece_at(k, s1), l);
}

// ψ colour cut at the breakpoints inside (s_f, s_b), pieces composited front to back.
fn psi_segment(s_f: f32, s_b: f32, l: f32) -> vec4f {
    let k = view.mode.y;
    if s_f == s_b {
        return psi_piece(s_f, s_b, l);
    }
    let per_value = l / abs(s_b - s_f);
    var acc = vec4f(0.0);
    var s0 = s_f;
    for (var j = 0u; j < k; j++) {
        var m = j;
        if s_f > s_b {
            m = k - 1u - j;
        }
        let knot = knots[m].x;
        if knot > min(s_f, s_b) && knot < max(s_f, s_b) {
            acc = under(acc, psi_piece(s0, knot, abs(knot - s0) * per_value));
            s0 = knot;
        }
    }
    return under(acc, psi_piece(s0, s_b, abs(s_b - s0) * per_value));
}

// The pixel's normalized ray coordinates (nx, ny), before the lens scale.
fn ndc(pixel: vec2f) -> vec2f {
    let w = f32(view.size.x);
    let h = f32(view.size.y);
    return vec2f((2.0 * pixel.x / w - 1.0) * (w / h), 1.0 - 2.0 * pixel.y / h);
}

fn secant(pixel: vec2f) -> f32 {
    if view.mode.x == 0u {
        return 1.0;
    }
    let n = ndc(pixel) * view.lens.x;
    return sqrt(1.0 + n.x * n.x + n.y * n.y);
}

// The pixel's ray direction (volux_render::pt::render's view_dir).
fn view_dir(pixel: vec2f) -> vec3f {
    if view.mode.x == 0u {
        return view.forward.xyz;
    }
    let n = ndc(pixel) * view.lens.x;
    return view.forward.xyz + view.right.xyz * n.x + view.up.xyz * n.y;
}

// --- isosurfaces (volux_render::integrate::fragment, seed 002 section 4.6) --------------

fn normalize_or_zero(v: vec3f) -> vec3f {
    let l = length(v);
    if l > 0.0 && finite(l) {
        return v / l;
    }
    return vec3f(0.0);
}

// Two-sided Blinn-Phong (volux_render::shading::BlinnPhong::shade).
fn shade(rgb: vec3f, gradient: vec3f, dir: vec3f) -> vec3f {
    let len = length(gradient);
    let to_eye = -normalize_or_zero(dir);
    if !(len >= view.light.w && len > 0.0 && finite(len)) || all(to_eye == vec3f(0.0)) {
        return rgb;
    }
    var n = gradient / len;
    if dot(n, to_eye) < 0.0 {
        n = -n;
    }
    var l = view.light.xyz;
    if view.extra.z == 1u {
        l = to_eye;
    }
    let n_l = dot(n, l);
    var diffuse = 0.0;
    var specular = 0.0;
    if n_l > 0.0 {
        let h = normalize_or_zero(l + to_eye);
        let n_h = max(dot(n, h), 0.0);
        diffuse = n_l;
        if view.shade.w == 0.0 {
            specular = 1.0;
        } else if n_h > 0.0 {
            specular = pow(n_h, view.shade.w);
        }
    }
    let k = view.shade.x + view.shade.y * diffuse;
    return rgb * k + vec3f(view.shade.z * specular);
}

// The volume colour of a segment (no isosurface inside).
fn segment(s_f: f32, s_b: f32, l: f32, piece: u32) -> vec4f {
    if !(l > 0.0) {
        return vec4f(0.0);
    }
    if view.mode.w == 1u {
        return psi_segment(s_f, s_b, l);
    }
    if piece != NONE {
        let mid = piece_at(piece, 0.5 * (s_f + s_b));
        return average_rgba(mid, mid, l);
    }
    return average_rgba(lookup(s_f), lookup(s_b), l);
}

// The segment cut at the isovalues it crosses (t in [0, 1), at most 8, as the CPU), the
// volume pieces and the lit surfaces composited front to back.
fn fragment_iso(s_f: f32, s_b: f32, l: f32, g_f: vec3f, g_b: vec3f, dir: vec3f) -> vec4f {
    let lo = min(s_f, s_b);
    let hi = max(s_f, s_b);
    var hits: array<vec2f, 8>;
    var n = 0u;
    for (var j = 0u; j < view.extra.x; j++) {
        let v = view.isos[2u * j].x;
        if v < lo {
            continue;
        }
        if v > hi {
            break;
        }
        let t = (v - s_f) / (s_b - s_f);
        if t >= 0.0 && t < 1.0 && n < 8u {
            hits[n] = vec2f(t, f32(j));
            n++;
        }
    }
    var acc = vec4f(0.0);
    var s0 = s_f;
    var t0 = 0.0;
    for (var m = 0u; m < n; m++) {
        var h = hits[m];
        if s_b < s_f {
            h = hits[n - 1u - m];
        }
        let j = u32(h.y);
        let v = view.isos[2u * j].x;
        let rgba = view.isos[2u * j + 1u];
        acc = under(acc, segment(s0, v, (h.x - t0) * l, NONE));
        let rgb = shade(rgba.xyz, g_f + (g_b - g_f) * h.x, dir);
        acc = under(acc, vec4f(rgb * rgba.w, rgba.w));
        s0 = v;
        t0 = h.x;
    }
    return under(acc, segment(s0, s_b, (1.0 - t0) * l, NONE));
}

// --- clipping planes (volux_render::pt::clip, seed 004 chapter 4) -----------------------

const BIG: f32 = 3.0e38;

// The pixel's window of view depth inside every plane; empty: (1, 0).
fn window(pixel: vec2f) -> vec2f {
    let n = ndc(pixel) * view.lens.x;
    var z0 = -BIG;
    var z1 = BIG;
    for (var j = 0u; j < view.extra.y; j++) {
        let a = view.planes[2u * j];
        let b = view.planes[2u * j + 1u];
        let across = b.x * n.x + b.y * n.y;
        var d0 = a.w;
        var rate = b.z;
        if view.mode.x == 1u {
            rate += across;
        } else {
            d0 += across;
        }
        if rate > 0.0 {
            z0 = max(z0, -d0 / rate);
        } else if rate < 0.0 {
            z1 = min(z1, -d0 / rate);
        } else if d0 < 0.0 {
            return vec2f(1.0, 0.0);
        }
    }
    if !(z1 > z0) {
        return vec2f(1.0, 0.0);
    }
    return vec2f(z0, z1);
}

struct Span {
    z_f: f32,
    s_f: f32,
    z_b: f32,
    s_b: f32,
    g_f: vec3f,
    g_b: vec3f,
    kept: bool,
}

// The span trimmed to the window, the scalars and gradients interpolated at the new ends
// (volux_render::pt::clip::DepthSpan::trim).
fn trim(in: Span, w: vec2f) -> Span {
    var out = in;
    if in.z_b <= w.x || in.z_f >= w.y || w.x > w.y {
        out.kept = false;
        return out;
    }
    let d = in.z_b - in.z_f;
    var a = 0.0;
    var b = 1.0;
    if d > 0.0 {
        a = (max(in.z_f, w.x) - in.z_f) / d;
        b = (min(in.z_b, w.y) - in.z_f) / d;
    }
    out.z_f = max(in.z_f, w.x);
    out.z_b = min(in.z_b, w.y);
    if a > 0.0 {
        out.s_f = in.s_f + (in.s_b - in.s_f) * a;
    }
    if b < 1.0 {
        out.s_b = in.s_f + (in.s_b - in.s_f) * b;
        out.g_b = in.g_f + (in.g_b - in.g_f) * b;
    }
    out.g_f = in.g_f + (in.g_b - in.g_f) * a;
    if a >= 1.0 {
        out.g_f = in.g_b;
    }
    return out;
}

@fragment
fn fs(in: Varyings) -> @location(0) vec4f {
    var span: Span;
    span.z_f = in.front.y / in.front.x;
    span.z_b = in.back.y / in.back.x;
    if view.mode.x == 1u {
        span.z_f = 1.0 / in.front.x;
        span.z_b = 1.0 / in.back.x;
    }
    span.s_f = in.front.z / in.front.x;
    span.s_b = in.back.z / in.back.x;
    let lit = view.extra.x > 0u;
    if lit {
        span.g_f = in.g_front / max(in.front.x, 1.17549435e-38);
        span.g_b = in.g_back / max(in.back.x, 1.17549435e-38);
    }
    span.kept = true;
    if view.extra.y > 0u {
        span = trim(span, window(in.position.xy));
        if !span.kept {
            discard;
        }
    }
    let l = max((span.z_b - span.z_f) * secant(in.position.xy), 0.0);
    if !(finite(l) && finite(span.s_f) && finite(span.s_b)) {
        return vec4f(0.0);
    }
    if lit && span.s_f != span.s_b {
        return fragment_iso(span.s_f, span.s_b, l, span.g_f, span.g_b,
            view_dir(in.position.xy));
    }
    return segment(span.s_f, span.s_b, l, in.piece);
}
