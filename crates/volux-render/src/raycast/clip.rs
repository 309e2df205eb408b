//! Ray clipping against the grid's box, voxel-boundary crossings, world to voxel space.
use glam::{DVec3, Vec3};

use super::options::Placement;

/// Entry and exit distances of a ray through the box [lo, hi] (slab test), if it hits.
pub fn ray_box(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let inv = dir.recip();
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    // NaN (0 * inf, ray in a slab plane) is ignored by max/min below.
    let tn = near.x.max(near.y).max(near.z).max(0.0);
    let tf = far.x.min(far.y).min(far.z);
    (tf > tn).then_some((tn, tf))
}

/// Distances in `[t0, t1]` where the voxel-space ray `o_v + t d_v` crosses an integer plane
/// (a voxel boundary), with `t0` and `t1`, sorted.
pub fn voxel_crossings(o_v: DVec3, d_v: DVec3, t0: f64, t1: f64) -> Vec<f64> {
    let mut ts = vec![t0, t1];
    for a in 0..3 {
        if d_v[a].abs() < 1e-300 {
            continue;
        }
        let (x0, x1) = (o_v[a] + d_v[a] * t0, o_v[a] + d_v[a] * t1);
        let (lo, hi) = (x0.min(x1).ceil() as i64, x0.max(x1).floor() as i64);
        ts.extend(
            (lo..=hi)
                .map(|k| (k as f64 - o_v[a]) / d_v[a])
                .filter(|t| *t > t0 && *t < t1),
        );
    }
    ts.sort_by(f64::total_cmp);
    ts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    ts
}

/// The voxel-space position of a world point (for tests and tools), through the placement's
/// direction.
pub fn to_voxel(place: &Placement, p: DVec3) -> Vec3 {
    ((place.point_to_local(p) - place.origin) / place.spacing).as_vec3()
}
