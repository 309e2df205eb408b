//! Gradients of a scalar field in world units: on the fly ([`gradient`]) or precomputed once
//! per volume ([`GradientVolume`]).
use glam::Vec3;
use rayon::prelude::*;

use crate::error::{RenderError, Setting, SettingError};
use crate::sampling::Field;

/// Clamps `p` into the grid box `[0, dims - 1]` per axis (NaN becomes 0; never panics).
#[inline]
fn clamp_to_grid(p: Vec3, dims: [usize; 3]) -> Vec3 {
    let c = |x: f32, n: usize| x.max(0.0).min(n.saturating_sub(1) as f32);
    Vec3::new(c(p.x, dims[0]), c(p.y, dims[1]), c(p.z, dims[2]))
}

/// Difference quotient along one axis from optional samples at `lo <= c <= hi`: central when
/// both ends are defined, one-sided (through the centre sample) when one is missing, else 0.
#[inline]
fn axis_difference(
    lo: (f32, Option<f32>),
    hi: (f32, Option<f32>),
    centre: (f32, &mut dyn FnMut() -> Option<f32>),
) -> f32 {
    match (lo.1, hi.1) {
        (Some(a), Some(b)) => (b - a) / (hi.0 - lo.0),
        (Some(a), None) if centre.0 > lo.0 => match (centre.1)() {
            Some(c) => (c - a) / (centre.0 - lo.0),
            None => 0.0,
        },
        (None, Some(b)) if hi.0 > centre.0 => match (centre.1)() {
            Some(c) => (b - c) / (hi.0 - centre.0),
            None => 0.0,
        },
        _ => 0.0,
    }
}

/// The gradient of `field` at voxel position `p_voxel`, in world units (data units per world
/// unit): central differences at **+-1 voxel** along each axis, divided by `2 * spacing`.
///
/// Why +-1 voxel and not +-0.5: on the trilinear field, the +-1 difference at any point equals
/// the trilinear interpolation of the classic grid-point central differences
/// `(v[i+1] - v[i-1]) / 2`. So the on-the-fly gradient is continuous, agrees exactly (in the
/// interior) with a precomputed [`GradientVolume`], and is exact for quadratic data at
/// grid points. +-0.5 gives the same value at grid points but between them blends forward and
/// backward differences over a narrower support, which is noisier and matches no precomputed
/// volume.
///
/// At the borders the stencil is clamped to the grid and the difference is divided by the
/// actual distance (one-sided at a border sample); positions outside the grid are clamped to
/// it. Where a stencil sample is undefined (`None`) the difference becomes one-sided through
/// the centre sample, or 0 if that fails too. Axes with one sample, non-positive or
/// non-finite spacings, and non-finite results give a 0 component: the result is always
/// finite and this never panics (a NaN position reads as the grid corner).
#[inline]
pub fn gradient<F: Field>(field: &F, p_voxel: Vec3, spacing: Vec3) -> Vec3 {
    let dims = field.dims();
    let p = clamp_to_grid(p_voxel, dims);
    let mut centre_cache: Option<Option<f32>> = None;
    let mut g = Vec3::ZERO;
    for a in 0..3 {
        let last = dims[a].saturating_sub(1) as f32;
        if last <= 0.0 {
            continue;
        }
        let lo = (p[a] - 1.0).max(0.0);
        let hi = (p[a] + 1.0).min(last);
        let (mut plo, mut phi) = (p, p);
        plo[a] = lo;
        phi[a] = hi;
        let mut centre = || *centre_cache.get_or_insert_with(|| field.sample(p));
        let d = axis_difference(
            (lo, field.sample(plo)),
            (hi, field.sample(phi)),
            (p[a], &mut centre),
        );
        let s = spacing[a];
        let w = d / s;
        if s > 0.0 && w.is_finite() {
            g[a] = w;
        }
    }
    g
}

/// Bytes per voxel of a gradient volume while it is built: the `[i16; 4]` gradients and the
/// temporary `f32` copy of the samples.
const BUILD_BYTES_PER_VOXEL: u64 = 8 + 4;

/// Identifies the data a [`GradientVolume`] was built from: the grid dimensions and a version
/// number the caller bumps whenever the samples (or the spacing) change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GradientKey {
    /// Samples per axis.
    pub dims: [usize; 3],
    /// The caller's data version.
    pub version: u64,
}

