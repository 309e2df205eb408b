//! Synthetic datasets with known structure, for tests, benchmarks and the demo.
//!
//! - [`marschner_lobb`]: the Marschner-Lobb test signal (f_M = 6, alpha = 0.25), the classic
//!   reconstruction benchmark, on [-1, 1]^3;
//! - [`shepp_logan`]: a 3D Shepp-Logan CT phantom (the modified ellipsoid table of Kak & Slaney);
//! - [`sphere`]: a signed distance field to a sphere;
//! - [`smooth_tets`]: a smooth field tetrahedralized at a chosen tet count;
//! - [`torus_tets`]: a thick-walled torus, a non-convex mesh for visibility tests.
use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::grid::{Buffer, Grid, Samples};
use crate::limits::{check_alloc, checked_dims};
use crate::mesh::TetMesh;
use crate::tetrahedralize::{curvilinear_to_tets, lattice_tets, orient_positive};

/// Names accepted by [`generate_grid`] and [`generate_mesh`].
pub const GENERATORS: [&str; 5] = [
    "marschner-lobb",
    "shepp-logan",
    "sphere",
    "tets-smooth",
    "torus",
];

/// Samples `f` at the points of an `n`-cube over [-1, 1]^3 into an f32 grid.
fn sample_cube(dims: [usize; 3], f: impl Fn(DVec3) -> f64 + Sync) -> Result<Grid> {
    let (dims, count) = checked_dims(dims.map(|d| d as i64))?;
    if dims.iter().any(|&d| d < 2) {
        return Err(Error::InvalidDims {
            dims: dims.map(|d| d as i64),
            reason: "need >= 2 samples per axis".into(),
        });
    }
    check_alloc("synthetic grid", count, 4)?;
    let step = dims.map(|d| 2.0 / (d - 1) as f64);
    let values: Vec<f32> = (0..count as usize)
        .into_par_iter()
        .map(|idx| {
            let i = idx % dims[0];
            let j = (idx / dims[0]) % dims[1];
            let k = idx / (dims[0] * dims[1]);
            let p = DVec3::new(
                i as f64 * step[0] - 1.0,
                j as f64 * step[1] - 1.0,
                k as f64 * step[2] - 1.0,
            );
            f(p) as f32
        })
        .collect();
    // Spacing in world units so the grid spans [-1, 1]^3... scaled to voxel units: the world
    // box is [0, n-1] with unit spacing, the convention of the seed's step sizes.
    Grid::new(
        dims,
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(values)),
    )
}

/// The Marschner-Lobb signal at `p` in [-1, 1]^3 (values in [0, 1]).
pub fn marschner_lobb_value(p: DVec3) -> f64 {
    let (fm, alpha) = (6.0, 0.25);
    let r = (p.x * p.x + p.y * p.y).sqrt();
    let rho_r = (2.0 * PI * fm * (PI * r / 2.0).cos()).cos();
    (1.0 - (PI * p.z / 2.0).sin() + alpha * (1.0 + rho_r)) / (2.0 * (1.0 + alpha))
}

/// Marschner-Lobb sampled on an `n`^3 grid.
pub fn marschner_lobb(n: usize) -> Result<Grid> {
    sample_cube([n; 3], marschner_lobb_value)
}

/// Modified 3D Shepp-Logan ellipsoids: intensity, semi-axes a b c, centre x0 y0 z0, rotation
/// about z in degrees.
const SHEPP_LOGAN: [[f64; 8]; 10] = [
    [1.0, 0.6900, 0.920, 0.810, 0.0, 0.0, 0.0, 0.0],
    [-0.8, 0.6624, 0.874, 0.780, 0.0, -0.0184, 0.0, 0.0],
    [-0.2, 0.1100, 0.310, 0.220, 0.22, 0.0, 0.0, -18.0],
    [-0.2, 0.1600, 0.410, 0.280, -0.22, 0.0, 0.0, 18.0],
    [0.1, 0.2100, 0.250, 0.410, 0.0, 0.35, -0.15, 0.0],
    [0.1, 0.0460, 0.046, 0.050, 0.0, 0.1, 0.25, 0.0],
    [0.1, 0.0460, 0.046, 0.050, 0.0, -0.1, 0.25, 0.0],
    [0.1, 0.0460, 0.023, 0.050, -0.08, -0.605, 0.0, 0.0],
    [0.1, 0.0230, 0.023, 0.020, 0.0, -0.606, 0.0, 0.0],
    [0.1, 0.0230, 0.046, 0.020, 0.06, -0.605, 0.0, 0.0],
];

