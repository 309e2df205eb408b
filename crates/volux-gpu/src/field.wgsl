// The field and its lighting, shared by the ray caster (`raycast.wgsl`) and texture slicing
// (`slicing.wgsl`), each appended after `common.wgsl` and this file and declaring the
// bindings `volume`, `mask_bits` and `gradients` these functions read: the trilinear sample,
// the sculpt mask (seed `004` §4.4.1), gradients (the gradient volume or on the fly),
// Blinn-Phong shading (`002` §4.6) and the cut faces lit with the cut's normal (`004` §4).

// The features a pipeline draws (the flags below), fixed when the pipeline is created, so
// that the driver compiles out what a frame does not use (lavapipe ran the plain Riemann sum
// 3 times slower with the lighting and isosurface code present behind uniform branches).
override FLAGS: u32 = 0u;

const SHADE: u32 = 1u;
const GRADIENT_VOLUME: u32 = 2u;
const MASK: u32 = 4u;
const SKIP: u32 = 8u;
const JITTER: u32 = 16u;
const ISO_LIT: u32 = 32u;
const ISOSURFACES: u32 = 64u;
const CUTS: u32 = 128u;

fn flag(f: u32) -> bool {
    return (FLAGS & f) != 0u;
}

// Trilinear sample at voxel-space q, clamped to the box (the lattice lies in it but for
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

// Whether voxel v is kept by the sculpt mask.
fn kept(v: vec3<u32>) -> f32 {
    let n = params.dims;
    let i = v.x + n.x * (v.y + n.y * v.z);
    return f32((mask_bits[i >> 5u] >> (i & 31u)) & 1u);
}

// `SculptMask::value`: the cell's kept corners blended at the point.
fn mask_value(q: vec3<f32>) -> f32 {
    let n = params.dims.xyz;
    let hi = vec3<f32>(n - vec3<u32>(1u));
    let x = clamp(q, vec3<f32>(0.0), hi);
    let top = vec3<f32>(max(n, vec3<u32>(2u)) - vec3<u32>(2u));
    let c = min(floor(x), top);
    let f = x - c;
    let lo = vec3<u32>(c);
    let up = min(lo + vec3<u32>(1u), n - vec3<u32>(1u));
    let x00 = mix(kept(lo), kept(vec3<u32>(up.x, lo.y, lo.z)), f.x);
    let x10 = mix(kept(vec3<u32>(lo.x, up.y, lo.z)), kept(vec3<u32>(up.x, up.y, lo.z)), f.x);
    let x01 = mix(kept(vec3<u32>(lo.x, lo.y, up.z)), kept(vec3<u32>(up.x, lo.y, up.z)), f.x);
    let x11 = mix(kept(vec3<u32>(lo.x, up.y, up.z)), kept(up), f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

// `SculptMask::visible`: the interpolated mask at least 0.5.
fn visible(q: vec3<f32>) -> bool {
    return mask_value(q) >= 0.5;
}

// The field: the trilinear sample, undefined where the mask hides the point.
fn field(q: vec3<f32>) -> f32 {
    if (flag(MASK) && !visible(q)) {
        return nan();
    }
    return sample(q);
}

// The gradient volume's gradient at q (`GradientVolume::gradient`), world units.
fn gradient_volume(q: vec3<f32>) -> vec3<f32> {
    let n = params.dims.xyz;
    let p = clamp(q, vec3<f32>(0.0), vec3<f32>(n - vec3<u32>(1u)));
    let ax = axis(p.x, n.x);
    let ay = axis(p.y, n.y);
    let az = axis(p.z, n.z);
    let b = vec3<i32>(i32(ax.x), i32(ay.x), i32(az.x));
    let d = vec3<i32>(select(0, 1, n.x > 1u), select(0, 1, n.y > 1u), select(0, 1, n.z > 1u));
    let g000 = vec3<f32>(textureLoad(gradients, b, 0).xyz);
    let g100 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(d.x, 0, 0), 0).xyz);
    let g010 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(0, d.y, 0), 0).xyz);
    let g110 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(d.x, d.y, 0), 0).xyz);
    let g001 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(0, 0, d.z), 0).xyz);
    let g101 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(d.x, 0, d.z), 0).xyz);
    let g011 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(0, d.y, d.z), 0).xyz);
    let g111 = vec3<f32>(textureLoad(gradients, b + vec3<i32>(d.x, d.y, d.z), 0).xyz);
    let c0 = mix(mix(g000, g100, ax.y), mix(g010, g110, ax.y), ay.y);
    let c1 = mix(mix(g001, g101, ax.y), mix(g011, g111, ax.y), ay.y);
    return mix(c0, c1, az.y) * params.gradient.xyz;
}

// One axis of `shading::gradient`: central where both ends are defined, one-sided through
// the centre where one is missing, else 0.
fn difference(lo: f32, a: f32, hi: f32, b: f32, c: f32, centre: f32) -> f32 {
    if (!is_nan(a) && !is_nan(b)) {
        return (b - a) / (hi - lo);
    }
    if (!is_nan(a) && c > lo && !is_nan(centre)) {
        return (centre - a) / (c - lo);
    }
    if (!is_nan(b) && hi > c && !is_nan(centre)) {
        return (b - centre) / (hi - c);
    }
    return 0.0;
}

