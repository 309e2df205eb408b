// Grid ray casting, one invocation per pixel, composited front to back in f32 (seed `001`).
// The same rays, sample lattice and tables as the CPU engine (`volux_render::raycast`):
//
// - Riemann (`001` eq. 2.14): sample i of a ray sits at t0 + (i + jitter) h, each slab
//   [t_i, t_i + h] takes the premultiplied entry of the step table, the last slab cut at the
//   ray's exit takes 1 - exp(-tau len) from the extinction table;
// - pre-integration (`000` §2.6): the segments between consecutive lattice points (the first
//   and last cut at the ray's ends) from the 2D table of their end values, a shortened one
//   opacity-corrected (`composite::under_partial`);
// - Blinn-Phong shading (`002` §4.6) with the gradient volume's gradients, or on the fly
//   (central differences at +-1 voxel, `shading::gradient`) for the isosurfaces of unshaded
//   volumes;
// - isosurfaces (`002` §4.6): crossings between consecutive samples, refined by Illinois
//   regula falsi on the field (`isosurface.rs`), lit and composited in depth order;
// - empty-space skipping: a sample in a macrocell whose values are all transparent (and hold
//   no isovalue) jumps to the first lattice point past the macrocell, so no sample moves;
// - the sculpt mask (`004` §4.4.1): a sample where the mask, interpolated, is under 0.5 is
//   undefined, as a NaN sample: it adds nothing, nor does a segment ending at it;
// - maximum intensity projection.

// The mode a pipeline draws (0 Riemann, 1 MIP, 2 pre-integration), fixed when it is
// created, as `FLAGS` (`field.wgsl`).
override MODE: u32 = 0u;

const MAX_ISO: u32 = 8u;
// Voxel cells per macrocell (`MacrocellGrid::BLOCK`).
const BLOCK: f32 = 8.0;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var volume: texture_3d<f32>;
// The slab table (premultiplied colour and opacity of one full slab), then the extinction
// table (colour and extinction per world unit), `size.w` entries each.
@group(0) @binding(2) var<storage, read> tables: array<vec4<f32>>;
// The pre-integration table, row-major by front value (one unused entry without it).
@group(0) @binding(3) var<storage, read> preint: array<vec4<f32>>;
// The clip planes (local frame: normal . p + w >= 0 is kept), then per isovalue its value
// (x) and its colour and opacity.
@group(0) @binding(4) var<storage, read> frame: array<vec4<f32>>;
// Per macrocell: 1 where rays sample it, 0 where they skip it.
@group(0) @binding(5) var<storage, read> cells: array<u32>;
// The sculpt mask, a bit per voxel (x fastest), 1 where kept.
@group(0) @binding(6) var<storage, read> mask_bits: array<u32>;
// The gradient volume: gradient counts per voxel (x, y, z, 0).
@group(0) @binding(7) var gradients: texture_3d<i32>;
@group(0) @binding(8) var<storage, read_write> out_rgba: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> out_samples: array<u32>;

// `PreintegrationTable::position_f32`: the row or column below s and the fraction.
fn preint_position(s: f32) -> vec2<f32> {
    let n = params.cells.w;
    let last = f32(n - 1u);
    var x = (s - params.spacing.w) * params.extra.x;
    x = select(0.0, x, x > 0.0);
    x = select(last, x, x < last);
    let i = min(floor(x), f32(n - 2u));
    return vec2<f32>(i, x - i);
}

// `PreintegrationTable::lookup_lanes`: the segment from s_f to s_b, bilinear.
fn preint_at(s_f: f32, s_b: f32) -> vec4<f32> {
    let n = params.cells.w;
    let a = preint_position(s_f);
    let b = preint_position(s_b);
    let row0 = u32(a.x) * n + u32(b.x);
    let row1 = row0 + n;
    let top = preint[row0] + (preint[row0 + 1u] - preint[row0]) * b.y;
    let bottom = preint[row1] + (preint[row1 + 1u] - preint[row1]) * b.y;
    return top + (bottom - top) * a.y;
}