/// The phantom's value at `p` in [-1, 1]^3 (sum of the ellipsoids containing `p`).
pub fn shepp_logan_value(p: DVec3) -> f64 {
    SHEPP_LOGAN
        .iter()
        .filter(|e| {
            let (s, c) = e[7].to_radians().sin_cos();
            let d = p - DVec3::new(e[4], e[5], e[6]);
            let (x, y) = (c * d.x + s * d.y, -s * d.x + c * d.y);
            (x / e[1]).powi(2) + (y / e[2]).powi(2) + (d.z / e[3]).powi(2) <= 1.0
        })
        .map(|e| e[0])
        .sum()
}

/// The 3D Shepp-Logan phantom on an `n`^3 grid.
pub fn shepp_logan(n: usize) -> Result<Grid> {
    sample_cube([n; 3], shepp_logan_value)
}

/// Signed distance to a sphere of radius 0.6 centred in [-1, 1]^3, negated so the inside is
/// high (values in about [-1.1, 0.6]).
pub fn sphere(n: usize) -> Result<Grid> {
    sample_cube([n; 3], |p| 0.6 - p.length())
}

/// A smooth field (a few Gaussian blobs over a gentle gradient) on [0, 1]^3.
pub fn smooth_value(p: DVec3) -> f64 {
    let blob = |c: DVec3, w: f64| (-(p - c).length_squared() / (w * w)).exp();
    0.2 * p.z
        + blob(DVec3::new(0.3, 0.4, 0.5), 0.2)
        + 0.8 * blob(DVec3::new(0.7, 0.6, 0.4), 0.15)
        + 0.6 * blob(DVec3::new(0.5, 0.7, 0.75), 0.1)
}

/// A smooth field tetrahedralized into about `target_tets` tets (5 per cell, cubic lattice).
pub fn smooth_tets(target_tets: usize) -> Result<TetMesh> {
    let c = ((target_tets.max(5) as f64 / 5.0).cbrt().round() as usize).max(1);
    let n = c + 1;
    check_alloc("synthetic mesh", (c * c * c) as u64 * 5, 16)?;
    let mut pos = Vec::with_capacity(n * n * n);
    let mut val = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = DVec3::new(i as f64, j as f64, k as f64) / c as f64;
                pos.push(p.as_vec3());
                val.push(smooth_value(p) as f32);
            }
        }
    }
    curvilinear_to_tets([n; 3], pos, val, None)
}

/// A thick-walled torus (major radius 1, tube radii 0.15 to 0.45) with `segments` cells
/// around the ring, a non-convex mesh: rays leave and re-enter it.
pub fn torus_tets(segments: usize) -> Result<TetMesh> {
    let nphi = (segments.max(8) + 1) & !1; // even, so the mirrored pattern closes up
    let ntheta = (nphi / 2 + 1).max(8) & !1;
    let nr = (nphi / 8).max(2);
    check_alloc("torus", (nphi * ntheta * nr) as u64 * 5, 16)?;
    let id =
        |i: usize, j: usize, k: usize| (i + (nr + 1) * ((j % ntheta) + ntheta * (k % nphi))) as u32;
    let mut pos = vec![Vec3::ZERO; (nr + 1) * ntheta * nphi];
    let mut val = vec![0.0f32; pos.len()];
    for k in 0..nphi {
        for j in 0..ntheta {
            for i in 0..=nr {
                let r = 0.15 + 0.3 * i as f64 / nr as f64;
                let theta = 2.0 * PI * j as f64 / ntheta as f64;
                let phi = 2.0 * PI * k as f64 / nphi as f64;
                let ring = 1.0 + r * theta.cos();
                let p = DVec3::new(ring * phi.cos(), ring * phi.sin(), r * theta.sin());
                let v = id(i, j, k) as usize;
                pos[v] = p.as_vec3();
                val[v] = (r + 0.1 * (3.0 * phi).sin() + 0.05 * theta.cos()) as f32;
            }
        }
    }
    let mut tets = lattice_tets([nr, ntheta, nphi], id, |_, _, _| true);
    orient_positive(&pos, &mut tets);
    TetMesh::new(pos, val, tets)
}

