//! Centroid depth keys and their O(n) LSD radix sort (seed `000_...txt` §4.2).
use rayon::prelude::*;
use volux_core::TetMesh;

use super::view::SortView;

/// Below this many ids a stable comparison sort is faster than three radix passes.
const SMALL: usize = 256;
/// Digit widths of the three LSD passes over the 32-bit key, least significant first.
const DIGITS: [u32; 3] = [11, 11, 10];
/// Items per chunk of the parallel key and histogram pass.
const CHUNK: usize = 1 << 15;

/// Maps a depth to a `u32` whose unsigned order is the numeric order of the depths: negative
/// depths first, `-0.0` and `+0.0` equal, `+inf` after every finite depth and NaN last of all
/// (a cell with an undefined depth is composited last, behind everything).
pub fn depth_key(depth: f32) -> u32 {
    if depth.is_nan() {
        return u32::MAX;
    }
    // -0.0 == 0.0 must give one key, or the sort would not be stable on equal depths.
    let bits = if depth == 0.0 { 0 } else { depth.to_bits() };
    if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

/// The centroid depth of every tet, indexed by tet id: the distance from the eye to the
/// centroid for a perspective view, the depth along the view direction for an orthographic one
/// ([`SortView::depth`]; seed `000` §4.1 and §4.2 compute it in the first pass as the centroid's
/// `z`, see the module documentation for why distance is used under perspective). Computed in
/// `f64`, stored as `f32` (the sort key).
pub fn centroid_keys(mesh: &TetMesh, view: &SortView) -> Vec<f32> {
    let pos = mesh.positions();
    mesh.tets()
        .par_iter()
        .map(|t| {
            let c = t
                .iter()
                .fold(glam::DVec3::ZERO, |a, &v| a + pos[v as usize].as_dvec3())
                * 0.25;
            view.depth(c) as f32
        })
        .collect()
}

/// Sorts the tets `ids` front to back by their depths, `depths[i]` being the depth of
/// `ids[i]` (to sort every tet, pass [`centroid_keys`] and `0..n`): the seeds' centroid sort (`000` §4.2) done as an LSD
/// radix sort, three passes of 11, 11 and 10 bits over [`depth_key`], O(n). A pass whose digit
/// is the same for every key (the high bits of depths in a narrow range) is skipped. The sort
/// is stable (equal depths keep the order of `ids`) and deterministic; the key pass and the
/// histograms run in parallel, the scatters sequentially.
///
/// # Panics
///
/// If `depths` and `ids` differ in length.
pub fn centroid_order(depths: &[f32], ids: &[u32]) -> Vec<u32> {
    assert_eq!(depths.len(), ids.len(), "one depth per id");
    if ids.len() < SMALL {
        let mut pairs: Vec<(u32, u32)> = depths
            .iter()
            .zip(ids)
            .map(|(&d, &t)| (depth_key(d), t))
            .collect();
        pairs.sort_by_key(|p| p.0);
        return pairs.into_iter().map(|p| p.1).collect();
    }
    // (key << 32 | id): one 8-byte item per tet, sorted on its high 32 bits only.
    let mut items: Vec<u64> = Vec::with_capacity(ids.len());
    depths
        .par_iter()
        .zip(ids.par_iter())
        .map(|(&d, &t)| (u64::from(depth_key(d)) << 32) | u64::from(t))
        .collect_into_vec(&mut items);
    let hist = histograms(&items);
    let mut scratch = vec![0u64; items.len()];
    let mut shift = 32;
    for (p, &bits) in DIGITS.iter().enumerate() {
        let h = &hist[p];
        let mask = (1u64 << bits) - 1;
        let first = ((items[0] >> shift) & mask) as usize;
        if h[first] as usize != items.len() {
            let mut offset = [0u32; 1 << 11];
            let mut sum = 0u32;
            for (o, &c) in offset.iter_mut().zip(h.iter()) {
                *o = sum;
                sum += c;
            }
            for &x in &items {
                let d = ((x >> shift) & mask) as usize;
                scratch[offset[d] as usize] = x;
                offset[d] += 1;
            }
            std::mem::swap(&mut items, &mut scratch);
        }
        shift += bits;
    }
    items.into_iter().map(|x| x as u32).collect()
}

/// The digit histograms of the three passes, counted in one parallel read of the items.
fn histograms(items: &[u64]) -> Vec<[u32; 1 << 11]> {
    let count = |chunk: &[u64]| {
        let mut h = vec![[0u32; 1 << 11]; DIGITS.len()];
        for &x in chunk {
            let mut shift = 32;
            for (hp, &bits) in h.iter_mut().zip(DIGITS.iter()) {
                hp[((x >> shift) & ((1u64 << bits) - 1)) as usize] += 1;
                shift += bits;
            }
        }
        h
    };
    items.par_chunks(CHUNK).map(count).reduce(
        || vec![[0u32; 1 << 11]; DIGITS.len()],
        |mut a, b| {
            for (ha, hb) in a.iter_mut().zip(b.iter()) {
                for (x, y) in ha.iter_mut().zip(hb.iter()) {
                    *x += y;
                }
            }
            a
        },
    )
}
