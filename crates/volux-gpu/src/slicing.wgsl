// Texture slicing (seed `004` ch. 3): the slice polygons of the volume of interest, drawn
// back to front and blended "over" (§3.3, eq. 3.2) by the render pipeline. Each fragment
// samples the field where its slice crosses the pixel's ray (the grid's local frame, world
// units), classifies it with the ray caster's slab table and stands for the ray segment from
// its slice to the next: h / cos(angle to the view direction) long, the opacity corrected to
// 1 - (1 - a)^(len / h), the colour with it; the first slice along a ray also covers the
// segment from the ray's entry, the last one stops at the exit, so that the slabs tile the
// ray as the ray caster's do (§3.3 eq. 3.1). The sculpt mask (§4.4.1) and the shading are
// the ray caster's (`field.wgsl`, before this file).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var volume: texture_3d<f32>;
// The slab table, then the extinction table, `size.w` entries each.
@group(0) @binding(2) var<storage, read> tables: array<vec4<f32>>;
// The clip planes (local frame: normal . p + w >= 0 is kept).
@group(0) @binding(3) var<storage, read> frame: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> mask_bits: array<u32>;
@group(0) @binding(5) var gradients: texture_3d<i32>;

struct Fragment {
    @builtin(position) clip: vec4<f32>,
    // The point relative to the eye (local frame, world units).
    @location(0) rel: vec3<f32>,
};

// The ray caster's projection (`raycast.wgsl` main) inverted: the pixel whose ray passes
// through the point; depth kept in (0, w) so that nothing is clipped but by the sides.
@vertex
fn vs(@location(0) rel: vec3<f32>) -> Fragment {
    let x = dot(rel, params.right.xyz);
    let y = dot(rel, params.up.xyz);
    let z = dot(rel, params.forward.xyz);
    let aspect = params.lens.y;
    var clip: vec4<f32>;
    if (params.size.z == 0u) {
        let t = params.lens.x;
        clip = vec4<f32>(x / (t * aspect), y / t, 0.5 * z, z);
    } else {
        let half = 0.5 * params.lens.x;
        clip = vec4<f32>(x / (half * aspect), y / half, 0.5, 1.0);
    }
    return Fragment(clip, rel);
}

// The distances from p along dir to the ray's entry (<= 0) and exit (>= 0): the box
// [0, dims - 1] (voxel space q), the clip planes, and the ray's start at the eye (or on the
// eye's plane).
fn span(p: vec3<f32>, rel: vec3<f32>, dir: vec3<f32>, q: vec3<f32>) -> vec2<f32> {
    let hi = vec3<f32>(params.dims.xyz - vec3<u32>(1u));
    let inv = 1.0 / (dir * params.inv_spacing.xyz);
    let ta = (vec3<f32>(0.0) - q) * inv;
    let tb = (hi - q) * inv;
    let near = min(ta, tb);
    let far = max(ta, tb);
    var t0 = max(max(max(near.x, near.y), near.z), -dot(rel, dir));
    var t1 = min(min(far.x, far.y), far.z);
    for (var k = 0u; k < params.dims.w; k++) {
        let pl = frame[k];
        let d0 = dot(pl.xyz, p) + pl.w;
        let rate = dot(pl.xyz, dir);
        if (rate > 0.0) {
            t0 = max(t0, -d0 / rate);
        } else if (rate < 0.0) {
            t1 = min(t1, -d0 / rate);
        }
    }
    return vec2<f32>(t0, t1);
}

@fragment
fn fs(in: Fragment) -> @location(0) vec4<f32> {
    let p = params.eye.xyz + in.rel;
    var dir = params.forward.xyz;
    if (params.size.z == 0u) {
        dir = normalize(in.rel);
    }
    let h = params.origin.w;
    let len = h / dot(dir, params.forward.xyz);
    let q = (p - params.origin.xyz) * params.inv_spacing.xyz;
    let v = field(q);
    if (is_nan(v)) {
        discard;
    }
    let s = span(p, in.rel, dir, q);
    let a = select(0.0, s.x, s.x > -len);
    let b = min(len, s.y);
    let covered = b - a;
    if (!(covered > 0.0)) {
        discard;
    }
    let e = slab_at(v);
    let alpha = 1.0 - pow(max(1.0 - e.w, 0.0), covered / h);
    var scale = covered / h;
    if (e.w > 0.0) {
        scale = alpha / e.w;
    }
    return lit(vec4<f32>(e.xyz * scale, alpha), q, dir);
}
