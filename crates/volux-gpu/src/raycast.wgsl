// Grid ray casting, one invocation per pixel (seed `001`'s Riemann sum with step-corrected
// opacity, composited front to back in f32). The same rays, sample lattice and table as the
// CPU lanes (`volux_render::raycast::stream`): sample i of a ray sits at t0 + i h, each slab
// [t_i, t_i + h] takes the premultiplied slab entry of the step table, the last slab cut at the
// ray's exit takes 1 - exp(-tau len) from the extinction table, an undefined (NaN) sample adds
// nothing.

struct Params {
    // Camera in the grid's local frame (world units): eye, right, up, forward.
    eye: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
    // xyz: world position of sample (0,0,0); w: the step h (world units).
    origin: vec4<f32>,
    // xyz: 1 / spacing; w: the opacity at which a ray stops (2 without early termination).
    inv_spacing: vec4<f32>,
    // xyz: samples per axis; w: clip planes.
    dims: vec4<u32>,
    // width, height, projection (0 perspective, 1 orthographic), table entries.
    size: vec4<u32>,
    // tan(fov / 2) or the orthographic view height, aspect, table lo, table scale.
    lens: vec4<f32>,
    // x: 1 for maximum intensity projection.
    mode: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var volume: texture_3d<f32>;
// Per entry: premultiplied colour and opacity of one full slab.
@group(0) @binding(2) var<storage, read> slab_table: array<vec4<f32>>;
// Per entry: colour and extinction per world unit.
@group(0) @binding(3) var<storage, read> tau_table: array<vec4<f32>>;
// Local-frame clip planes: normal . p + w >= 0 is kept.
@group(0) @binding(4) var<storage, read> planes: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> out_rgba: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_samples: array<u32>;

fn is_nan(v: f32) -> bool {
    return (bitcast<u32>(v) & 0x7fffffffu) > 0x7f800000u;
}

fn axis(p: f32, n: u32) -> vec2<f32> {
    // The cell below p (clamped so that the cell exists) and the fraction in it.
    if (n < 2u) {
        return vec2<f32>(0.0, 0.0);
    }
    let i = clamp(floor(p), 0.0, f32(n - 2u));
    return vec2<f32>(i, p - i);
}

// Trilinear sample at voxel-space p, clamped to the box (the lattice lies in it but for
// rounding); NaN where a corner is undefined.
fn sample(q: vec3<f32>) -> f32 {
    let n = params.dims.xyz;
    let p = clamp(q, vec3<f32>(0.0), vec3<f32>(n - vec3<u32>(1u)));
    let ax = axis(p.x, n.x);
    let ay = axis(p.y, n.y);
    let az = axis(p.z, n.z);
    let b = vec3<i32>(i32(ax.x), i32(ay.x), i32(az.x));
    let d = vec3<i32>(select(0, 1, n.x > 1u), select(0, 1, n.y > 1u), select(0, 1, n.z > 1u));
    let v000 = textureLoad(volume, b, 0).r;
    let v100 = textureLoad(volume, b + vec3<i32>(d.x, 0, 0), 0).r;
    let v010 = textureLoad(volume, b + vec3<i32>(0, d.y, 0), 0).r;
    let v110 = textureLoad(volume, b + vec3<i32>(d.x, d.y, 0), 0).r;
    let v001 = textureLoad(volume, b + vec3<i32>(0, 0, d.z), 0).r;
    let v101 = textureLoad(volume, b + vec3<i32>(d.x, 0, d.z), 0).r;
    let v011 = textureLoad(volume, b + vec3<i32>(0, d.y, d.z), 0).r;
    let v111 = textureLoad(volume, b + vec3<i32>(d.x, d.y, d.z), 0).r;
    let c0 = mix(mix(v000, v100, ax.y), mix(v010, v110, ax.y), ay.y);
    let c1 = mix(mix(v001, v101, ax.y), mix(v011, v111, ax.y), ay.y);
    return mix(c0, c1, az.y);
}

// The table entry below value s and the fraction towards the next, as `LaneTable::position`
// computes them (NaN reads entry 0).
fn position(s: f32) -> vec2<f32> {
    let last = f32(params.size.w - 1u);
    var x = (s - params.lens.z) * params.lens.w;
    x = select(0.0, x, x > 0.0);
    x = select(last, x, x < last);
    let i = min(floor(x), f32(params.size.w - 2u));
    return vec2<f32>(i, x - i);
}

// The slab table at value s.
fn slab_at(s: f32) -> vec4<f32> {
    let p = position(s);
    let i = u32(p.x);
    return mix(slab_table[i], slab_table[i + 1u], p.y);
}

// The extinction table at value s.
fn tau_at(s: f32) -> vec4<f32> {
    let p = position(s);
    let i = u32(p.x);
    return mix(tau_table[i], tau_table[i + 1u], p.y);
}

// The ray's entry and exit distances through the box [0, dims - 1] (voxel space) and the
// clip planes (local frame); x > y when it misses.
fn extent(o: vec3<f32>, dir: vec3<f32>, o_v: vec3<f32>, d_v: vec3<f32>) -> vec2<f32> {
    let hi = vec3<f32>(params.dims.xyz - vec3<u32>(1u));
    let inv = 1.0 / d_v;
    let ta = (vec3<f32>(0.0) - o_v) * inv;
    let tb = (hi - o_v) * inv;
    let near = min(ta, tb);
    let far = max(ta, tb);
    var t0 = max(max(max(near.x, near.y), near.z), 0.0);
    var t1 = min(min(far.x, far.y), far.z);
    for (var k = 0u; k < params.dims.w; k++) {
        let pl = planes[k];
        let d0 = dot(pl.xyz, o) + pl.w;
        let rate = dot(pl.xyz, dir);
        if (rate > 0.0) {
            t0 = max(t0, -d0 / rate);
        } else if (rate < 0.0) {
            t1 = min(t1, -d0 / rate);
        } else if (d0 < 0.0) {
            t1 = t0 - 1.0;
        }
    }
    return vec2<f32>(t0, t1);
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
fn mip(o_v: vec3<f32>, d_v: vec3<f32>, t0: f32, t1: f32) -> Traced {
    let h = params.origin.w;
    let base = o_v + d_v * t0;
    let stride = d_v * h;
    let nan = bitcast<f32>(0x7fc00000u);
    var found = false;
    var best = 0.0;
    var best_i = 0u;
    var before = nan;
    var after = nan;
    var waiting = false;
    var prev = nan;
    var samples = 0u;
    var i = 0u;
    loop {
        if (t0 + h * f32(i) > t1) {
            break;
        }
        let v = sample(base + stride * f32(i));
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
            after = nan;
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
            let s = sample(o_v + d_v * (t0 + h * f32(best_i) + peak.x));
            samples += 1u;
            if (!is_nan(s)) {
                v = select(best, s, s >= best);
            }
        }
    }
    return Traced(vec4<f32>(tau_at(v).xyz, 1.0), samples);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.size.x;
    let h = params.size.y;
    if (id.x >= w || id.y >= h) {
        return;
    }
    let pixel = id.y * w + id.x;
    let nx = (2.0 * (f32(id.x) + 0.5) / f32(w) - 1.0) * params.lens.y;
    let ny = 1.0 - 2.0 * (f32(id.y) + 0.5) / f32(h);
    var o = params.eye.xyz;
    var dir = params.forward.xyz;
    if (params.size.z == 0u) {
        let t = params.lens.x;
        dir = normalize(params.forward.xyz + params.right.xyz * (nx * t) + params.up.xyz * (ny * t));
    } else {
        o = o + (params.right.xyz * nx + params.up.xyz * ny) * (params.lens.x * 0.5);
    }
    let o_v = (o - params.origin.xyz) * params.inv_spacing.xyz;
    let d_v = dir * params.inv_spacing.xyz;
    let span = extent(o, dir, o_v, d_v);
    if (params.mode.x == 1u && span.y > span.x) {
        let traced = mip(o_v, d_v, span.x, span.y);
        out_rgba[pixel] = traced.rgba;
        out_samples[pixel] = traced.samples;
        return;
    }
    var acc = vec4<f32>(0.0);
    var samples = 0u;
    if (span.y > span.x) {
        let step = params.origin.w;
        let stop = params.inv_spacing.w;
        let t0 = span.x;
        let t1 = span.y;
        let base = o_v + d_v * t0;
        let stride = d_v * step;
        var i = 0u;
        loop {
            let t = t0 + step * f32(i);
            if (t >= t1) {
                break;
            }
            let v = sample(base + stride * f32(i));
            samples += 1u;
            if (!is_nan(v)) {
                var e: vec4<f32>;
                if (t + step <= t1) {
                    e = slab_at(v);
                } else {
                    let c = tau_at(v);
                    let a = 1.0 - exp(-c.w * (t1 - t));
                    e = vec4<f32>(c.xyz * a, a);
                }
                acc += (1.0 - acc.w) * e;
                if (acc.w >= stop) {
                    break;
                }
            }
            i += 1u;
        }
    }
    out_rgba[pixel] = acc;
    out_samples[pixel] = samples;
}