/// Gradients precomputed at every grid sample, stored as 3 x `i16` per voxel with one scale
/// for the whole volume, padded to 8 bytes so that a corner is one load (134 MB for 256^3),
/// looked up trilinearly.
///
/// Grid-point gradients are the central differences of [`gradient`] (one-sided at the
/// borders), so in the interior a lookup equals [`gradient`] up to the quantization step,
/// `max |component| / 32767` (relative error about 1.5e-5 of the largest gradient). In the
/// cells touching the border, and next to undefined samples, the two differ slightly: the
/// volume interpolates one-sided and central differences, [`gradient`] shortens its stencil.
///
/// Build cost: one field sample per voxel into a temporary `f32` copy, then two cheap passes
/// over it (largest component, then quantization); peak memory 12 bytes per voxel; parallel
/// over z slices with rayon. Measured for a 256^3 `u16` volume in the test profile
/// (opt-level 2) on the shared 2-core development machine while other builds ran: 1.3 s best
/// of 5 (up to 2.3 s), of which about 0.75 s is the field sampling (test
/// `shading::tests::gradient_volume_build_time_256`, run with `--ignored --nocapture`). Per
/// lookup, single-threaded: about 45 ns, against about 190 ns for [`gradient`] on the fly
/// (6 trilinear samples), so the volume pays for itself after roughly 10 million shaded
/// samples, i.e. within the first frame or two of a 512^2 shaded render.
///
/// A renderer keeps one and rebuilds it only when [`GradientVolume::is_current`] says the data
/// changed.
#[derive(Clone, Debug)]
pub struct GradientVolume {
    pub(super) key: GradientKey,
    /// Gradients x, y, z and a zero pad: one aligned 8-byte load per voxel.
    pub(super) data: Vec<[i16; 4]>,
    /// World-unit gradient per quantization count, per axis (`scale / spacing`).
    pub(super) to_world: Vec3,
}

impl GradientVolume {
    /// Bytes a gradient volume of `dims` needs while it is built (its peak): the 8-byte
    /// gradients and the temporary 4-byte copy of the samples, `u64::MAX` on overflow.
    pub fn build_bytes(dims: [usize; 3]) -> u64 {
        volux_core::limits::count_of(&dims).saturating_mul(BUILD_BYTES_PER_VOXEL)
    }

    /// Builds the gradient volume of `field` (dimensions from [`Field::dims`]) placed with
    /// `spacing` (world units per voxel), tagged with the caller's data `version`.
    ///
    /// Errors on a zero dimension, a non-positive or non-finite spacing, or a size over the
    /// process's memory budget ([`volux_core::limits::memory_budget`]).
    pub fn build<F: Field>(field: &F, spacing: Vec3, version: u64) -> Result<Self, RenderError> {
        Self::build_within(volux_core::limits::memory_budget(), field, spacing, version)
    }

    /// [`GradientVolume::build`] within a memory budget of `budget` bytes: over it, the error
    /// names the gradient volume, its size and the budget (callers then take gradients on the
    /// fly, which need no memory).
    pub fn build_within<F: Field>(
        budget: u64,
        field: &F,
        spacing: Vec3,
        version: u64,
    ) -> Result<Self, RenderError> {
        let dims = field.dims();
        if dims.contains(&0) {
            return Err(SettingError::new(
                Setting::Dimensions,
                format!("{dims:?}"),
                "positive on every axis for a gradient volume",
            )
            .into());
        }
        if !(spacing.is_finite() && spacing.min_element() > 0.0) {
            return Err(SettingError::new(
                Setting::Spacing,
                spacing,
                "finite and > 0 for a gradient volume",
            )
            .into());
        }
        let count = volux_core::limits::count_of(&dims);
        volux_core::limits::check_alloc_within(
            budget,
            "the gradient volume",
            count,
            BUILD_BYTES_PER_VOXEL,
        )?;
        let n = count as usize;
        let [nx, ny, nz] = dims;
        let slice = nx * ny;

        // Pass 1: the samples at grid points (NaN where undefined).
        let mut values = vec![0.0f32; n];
        values.par_chunks_mut(slice).enumerate().for_each(|(k, s)| {
            for j in 0..ny {
                for i in 0..nx {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    s[i + nx * j] = field.sample(p).unwrap_or(f32::NAN);
                }
            }
        });

        // Pass 2: the largest gradient component, for the quantization scale.
        let max_abs = (0..nz)
            .into_par_iter()
            .map(|k| {
                let mut row = vec![Vec3::ZERO; nx];
                let mut m = 0.0f32;
                for j in 0..ny {
                    row_gradients(&values, dims, j, k, &mut row);
                    m = row.iter().fold(m, |m, g| m.max(g.abs().max_element()));
                }
                m
            })
            .reduce(|| 0.0, f32::max);
        let scale = if max_abs > 0.0 && max_abs.is_finite() {
            max_abs / 32767.0
        } else {
            0.0
        };
        let inv = if scale > 0.0 { 1.0 / scale } else { 0.0 };

        // Pass 3: quantize.
        let mut data = vec![[0i16; 4]; n];
        data.par_chunks_mut(slice).enumerate().for_each(|(k, s)| {
            let mut row = vec![Vec3::ZERO; nx];
            for (j, out) in s.chunks_mut(nx).enumerate() {
                row_gradients(&values, dims, j, k, &mut row);
                for (o, g) in out.iter_mut().zip(&row) {
                    let q = (*g * inv).round();
                    let [x, y, z] = [q.x, q.y, q.z].map(|c| c.clamp(-32767.0, 32767.0) as i16);
                    *o = [x, y, z, 0];
                }
            }
        });
        Ok(Self {
            key: GradientKey { dims, version },
            data,
            to_world: Vec3::splat(scale) / spacing,
        })
    }