// `shading::gradient`: central differences of the field at +-1 voxel, world units.
fn gradient_fly(q: vec3<f32>) -> vec3<f32> {
    let n = params.dims.xyz;
    let p = clamp(q, vec3<f32>(0.0), vec3<f32>(n - vec3<u32>(1u)));
    let centre = field(p);
    var g = vec3<f32>(0.0);
    for (var a = 0; a < 3; a++) {
        let last = f32(n[a] - 1u);
        if (last <= 0.0) {
            continue;
        }
        let lo = max(p[a] - 1.0, 0.0);
        let hi = min(p[a] + 1.0, last);
        var plo = p;
        var phi = p;
        plo[a] = lo;
        phi[a] = hi;
        let d = difference(lo, field(plo), hi, field(phi), p[a], centre);
        let w = d / params.spacing[a];
        if (!is_nan(w) && abs(w) <= 3.4e38) {
            g[a] = w;
        }
    }
    return g;
}

fn gradient_at(q: vec3<f32>) -> vec3<f32> {
    if (flag(GRADIENT_VOLUME)) {
        return gradient_volume(q);
    }
    return gradient_fly(q);
}

// `BlinnPhong::shade`: two-sided Blinn-Phong of colour rgb with gradient g seen along view
// (unit, from the eye); unlit below the smallest gradient.
fn shade(rgb: vec3<f32>, g: vec3<f32>, view: vec3<f32>) -> vec3<f32> {
    let len = length(g);
    let to_eye = -view;
    if (!(len >= params.gradient.w && len > 0.0 && len <= 3.4e38)) {
        return rgb;
    }
    var n = g / len;
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    var l = to_eye;
    if (params.light.w == 0.0) {
        l = params.light.xyz;
    }
    let n_l = dot(n, l);
    var diffuse = 0.0;
    var specular = 0.0;
    if (n_l > 0.0) {
        let sum = l + to_eye;
        let s_len = length(sum);
        var n_h = 0.0;
        if (s_len > 0.0) {
            n_h = max(dot(n, sum / s_len), 0.0);
        }
        diffuse = n_l;
        specular = pow(n_h, params.phong.w);
    }
    let k = params.phong.x + params.phong.y * diffuse;
    return rgb * k + vec3<f32>(params.phong.z * specular);
}

// Whether q's cell has kept and removed corners (`SculptMask::cut_gradient` is some).
fn cell_cut(q: vec3<f32>) -> bool {
    let n = params.dims.xyz;
    let hi = vec3<f32>(n - vec3<u32>(1u));
    let x = clamp(q, vec3<f32>(0.0), hi);
    let top = vec3<f32>(max(n, vec3<u32>(2u)) - vec3<u32>(2u));
    let lo = vec3<u32>(min(floor(x), top));
    let up = min(lo + vec3<u32>(1u), n - vec3<u32>(1u));
    let sum = kept(lo) + kept(vec3<u32>(up.x, lo.y, lo.z)) + kept(vec3<u32>(lo.x, up.y, lo.z))
        + kept(vec3<u32>(up.x, up.y, lo.z)) + kept(vec3<u32>(lo.x, lo.y, up.z))
        + kept(vec3<u32>(up.x, lo.y, up.z)) + kept(vec3<u32>(lo.x, up.y, up.z)) + kept(up);
    return sum > 0.0 && sum < 8.0;
}

// `cut_faces::mask_differences`: the central differences of the interpolated mask at one
// voxel on either side of q along each axis, per voxel.
fn mask_differences(q: vec3<f32>) -> vec3<f32> {
    var g = vec3<f32>(0.0);
    for (var a = 0; a < 3; a++) {
        var lo = q;
        var hi = q;
        lo[a] -= 1.0;
        hi[a] += 1.0;
        g[a] = 0.5 * (mask_value(hi) - mask_value(lo));
    }
    return g;
}

// `CutFaces::lighting_gradient` (seed `004` sec. 4): behind the nearest clip plane within the
// layer (`params.extra.z` world units), the plane's normal; where the sculpt mask's cell is
// cut, the interpolated mask's gradient; each of length `params.extra.w` (above the
// threshold); else the field's gradient g.
fn lighting_gradient(q: vec3<f32>, g: vec3<f32>) -> vec3<f32> {
    if (!flag(CUTS)) {
        return g;
    }
    let x = params.origin.xyz + q * params.spacing.xyz;
    var best = params.extra.z;
    var normal = vec3<f32>(0.0);
    for (var k = 0u; k < params.dims.w; k++) {
        let pl = frame[k];
        let d = dot(pl.xyz, x) + pl.w;
        if (d >= 0.0 && d < best) {
            best = d;
            normal = pl.xyz;
        }
    }
    if (flag(MASK) && all(normal == vec3<f32>(0.0)) && cell_cut(q)) {
        let m = mask_differences(q) * params.inv_spacing.xyz;
        let len = length(m);
        if (len > 0.0) {
            normal = m / len;
        }
    }
    if (all(normal == vec3<f32>(0.0))) {
        return g;
    }
    return normal * params.extra.w;
}

// A premultiplied entry e lit at q (its colour e.rgb / e.a).
fn lit(e: vec4<f32>, q: vec3<f32>, view: vec3<f32>) -> vec4<f32> {
    if (!flag(SHADE) || !(e.w > 0.0)) {
        return e;
    }
    let c = shade(e.xyz / e.w, lighting_gradient(q, gradient_at(q)), view);
    return vec4<f32>(c * e.w, e.w);
}

