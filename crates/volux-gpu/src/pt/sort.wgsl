// Visibility order (seed 000 section 4.2, seed 002 section 4.2): a stable LSD radix sort of
// (key, id) pairs by key, 4 bits a pass, in three dispatches a pass: per-block digit counts,
// one exclusive scan of the counts (digit-major, so that equal digits keep block order), and
// a scatter in which every item's rank among the equal digits before it in its block (a
// workgroup scan of per-digit counters, 8 steps) keeps the order of equal keys (the CPU's order: by depth, ties by id).

struct Pass {
    n: u32,
    shift: u32,
    blocks: u32,
    unused: u32,
}

const BLOCK: u32 = 256u;
const RADIX: u32 = 16u;

@group(0) @binding(0) var<uniform> params: Pass;
@group(0) @binding(1) var<storage, read> src: array<vec2u>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec2u>;
@group(0) @binding(3) var<storage, read_write> counts: array<u32>;

var<workgroup> tally: array<atomic<u32>, 16>;
var<workgroup> digits: array<u32, 256>;
var<workgroup> sums: array<u32, 256>;
var<workgroup> ranks: array<vec4u, 256>;

fn digit(key: u32) -> u32 {
    return (key >> params.shift) & (RADIX - 1u);
}

@compute @workgroup_size(256)
fn count(@builtin(workgroup_id) wg: vec3u, @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) li: u32) {
    let block = wg.x + wg.y * groups.x;
    if li < RADIX {
        atomicStore(&tally[li], 0u);
    }
    workgroupBarrier();
    let i = block * BLOCK + li;
    if block < params.blocks && i < params.n {
        atomicAdd(&tally[digit(src[i].x)], 1u);
    }
    workgroupBarrier();
    if li < RADIX && block < params.blocks {
        counts[li * params.blocks + block] = atomicLoad(&tally[li]);
    }
}

@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) li: u32) {
    let m = RADIX * params.blocks;
    let per = (m + BLOCK - 1u) / BLOCK;
    let start = li * per;
    var s = 0u;
    for (var k = 0u; k < per; k++) {
        let j = start + k;
        if j < m {
            s += counts[j];
        }
    }
    sums[li] = s;
    workgroupBarrier();
    if li == 0u {
        var run = 0u;
        for (var k = 0u; k < BLOCK; k++) {
            let v = sums[k];
            sums[k] = run;
            run += v;
        }
    }
    workgroupBarrier();
    var run = sums[li];
    for (var k = 0u; k < per; k++) {
        let j = start + k;
        if j < m {
            let v = counts[j];
            counts[j] = run;
            run += v;
        }
    }
}

// The item's one-hot digit as 16 8-bit counters (digit d: byte d % 4 of word d / 4).
fn one_hot(d: u32) -> vec4u {
    if d >= RADIX {
        return vec4u(0u);
    }
    var v = vec4u(0u);
    v[d / 4u] = 1u << (8u * (d % 4u));
    return v;
}

@compute @workgroup_size(256)
fn scatter(@builtin(workgroup_id) wg: vec3u, @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) li: u32) {
    let block = wg.x + wg.y * groups.x;
    let i = block * BLOCK + li;
    let live = block < params.blocks && i < params.n;
    var item = vec2u(0u);
    var d = 0xffffffffu;
    if live {
        item = src[i];
        d = digit(item.x);
    }
    digits[li] = d;
    workgroupBarrier();
    // Exclusive per-digit counts: a Hillis-Steele scan of the previous item's one-hot
    // counters (at most 255 before the last item: no byte overflows).
    var own = vec4u(0u);
    if li > 0u {
        own = one_hot(digits[li - 1u]);
    }
    ranks[li] = own;
    for (var offset = 1u; offset < BLOCK; offset *= 2u) {
        workgroupBarrier();
        var add = vec4u(0u);
        if li >= offset {
            add = ranks[li - offset];
        }
        workgroupBarrier();
        own += add;
        ranks[li] = own;
    }
    if live {
        let rank = (own[d / 4u] >> (8u * (d % 4u))) & 0xffu;
        dst[counts[d * params.blocks + block] + rank] = item;
    }
}