    /// The quantized gradients, `[x, y, z, 0]` counts per grid sample (x fastest), and the
    /// world-unit gradient per count along each axis: what a GPU backend uploads to look
    /// gradients up as [`GradientVolume::gradient`] does.
    pub fn quantized(&self) -> (&[[i16; 4]], Vec3) {
        (&self.data, self.to_world)
    }

    /// The key of the data this volume was built from.
    pub fn key(&self) -> GradientKey {
        self.key
    }

    /// Whether this volume was built from data with these `dims` and `version` (if not, the
    /// renderer rebuilds it).
    pub fn is_current(&self, dims: [usize; 3], version: u64) -> bool {
        self.key == GradientKey { dims, version }
    }

    /// Memory held, in bytes.
    pub fn bytes(&self) -> usize {
        self.data.len() * std::mem::size_of::<[i16; 4]>()
    }

    /// The gradient at voxel position `p_voxel` (clamped to the grid), in world units, by
    /// trilinear interpolation of the grid-point gradients. Always finite.
    #[inline]
    pub fn gradient(&self, p_voxel: Vec3) -> Vec3 {
        let [nx, ny, nz] = self.key.dims;
        let (i, fx) = cell(p_voxel.x, nx);
        let (j, fy) = cell(p_voxel.y, ny);
        let (k, fz) = cell(p_voxel.z, nz);
        let dx = usize::from(nx > 1);
        let sy = if ny > 1 { nx } else { 0 };
        let sz = if nz > 1 { nx * ny } else { 0 };
        let b = i + nx * (j + ny * k);
        let v = |o: usize| {
            let q = self.data.get(b + o).copied().unwrap_or([0; 4]);
            Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32)
        };
        let c00 = v(0).lerp(v(dx), fx);
        let c10 = v(sy).lerp(v(sy + dx), fx);
        let c01 = v(sz).lerp(v(sz + dx), fx);
        let c11 = v(sz + sy).lerp(v(sz + sy + dx), fx);
        let c0 = c00.lerp(c10, fy);
        let c1 = c01.lerp(c11, fy);
        c0.lerp(c1, fz) * self.to_world
    }
}

/// Cell index and fraction along one axis, clamped to the grid (NaN reads as 0).
#[inline]
fn cell(x: f32, n: usize) -> (usize, f32) {
    if n < 2 {
        return (0, 0.0);
    }
    let x = x.max(0.0).min((n - 1) as f32);
    let i = (x as usize).min(n - 2);
    (i, x - i as f32)
}