// `composite::under_partial`: the entry of a full segment, cut to the fraction frac.
fn under_partial(acc: vec4<f32>, e: vec4<f32>, frac: f32) -> vec4<f32> {
    var alpha = e.w;
    if (frac < 0.999999) {
        alpha = 1.0 - pow(max(1.0 - e.w, 0.0), frac);
    }
    var scale = frac;
    if (e.w > 0.0) {
        scale = alpha / e.w;
    }
    return acc + (1.0 - acc.w) * vec4<f32>(e.xyz * scale, alpha);
}

// The distance at which the ray leaves the macrocell holding voxel-space p.
fn cell_exit(ray: Ray, p: vec3<f32>) -> f32 {
    let c = floor(max(p, vec3<f32>(0.0)) / BLOCK);
    let lo = c * BLOCK;
    let hi = lo + BLOCK;
    let inv = 1.0 / ray.d_v;
    let ta = (lo - ray.o_v) * inv;
    let tb = (hi - ray.o_v) * inv;
    let far = max(ta, tb);
    return min(min(far.x, far.y), far.z);
}

// Whether the macrocell holding voxel-space p is skipped.
fn skipped(p: vec3<f32>) -> bool {
    if (!flag(SKIP)) {
        return false;
    }
    let n = params.cells.xyz;
    let c = min(vec3<u32>(max(p, vec3<f32>(0.0)) / BLOCK), n - vec3<u32>(1u));
    return cells[c.x + n.x * (c.y + n.y * c.z)] == 0u;
}

// The first lattice index (start + i h) at or after the distance t, conservatively (a point
// on the boundary is sampled, not skipped).
fn index_after(start: f32, h: f32, t: f32, i: u32) -> u32 {
    let k = ceil((t - start) / h - 1e-3);
    return max(i + 1u, u32(max(k, 0.0)));
}

// The root of field - c between (ta, fa) and (tb, fb) of opposite signs (`isosurface::refine`):
// Illinois regula falsi with a bisection safeguard.
fn refine(ray: Ray, ta0: f32, fa0: f32, tb0: f32, fb0: f32, c: f32) -> f32 {
    var a = ta0;
    var fa = fa0;
    var b = tb0;
    var fb = fb0;
    let tol = 1e-5 * abs(tb0 - ta0);
    var kept = 0;
    var width = abs(b - a);
    for (var it = 0; it < 32; it++) {
        if (abs(b - a) <= tol) {
            break;
        }
        var t = secant(a, fa, b, fb);
        if (it % 3 == 2 && abs(b - a) > 0.5 * width) {
            t = 0.5 * (a + b);
        }
        if (it % 3 == 2) {
            width = abs(b - a);
        }
        let ft = field(ray.o_v + ray.d_v * t) - c;
        if (ft == 0.0) {
            return t;
        }
        if (is_nan(ft) || abs(ft) > 3.4e38) {
            break;
        }
        if ((ft < 0.0) == (fb < 0.0)) {
            b = t;
            fb = ft;
            if (kept == 1) {
                fa *= 0.5;
            }
            kept = 1;
        } else {
            a = t;
            fa = ft;
            if (kept == -1) {
                fb *= 0.5;
            }
            kept = -1;
        }
    }
    return secant(a, fa, b, fb);
}

fn secant(a: f32, fa: f32, b: f32, fb: f32) -> f32 {
    let t = a - fa * (b - a) / (fb - fa);
    if (t > min(a, b) && t < max(a, b)) {
        return t;
    }
    return 0.5 * (a + b);
}

