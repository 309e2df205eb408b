// The brick pool (seed `003`, done in one pass): the grid's bricks of B cells per axis (B + 1
// samples, the shared face included, so that every trilinear sample reads one brick) live
// in slots of a 3D texture atlas; a page table says which slot holds each brick, or that the
// brick is transparent under the TF. A ray continues from its saved state (the opacity so
// far and its next lattice index): it samples and composites front to back until it needs a
// brick that is not resident, asks for it, and stops; the host loads the asked bricks and
// dispatches again. Opacity is carried across bricks and rounds, never reset (`003`'s merge
// reset it per brick). Samples sit on the lattice t0 + (i + jitter) h of the whole-texture
// ray caster, and read the same values: the pictures are the same.

override FLAGS: u32 = 0u;
const JITTER: u32 = 16u;
// A ray that is finished.
const DONE: u32 = 0xffffffffu;
// A page entry for a brick the TF leaves transparent (never loaded).
const EMPTY: u32 = 0xffffffffu;

struct Pool {
    // xyz: bricks per axis; w: cells per brick side B.
    bricks: vec4<u32>,
    // xyz: slots per axis; w: samples per slot side, B + 1.
    slots: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var atlas: texture_3d<f32>;
@group(0) @binding(2) var<storage, read> tables: array<vec4<f32>>;
@group(0) @binding(3) var<uniform> pool: Pool;
// The clip planes (local frame).
@group(0) @binding(4) var<storage, read> frame: array<vec4<f32>>;
// Per brick: 0 absent, EMPTY transparent, else its slot + 1.
@group(0) @binding(5) var<storage, read> page: array<u32>;
// Per brick: 1 where a ray asked for it this round.
@group(0) @binding(6) var<storage, read_write> requests: array<u32>;
@group(0) @binding(7) var<storage, read_write> state_acc: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> state_i: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_samples: array<u32>;

// A sample looked up in the pool: its value, its brick and that brick's page entry.
struct Looked {
    value: f32,
    brick: u32,
    entry: u32,
};

// The trilinear sample at voxel-space q (as `sample` in raycast.wgsl: the same cell, the
// same fractions, the same corners), read from the slot of the brick holding its cell.
fn pooled(q: vec3<f32>) -> Looked {
    let n = params.dims.xyz;
    let p = clamp(q, vec3<f32>(0.0), vec3<f32>(n - vec3<u32>(1u)));
    let ax = axis(p.x, n.x);
    let ay = axis(p.y, n.y);
    let az = axis(p.z, n.z);
    let cell = vec3<u32>(u32(ax.x), u32(ay.x), u32(az.x));
    let b = cell / pool.bricks.w;
    let nb = pool.bricks.xyz;
    let brick = b.x + nb.x * (b.y + nb.y * b.z);
    let entry = page[brick];
    if (entry == 0u || entry == EMPTY) {
        return Looked(0.0, brick, entry);
    }
    let s = entry - 1u;
    let ns = pool.slots.xyz;
    let slot = vec3<u32>(s % ns.x, (s / ns.x) % ns.y, s / (ns.x * ns.y));
    let base = vec3<i32>(slot * pool.slots.w + (cell - b * pool.bricks.w));
    let d = vec3<i32>(select(0, 1, n.x > 1u), select(0, 1, n.y > 1u), select(0, 1, n.z > 1u));
    let v000 = textureLoad(atlas, base, 0).r;
    let v100 = textureLoad(atlas, base + vec3<i32>(d.x, 0, 0), 0).r;
    let v010 = textureLoad(atlas, base + vec3<i32>(0, d.y, 0), 0).r;
    let v110 = textureLoad(atlas, base + vec3<i32>(d.x, d.y, 0), 0).r;
    let v001 = textureLoad(atlas, base + vec3<i32>(0, 0, d.z), 0).r;
    let v101 = textureLoad(atlas, base + vec3<i32>(d.x, 0, d.z), 0).r;
    let v011 = textureLoad(atlas, base + vec3<i32>(0, d.y, d.z), 0).r;
    let v111 = textureLoad(atlas, base + vec3<i32>(d.x, d.y, d.z), 0).r;
    let c0 = mix(mix(v000, v100, ax.y), mix(v010, v110, ax.y), ay.y);
    let c1 = mix(mix(v001, v101, ax.y), mix(v011, v111, ax.y), ay.y);
    return Looked(mix(c0, c1, az.y), brick, entry);
}

// The distance at which the ray leaves the cells of brick `brick`.
fn brick_exit(ray: Ray, brick: u32) -> f32 {
    let nb = pool.bricks.xyz;
    let b = vec3<u32>(brick % nb.x, (brick / nb.x) % nb.y, brick / (nb.x * nb.y));
    let lo = vec3<f32>(b * pool.bricks.w);
    let hi = lo + f32(pool.bricks.w);
    let ta = (lo - ray.o_v) / ray.d_v;
    let tb = (hi - ray.o_v) / ray.d_v;
    let far = max(ta, tb);
    return min(min(far.x, far.y), far.z);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let pixel = id.y * params.size.x + id.x;
    var i = state_i[pixel];
    if (i == DONE) {
        return;
    }
    let ray = pixel_ray(id);
    if (!(ray.t1 > ray.t0)) {
        state_i[pixel] = DONE;
        return;
    }
    var jitter = 0.0;
    if ((FLAGS & JITTER) != 0u) {
        jitter = pixel_hash(id.x, id.y);
    }
    let h = params.origin.w;
    let stop = params.inv_spacing.w;
    let start = ray.t0 + jitter * h;
    let base = ray.o_v + ray.d_v * start;
    let stride = ray.d_v * h;
    var acc = state_acc[pixel];
    var samples = out_samples[pixel];
    loop {
        let t = start + h * f32(i);
        if (t >= ray.t1) {
            i = DONE;
            break;
        }
        let p = base + stride * f32(i);
        let looked = pooled(p);
        if (looked.entry == 0u) {
            requests[looked.brick] = 1u;
            break;
        }
        if (looked.entry == EMPTY) {
            // Transparent: on to the first lattice point past the brick (a point on its
            // boundary is sampled, not skipped).
            let k = ceil((brick_exit(ray, looked.brick) - start) / h - 1e-3);
            i = max(i + 1u, u32(max(k, 0.0)));
            continue;
        }
        samples += 1u;
        let v = looked.value;
        if (!is_nan(v)) {
            var e: vec4<f32>;
            if (t + h <= ray.t1) {
                e = slab_at(v);
            } else {
                let c = tau_at(v);
                let a = 1.0 - exp(-c.w * (ray.t1 - t));
                e = vec4<f32>(c.xyz * a, a);
            }
            acc = under(acc, e);
            if (acc.w >= stop) {
                i = DONE;
                break;
            }
        }
        i += 1u;
    }
    state_i[pixel] = i;
    state_acc[pixel] = acc;
    out_samples[pixel] = samples;
}