/// Voxel-unit gradients of grid row `(j, k)` of `values` into `out` (`dims[0]` long): direct
/// central differences where the stencil is interior and defined, [`grid_gradient`] elsewhere.
fn row_gradients(values: &[f32], dims: [usize; 3], j: usize, k: usize, out: &mut [Vec3]) {
    let [nx, ny, nz] = dims;
    let (sy, sz) = (nx, nx * ny);
    let base = nx * (j + ny * k);
    let rows = (|| {
        if j == 0 || j + 1 >= ny || k == 0 || k + 1 >= nz || nx < 3 {
            return None;
        }
        Some((
            values.get(base..base + nx)?,
            values.get(base - sy..base - sy + nx)?,
            values.get(base + sy..base + sy + nx)?,
            values.get(base - sz..base - sz + nx)?,
            values.get(base + sz..base + sz + nx)?,
        ))
    })();
    for (i, o) in out.iter_mut().enumerate().take(nx) {
        *o = match rows {
            Some((c, ym, yp, zm, zp)) if i > 0 && i + 1 < nx => {
                let g = Vec3::new(c[i + 1] - c[i - 1], yp[i] - ym[i], zp[i] - zm[i]) * 0.5;
                if g.is_finite() {
                    g
                } else {
                    grid_gradient(values, dims, [i, j, k])
                }
            }
            _ => grid_gradient(values, dims, [i, j, k]),
        };
    }
}

