// What the grid shaders share (`raycast.wgsl`, `pool.wgsl`, each appended to this file):
// the parameters, the pixel's ray, the classification tables' look-up, compositing.
// Each shader declares the bindings `params`, `tables` and `frame` these functions read.

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
    // x, y, z: unused; w: isovalues.
    mode: vec4<u32>,
    // ambient, diffuse, specular, shininess.
    phong: vec4<f32>,
    // xyz: direction towards the light; w: 1 for a headlight.
    light: vec4<f32>,
    // xyz: world units per count of the gradient volume; w: the smallest lit gradient.
    gradient: vec4<f32>,
    // xyz: spacing; w: the pre-integration table's lo.
    spacing: vec4<f32>,
    // xyz: macrocells per axis; w: pre-integration table entries per axis.
    cells: vec4<u32>,
    // x: the pre-integration table's scale; y: the jitter-free first lattice offset (0);
    // z: the depth behind a clip plane lit with its normal (world units); w: the length
    // given to a cut's normal (`CutFaces`).
    extra: vec4<f32>,
};

fn nan() -> f32 {
    return bitcast<f32>(0x7fc00000u);
}

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
    return mix(tables[i], tables[i + 1u], p.y);
}

// The extinction table at value s.
fn tau_at(s: f32) -> vec4<f32> {
    let p = position(s);
    let i = u32(p.x) + params.size.w;
    return mix(tables[i], tables[i + 1u], p.y);
}

// `composite::under`: a layer of colour rgb and opacity a behind acc.
fn under(acc: vec4<f32>, e: vec4<f32>) -> vec4<f32> {
    return acc + (1.0 - acc.w) * e;
}

struct Ray {
    // Voxel-space origin and direction (per world unit of t).
    o_v: vec3<f32>,
    d_v: vec3<f32>,
    // Unit direction in the grid's frame, for lighting.
    view: vec3<f32>,
    t0: f32,
    t1: f32,
};

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
        let pl = frame[k];
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

// The ray of pixel `id` in the grid's local frame, clipped to the box and the clip planes
// (t0 > t1 when it misses): generated from the camera as `RayGenerator::ray` does.
fn pixel_ray(id: vec3<u32>) -> Ray {
    let w = params.size.x;
    let h = params.size.y;
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
    return Ray(o_v, d_v, normalize(d_v * params.spacing.xyz), span.x, span.y);
}

// `RayContext`'s jitter: a hash of the pixel, in [0, 1).
fn pixel_hash(x: u32, y: u32) -> f32 {
    var v = (x * 0x9E3779B9u) ^ (y * 0x85EBCA6Bu);
    v ^= v >> 16u;
    v *= 0x7FEB352Du;
    v ^= v >> 15u;
    v *= 0x846CA68Bu;
    v ^= v >> 16u;
    return f32(v) / 4294967296.0;
}