// The isosurfaces crossed between (tp, vp) and (t, v), lit and composited under acc in depth
// order (`Isosurfaces::crossings`: an isovalue c in (vp, v] or [v, vp)).
fn isosurfaces(acc_in: vec4<f32>, ray: Ray, tp: f32, vp: f32, t: f32, v: f32) -> vec4<f32> {
    var acc = acc_in;
    if (is_nan(vp) || is_nan(v) || vp == v) {
        return acc;
    }
    var ts: array<f32, 8>;
    var ks: array<u32, 8>;
    var m = 0u;
    let planes = params.dims.w;
    for (var k = 0u; k < params.mode.w; k++) {
        let c = frame[planes + 2u * k].x;
        let crossed = (vp < v && vp < c && c <= v) || (v < vp && v <= c && c < vp);
        if (!crossed) {
            continue;
        }
        var tc = t;
        if (v != c) {
            tc = refine(ray, tp, vp - c, t, v - c, c);
        }
        // Insertion by depth.
        var j = m;
        while (j > 0u && ts[j - 1u] > tc) {
            ts[j] = ts[j - 1u];
            ks[j] = ks[j - 1u];
            j -= 1u;
        }
        ts[j] = tc;
        ks[j] = k;
        m += 1u;
    }
    for (var j = 0u; j < m; j++) {
        let iso = frame[planes + 2u * ks[j] + 1u];
        var rgb = iso.xyz;
        if (flag(ISO_LIT)) {
            rgb = shade(rgb, gradient_at(ray.o_v + ray.d_v * ts[j]), ray.view);
        }
        acc = under(acc, vec4<f32>(rgb * iso.w, iso.w));
    }
    return acc;
}

// The vertex of the parabola through (-h, y0), (0, y1), (h, y2) where y1 is the largest:
// (offset in [-h/2, h/2], value >= y1), or (0, y1) for a flat or non-peaked triple
// (`volux_render::mip::parabolic_peak`, in f32).
fn parabolic_peak(y0: f32, y1: f32, y2: f32, h: f32) -> vec2<f32> {
    let curv = y0 - 2.0 * y1 + y2;
    if (!(y0 <= y1 && y2 <= y1 && curv < 0.0)) {
        return vec2<f32>(0.0, y1);
    }
    let offset = clamp(h * (y0 - y2) / (2.0 * curv), -0.5 * h, 0.5 * h);
    let value = y1 - (y2 - y0) * (y2 - y0) / (8.0 * curv);
    return vec2<f32>(offset, max(value, y1));
}

struct Traced {
    rgba: vec4<f32>,
    samples: u32,
};

// Maximum intensity projection (`volux_render::mip::max_along`): the largest sample of the
// lattice t0 + i h <= t1 (the first of equal ones), refined by the parabola through it and
// its neighbours and polished by one more sample at the vertex; the TF colour there, opaque.
fn mip(ray: Ray) -> Traced {
    let h = params.origin.w;
    let base = ray.o_v + ray.d_v * ray.t0;
    let stride = ray.d_v * h;
    var found = false;
    var best = 0.0;
    var best_i = 0u;
    var before = nan();
    var after = nan();
    var waiting = false;
    var prev = nan();
    var samples = 0u;
    var i = 0u;
    loop {
        if (ray.t0 + h * f32(i) > ray.t1) {
            break;
        }
        let v = field(base + stride * f32(i));
        samples += 1u;
        if (waiting) {
            after = v;
        }
        let better = !is_nan(v) && (!found || v > best);
        waiting = better;
        if (better) {
            found = true;
            best = v;
            best_i = i;
            before = prev;
            after = nan();
        }
        prev = v;
        i += 1u;
    }
    if (!found) {
        return Traced(vec4<f32>(0.0), samples);
    }
    var v = best;
    if (!is_nan(before) && !is_nan(after)) {
        let peak = parabolic_peak(before, best, after, h);
        v = peak.y;
        if (peak.x != 0.0) {
            let s = field(ray.o_v + ray.d_v * (ray.t0 + h * f32(best_i) + peak.x));
            samples += 1u;
            if (!is_nan(s)) {
                v = select(best, s, s >= best);
            }
        }
    }
    return Traced(vec4<f32>(tau_at(v).xyz, 1.0), samples);
}