/// Voxel-unit gradient at grid point `ijk` of `values` (NaN = undefined), with the rules of
/// [`gradient`] (central, one-sided at borders and next to undefined samples).
#[inline]
fn grid_gradient(values: &[f32], dims: [usize; 3], ijk: [usize; 3]) -> Vec3 {
    let strides = [1, dims[0], dims[0] * dims[1]];
    let at = |idx: usize| values.get(idx).copied().filter(|v| v.is_finite());
    let c = ijk[0] + strides[1] * ijk[1] + strides[2] * ijk[2];
    let mut g = Vec3::ZERO;
    for a in 0..3 {
        let (x, n, s) = (ijk[a], dims[a], strides[a]);
        if n < 2 {
            continue;
        }
        let lo = x.saturating_sub(1);
        let hi = (x + 1).min(n - 1);
        let mut centre = || at(c);
        let d = axis_difference(
            (lo as f32, at(c - (x - lo) * s)),
            (hi as f32, at(c + (hi - x) * s)),
            (x as f32, &mut centre),
        );
        if d.is_finite() {
            g[a] = d;
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Trilinear;
    use crate::shading::blinn_phong::{BlinnPhong, Light};
    use serde::Deserialize;

    fn grid(dims: [usize; 3], f: impl Fn(f32, f32, f32) -> f32) -> Vec<f32> {
        let mut v = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    v.push(f(i as f32, j as f32, k as f32));
                }
            }
        }
        v
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol * (1.0 + b.abs().max_element())
    }

    #[test]
    fn gradient_of_linear_field_is_exact_with_anisotropic_spacing() {
        let dims = [6, 7, 5];
        let v = grid(dims, |x, y, z| 1.0 + 2.0 * x - 0.5 * y + 3.0 * z);
        let s = Trilinear::new(&v, dims);
        let spacing = Vec3::new(0.5, 2.0, 1.25);
        let exact = Vec3::new(2.0 / 0.5, -0.5 / 2.0, 3.0 / 1.25);
        // Interior, off-grid, on the borders and at the corners: the stencil is clamped and
        // divided by its real length, so linear data stays exact everywhere.
        for p in [
            Vec3::new(2.3, 3.1, 1.7),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::ZERO,
            Vec3::new(5.0, 6.0, 4.0),
            Vec3::new(0.4, 5.7, 3.9),
            Vec3::new(-3.0, 100.0, 2.0),
        ] {
            let g = gradient(&s, p, spacing);
            assert!(close(g, exact, 1e-5), "{p}: {g} vs {exact}");
        }
    }

    /// For a quadratic `q`, `(q(x + h) - q(x - h)) / 2h = q'(x)` exactly (the `x^2` terms
    /// cancel: `(x + h)^2 - (x - h)^2 = 4 x h`). At interior grid points the stencil samples
    /// land on grid points, where the trilinear field equals `q`, so the +-1 voxel central
    /// difference is exact there (between grid points the trilinear field is not quadratic).
    #[test]
    fn gradient_of_quadratic_is_exact_at_interior_grid_points() {
        let dims = [7, 6, 8];
        let q = |x: f32, y: f32, z: f32| 0.5 * x * x - 0.25 * y * y + 0.1 * z * z + x * y - z;
        let dq = |x: f32, y: f32, z: f32| Vec3::new(x + y, -0.5 * y + x, 0.2 * z - 1.0);
        let v = grid(dims, q);
        let s = Trilinear::new(&v, dims);
        let spacing = Vec3::new(0.7, 1.3, 2.0);
        for k in 1..dims[2] - 1 {
            for j in 1..dims[1] - 1 {
                for i in 1..dims[0] - 1 {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    let g = gradient(&s, p, spacing);
                    let exact = dq(p.x, p.y, p.z) / spacing;
                    assert!(close(g, exact, 1e-5), "{p}: {g} vs {exact}");
                }
            }
        }
    }

    #[test]
    fn gradient_never_panics_and_stays_finite() {
        let dims = [3, 3, 3];
        let mut v = grid(dims, |x, y, z| x + y + z);
        v[13] = f32::NAN; // centre sample undefined
        let s = Trilinear::new(&v, dims);
        for p in [
            Vec3::NAN,
            Vec3::splat(f32::INFINITY),
            Vec3::splat(1.0),
            Vec3::new(0.5, 1.5, 1.0),
        ] {
            for spacing in [Vec3::ONE, Vec3::ZERO, Vec3::NAN, Vec3::splat(-1.0)] {
                assert!(gradient(&s, p, spacing).is_finite());
            }
        }
        let one = [5.0f32];
        assert_eq!(
            gradient(&Trilinear::new(&one, [1, 1, 1]), Vec3::ONE, Vec3::ONE),
            Vec3::ZERO
        );
        let empty: [f32; 0] = [];
        assert!(GradientVolume::build(&Trilinear::new(&empty, [0, 4, 4]), Vec3::ONE, 0).is_err());
    }

    #[test]
    fn gradient_volume_matches_on_the_fly_gradient_in_the_interior() {
        let dims = [9, 8, 10];
        let v = grid(dims, |x, y, z| {
            (0.7 * x).sin() * 40.0 + y * y - (0.3 * z).cos() * 10.0
        });
        let s = Trilinear::new(&v, dims);
        let spacing = Vec3::new(0.8, 1.0, 1.6);
        let gv = GradientVolume::build(&s, spacing, 7).unwrap();
        assert!(gv.is_current(dims, 7));
        assert!(!gv.is_current(dims, 8));
        assert!(!gv.is_current([9, 8, 11], 7));
        assert_eq!(gv.bytes(), 9 * 8 * 10 * 8);
        // Bound on the largest world-unit gradient component of this field.
        let max = 40.0 * 0.7 / 0.8 + 2.0 * 7.0;
        for p in [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(3.3, 2.7, 4.9),
            Vec3::new(6.9, 5.1, 7.5),
            Vec3::new(2.0, 4.0, 8.0),
        ] {
            let a = gv.gradient(p);
            let b = gradient(&s, p, spacing);
            assert!((a - b).abs().max_element() <= 1e-4 * max, "{p}: {a} vs {b}");
        }
        // Border grid points: one-sided differences, as on the fly.
        for p in [
            Vec3::ZERO,
            Vec3::new(8.0, 7.0, 9.0),
            Vec3::new(0.0, 3.0, 9.0),
        ] {
            let a = gv.gradient(p);
            let b = gradient(&s, p, spacing);
            assert!((a - b).abs().max_element() <= 1e-4 * max, "{p}: {a} vs {b}");
        }
        assert!(gv.gradient(Vec3::NAN).is_finite());
        assert!(gv.gradient(Vec3::splat(1e30)).is_finite());
    }

    /// Build time of a 256^3 volume; run with
    /// `cargo test -p volux-render --lib gradient_volume_build_time -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn gradient_volume_build_time_256() {
        let n = 256;
        let dims = [n, n, n];
        let v: Vec<u16> = (0..n * n * n)
            .map(|i| ((i * 2654435761usize) >> 7) as u16 & 0x0fff)
            .collect();
        let s = Trilinear::new(&v, dims);
        let t = std::time::Instant::now();
        let gv = GradientVolume::build(&s, Vec3::ONE, 1).unwrap();
        let build = t.elapsed();
        let t = std::time::Instant::now();
        let mut acc = Vec3::ZERO;
        for j in 0..n {
            for i in 0..n {
                acc += gradient(
                    &s,
                    Vec3::new(i as f32 + 0.3, j as f32 + 0.6, 100.4),
                    Vec3::ONE,
                );
            }
        }
        let fly = t.elapsed();
        let t = std::time::Instant::now();
        for j in 0..n {
            for i in 0..n {
                acc += gv.gradient(Vec3::new(i as f32 + 0.3, j as f32 + 0.6, 100.4));
            }
        }
        let lookup = t.elapsed();
        println!(
            "256^3 gradient volume: build {:.3} s ({} MB); 65536 gradients on the fly {:.2} ms, \
             by lookup {:.2} ms ({acc})",
            build.as_secs_f64(),
            gv.bytes() >> 20,
            fly.as_secs_f64() * 1e3,
            lookup.as_secs_f64() * 1e3
        );
    }

    fn approx(a: [f32; 3], b: [f32; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
    }

    #[test]
    fn light_along_the_normal_gives_ambient_diffuse_and_specular() {
        let bp = BlinnPhong::default();
        let rgb = [0.5, 0.2, 1.0];
        // Looking down -z at a surface whose gradient is along z: headlight along the normal.
        let out = bp.shade(rgb, Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0));
        let k = bp.ambient + bp.diffuse;
        assert!(approx(out, rgb.map(|c| c * k + bp.specular)), "{out:?}");
        // The same with a directional light along the normal.
        let dir = BlinnPhong {
            light: Light::Direction(Vec3::new(0.0, 0.0, 5.0)),
            ..bp
        };
        let out = dir.shade(rgb, Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -2.0));
        assert!(approx(out, rgb.map(|c| c * k + bp.specular)), "{out:?}");
    }

    #[test]
    fn light_perpendicular_to_the_normal_gives_ambient_only() {
        let bp = BlinnPhong {
            light: Light::Direction(Vec3::X),
            ..Default::default()
        };
        let rgb = [0.5, 0.2, 1.0];
        let out = bp.shade(rgb, Vec3::Z, -Vec3::Z);
        assert!(approx(out, rgb.map(|c| c * bp.ambient)), "{out:?}");
        // Light behind the surface: ambient only as well.
        let behind = BlinnPhong {
            light: Light::Direction(-Vec3::Z),
            ..bp
        };
        let out = behind.shade(rgb, Vec3::Z, -Vec3::Z);
        assert!(approx(out, rgb.map(|c| c * bp.ambient)), "{out:?}");
    }

    #[test]
    fn weak_or_invalid_gradients_leave_the_colour_unchanged() {
        let bp = BlinnPhong {
            min_gradient: 0.5,
            ..Default::default()
        };
        let rgb = [0.5, 0.2, 1.0];
        assert_eq!(bp.shade(rgb, Vec3::new(0.0, 0.3, 0.3), -Vec3::Z), rgb);
        assert_eq!(bp.shade(rgb, Vec3::ZERO, -Vec3::Z), rgb);
        assert_eq!(bp.shade(rgb, Vec3::NAN, -Vec3::Z), rgb);
        assert_eq!(bp.shade(rgb, Vec3::Z, Vec3::ZERO), rgb);
        assert_eq!(bp.shade(rgb, Vec3::Z, Vec3::NAN), rgb);
        assert_ne!(bp.shade(rgb, Vec3::new(0.0, 0.0, 0.6), -Vec3::Z), rgb);
        let bad = BlinnPhong {
            light: Light::Direction(Vec3::NAN),
            ..bp
        };
        assert!(bad.validate().is_err());
        assert!(bad
            .shade(rgb, Vec3::Z, -Vec3::Z)
            .iter()
            .all(|c| c.is_finite()));
        assert!(BlinnPhong::default().validate().is_ok());
    }

    #[test]
    fn shading_is_two_sided() {
        let bp = BlinnPhong {
            light: Light::Direction(Vec3::new(0.3, 0.2, 1.0)),
            ..Default::default()
        };
        let rgb = [0.5, 0.2, 1.0];
        let g = Vec3::new(0.2, -0.4, 1.0);
        let view = Vec3::new(0.1, 0.1, -1.0);
        let a = bp.shade(rgb, g, view);
        let b = bp.shade(rgb, -g, view);
        assert!(approx(a, b), "{a:?} vs {b:?}");
        assert!(a[0] > rgb[0] * bp.ambient + 0.1);
    }

    #[test]
    fn relative_threshold_and_serde_names() {
        let t = BlinnPhong::relative_min_gradient([0.0, 1000.0], Vec3::new(0.5, 1.0, 2.0), 0.01);
        assert!((t - 20.0).abs() < 1e-4);
        assert_eq!(
            BlinnPhong::relative_min_gradient([0.0, 1.0], Vec3::ZERO, 0.01),
            0.0
        );
        use serde::de::value::{Error, StrDeserializer};
        use serde::de::IntoDeserializer;
        let d: StrDeserializer<Error> = "headlight".into_deserializer();
        assert_eq!(Light::deserialize(d).unwrap(), Light::Headlight);
    }
}