/// Generates a named grid at `n`^3.
pub fn generate_grid(kind: &str, n: usize) -> Result<Grid> {
    match kind {
        "marschner-lobb" => marschner_lobb(n),
        "shepp-logan" => shepp_logan(n),
        "sphere" => sphere(n),
        _ => Err(unknown(kind)),
    }
}

/// Generates a named mesh: `tets-smooth` with about `size` tets, `torus` with `size`
/// segments around the ring.
pub fn generate_mesh(kind: &str, size: usize) -> Result<TetMesh> {
    match kind {
        "tets-smooth" => smooth_tets(size),
        "torus" => torus_tets(size),
        _ => Err(unknown(kind)),
    }
}

fn unknown(kind: &str) -> Error {
    Error::UnknownName {
        kind: "generator",
        name: kind.into(),
        known: GENERATORS.join(", "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::signed_volume6;

    #[test]
    fn marschner_lobb_range() {
        let g = marschner_lobb(41).unwrap();
        let [lo, hi] = g.range();
        assert!(
            lo >= -1e-6 && hi <= 1.0 + 1e-6 && hi - lo > 0.9,
            "{lo} {hi}"
        );
    }

    #[test]
    fn shepp_logan_has_skull_and_brain() {
        assert!((shepp_logan_value(DVec3::ZERO) - 0.2).abs() < 1e-9);
        assert!((shepp_logan_value(DVec3::new(0.0, 0.9, 0.0)) - 1.0).abs() < 1e-9);
        assert_eq!(shepp_logan_value(DVec3::splat(0.99)), 0.0);
    }

    #[test]
    fn smooth_tets_size() {
        let m = smooth_tets(200_000).unwrap();
        let n = m.tets().len();
        assert!((180_000..220_000).contains(&n), "{n}");
    }

    #[test]
    fn torus_is_closed_and_positive() {
        let m = torus_tets(64).unwrap();
        assert_eq!(m.report().inverted_reoriented, 0);
        assert_eq!(m.report().degenerate, 0);
        for t in 0..m.tets().len() {
            let p = m.tet_positions(t);
            assert!(signed_volume6(p[0], p[1], p[2], p[3]) > 0.0);
        }
        // Conforming and closed: every boundary face lies on the inner or outer tube wall.
        let vol: f64 = (0..m.tets().len())
            .map(|t| {
                let p = m.tet_positions(t);
                signed_volume6(p[0], p[1], p[2], p[3]) / 6.0
            })
            .sum();
        let exact = 2.0 * PI * PI * 1.0 * (0.45f64.powi(2) - 0.15f64.powi(2));
        assert!((vol - exact).abs() / exact < 0.02, "{vol} vs {exact}");
        let m2 = torus_tets(16).unwrap();
        let bf = m2.boundary_faces();
        for f in bf {
            let c = f.map(|v| m2.positions()[v as usize].as_dvec3());
            let mid = (c[0] + c[1] + c[2]) / 3.0;
            let ring = DVec3::new(mid.x, mid.y, 0.0).normalize();
            let r = (mid - ring).length();
            assert!(
                !(0.2..=0.35).contains(&r),
                "boundary face inside the wall at r = {r}"
            );
        }
    }
}