// The left Riemann sum with step-corrected opacity, lit and with isosurfaces when asked.
fn riemann(ray: Ray, jitter: f32) -> Traced {
    let h = params.origin.w;
    let stop = params.inv_spacing.w;
    let start = ray.t0 + jitter * h;
    let base = ray.o_v + ray.d_v * start;
    let stride = ray.d_v * h;
    var acc = vec4<f32>(0.0);
    var samples = 0u;
    var tp = 0.0;
    var vp = nan();
    var i = 0u;
    loop {
        let t = start + h * f32(i);
        if (t >= ray.t1) {
            break;
        }
        let p = base + stride * f32(i);
        if (skipped(p)) {
            i = index_after(start, h, cell_exit(ray, p), i);
            continue;
        }
        let v = field(p);
        samples += 1u;
        if (is_nan(v)) {
            vp = nan();
            i += 1u;
            continue;
        }
        if (flag(ISOSURFACES)) {
            acc = isosurfaces(acc, ray, tp, vp, t, v);
        }
        var e: vec4<f32>;
        if (t + h <= ray.t1) {
            e = slab_at(v);
        } else {
            let c = tau_at(v);
            let a = 1.0 - exp(-c.w * (ray.t1 - t));
            e = vec4<f32>(c.xyz * a, a);
        }
        acc = under(acc, lit(e, p, ray.view));
        tp = t;
        vp = v;
        if (acc.w >= stop) {
            break;
        }
        i += 1u;
    }
    return Traced(acc, samples);
}

// The value at distance t, clamped to the ray.
fn value_at(ray: Ray, t: f32) -> f32 {
    return field(ray.o_v + ray.d_v * clamp(t, ray.t0, ray.t1));
}

// Pre-integration: the segments between the lattice points start + i h (start = t0 +
// (jitter - 1) h), cut to the ray, each from the table of its end values.
fn preintegrated(ray: Ray, jitter: f32) -> Traced {
    let h = params.origin.w;
    let stop = params.inv_spacing.w;
    let start = ray.t0 + (jitter - 1.0) * h;
    var acc = vec4<f32>(0.0);
    var samples = 0u;
    var front = nan();
    var have_front = false;
    var i = 0u;
    loop {
        let ta = max(start + h * f32(i), ray.t0);
        let tb = min(start + h * f32(i + 1u), ray.t1);
        if (ta >= ray.t1) {
            break;
        }
        if (tb <= ta) {
            i += 1u;
            continue;
        }
        let pa = ray.o_v + ray.d_v * ta;
        if (skipped(pa)) {
            // Segments wholly in the macrocell add nothing: on from the last lattice point in
            // it, with a fresh front value.
            let k = index_after(start, h, cell_exit(ray, pa), i + 1u) - 1u;
            if (k > i) {
                i = k;
                have_front = false;
                continue;
            }
        }
        if (!have_front) {
            front = value_at(ray, ta);
            samples += 1u;
        }
        let back = value_at(ray, tb);
        samples += 1u;
        if (!is_nan(front) && !is_nan(back)) {
            let mid = ray.o_v + ray.d_v * (0.5 * (ta + tb));
            let e = lit(preint_at(front, back), mid, ray.view);
            acc = under_partial(acc, e, (tb - ta) / h);
        }
        front = back;
        have_front = true;
        i += 1u;
        if (acc.w >= stop) {
            break;
        }
    }
    return Traced(acc, samples);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let pixel = id.y * params.size.x + id.x;
    let ray = pixel_ray(id);
    if (!(ray.t1 > ray.t0)) {
        out_rgba[pixel] = vec4<f32>(0.0);
        out_samples[pixel] = 0u;
        return;
    }
    var jitter = 0.0;
    if (flag(JITTER)) {
        jitter = pixel_hash(id.x, id.y);
    }
    var traced: Traced;
    if (MODE == 1u) {
        traced = mip(ray);
    } else if (MODE == 2u) {
        traced = preintegrated(ray, jitter);
    } else {
        traced = riemann(ray, jitter);
    }
    out_rgba[pixel] = traced.rgba;
    out_samples[pixel] = traced.samples;
}
