//! Field reconstruction: trilinear sampling of a regular grid in its native scalar type.
//!
//! The sampler reads `u8`/`u16`/`i16`/`f32` samples directly (no f32 copy of the volume) and
//! works in voxel coordinates, where sample (i, j, k) sits at (i, j, k).
use glam::{DVec3, Vec3};
use volux_core::grid::Scalar;

/// A regular scalar field that can be sampled in voxel coordinates.
pub trait Field: Sync {
    /// Samples per axis.
    fn dims(&self) -> [usize; 3];
    /// Trilinear value at voxel coordinates `p` (each in `[0, dims - 1]`), or `None` where the
    /// field is undefined (e.g. outside a resampled mesh).
    fn sample(&self, p: Vec3) -> Option<f32>;
    /// Four samples at once, lane `l` at (`x[l]`, `y[l]`, `z[l]`), NaN where undefined; each
    /// lane equals [`Field::sample`] exactly. Fields override it to compute the lanes together.
    #[inline]
    fn sample4(&self, x: [f32; 4], y: [f32; 4], z: [f32; 4]) -> [f32; 4] {
        std::array::from_fn(|l| self.sample(Vec3::new(x[l], y[l], z[l])).unwrap_or(f32::NAN))
    }
    /// The same in f64 (the reference path); defaults to the f32 sample.
    fn sample64(&self, p: DVec3) -> Option<f64> {
        self.sample(p.as_vec3()).map(f64::from)
    }
}

/// Trilinear sampling of a native-type slice of samples.
#[derive(Clone, Copy, Debug)]
pub struct Trilinear<'a, T> {
    values: &'a [T],
    dims: [usize; 3],
    /// Offsets of the +1 neighbour along x, y, z (0 along an axis with one sample).
    step: [usize; 3],
    /// Largest coordinate and largest cell index per axis.
    hi: [f32; 3],
    cell_max: [u32; 3],
}

impl<'a, T: Scalar> Trilinear<'a, T> {
    /// A sampler over `values` laid out x fastest with `dims` samples per axis.
    pub fn new(values: &'a [T], dims: [usize; 3]) -> Self {
        debug_assert_eq!(values.len(), dims[0] * dims[1] * dims[2]);
        let stride = [1, dims[0], dims[0] * dims[1]];
        Self {
            values,
            dims,
            step: std::array::from_fn(|a| if dims[a] > 1 { stride[a] } else { 0 }),
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| u32::try_from(n.saturating_sub(2)).unwrap_or(u32::MAX)),
        }
    }
}

impl<T: Scalar> Trilinear<'_, T> {
    /// The trilinear value at `p` (clamped to the grid), NaN or infinite where a corner is.
    ///
    /// The hot path of every grid integrator: clamping by `max`/`min` (no panic branch),
    /// 32-bit cell indices (cheap float conversion), and plain loads (the clamped cell and its
    /// +1 neighbours are always inside the slice).
    #[inline(always)]
    pub fn sample_raw(&self, p: Vec3) -> f32 {
        let x = p.x.max(0.0).min(self.hi[0]);
        let y = p.y.max(0.0).min(self.hi[1]);
        let z = p.z.max(0.0).min(self.hi[2]);
        let [ci, cj, ck] = self.cell_max;
        let (i, j, k) = ((x as u32).min(ci), (y as u32).min(cj), (z as u32).min(ck));
        let (fx, fy, fz) = (x - i as f32, y - j as f32, z - k as f32);
        let [dx, sy, sz] = self.step;
        let b = i as usize + self.dims[0] * (j as usize + self.dims[1] * k as usize);
        // The x neighbours as one two-element slice: one bounds check per pair.
        let pair = |o: usize| -> (f32, f32) {
            if dx == 1 {
                match self.values[b + o..b + o + 2] {
                    [a, c] => (a.to_f32(), c.to_f32()),
                    _ => (f32::NAN, f32::NAN),
                }
            } else {
                let a = self.values[b + o].to_f32();
                (a, a)
            }
        };
        let lerp = |(a, c): (f32, f32)| a + (c - a) * fx;
        let c00 = lerp(pair(0));
        let c10 = lerp(pair(sy));
        let c01 = lerp(pair(sz));
        let c11 = lerp(pair(sz + sy));
        let c0 = c00 + (c10 - c00) * fy;
        let c1 = c01 + (c11 - c01) * fy;
        c0 + (c1 - c0) * fz
    }
}

impl<T: Scalar> Trilinear<'_, T> {
    /// [`Self::sample_raw`] of four points, the arithmetic done lane-wise (SIMD) and only the
    /// loads per lane; each lane is bit-identical to `sample_raw`.
    #[inline(always)]
    pub fn sample_raw4(&self, x: [f32; 4], y: [f32; 4], z: [f32; 4]) -> [f32; 4] {
        let [ci, cj, ck] = self.cell_max.map(|c| c.min(i32::MAX as u32) as i32);
        let axis = |v: [f32; 4], hi: f32, cmax: i32| -> ([i32; 4], [f32; 4]) {
            let v = v.map(|v| v.max(0.0).min(hi));
            let i: [i32; 4] = std::array::from_fn(|l| (v[l] as i32).min(cmax));
            (i, std::array::from_fn(|l| v[l] - i[l] as f32))
        };
        let (i, fx) = axis(x, self.hi[0], ci);
        let (j, fy) = axis(y, self.hi[1], cj);
        let (k, fz) = axis(z, self.hi[2], ck);
        let [dx, sy, sz] = self.step;
        let [nx, ny, _] = self.dims;
        let mut c = [[0.0f32; 4]; 4];
        for l in 0..4 {
            let b = i[l] as usize + nx * (j[l] as usize + ny * k[l] as usize);
            let pair = |o: usize| -> (f32, f32) {
                if dx == 1 {
                    match self.values[b + o..b + o + 2] {
                        [a, c] => (a.to_f32(), c.to_f32()),
                        _ => (f32::NAN, f32::NAN),
                    }
                } else {
                    let a = self.values[b + o].to_f32();
                    (a, a)
                }
            };
            for (q, o) in [0, sy, sz, sz + sy].into_iter().enumerate() {
                let (a, e) = pair(o);
                c[q][l] = a + (e - a) * fx[l];
            }
        }
        std::array::from_fn(|l| {
            let c0 = c[0][l] + (c[1][l] - c[0][l]) * fy[l];
            let c1 = c[2][l] + (c[3][l] - c[2][l]) * fy[l];
            c0 + (c1 - c0) * fz[l]
        })
    }
}

/// Cell index and fraction along one axis, clamped to the grid.
#[inline]
fn axis(x: f32, n: usize) -> (usize, f32) {
    if n < 2 {
        return (0, 0.0);
    }
    let x = x.clamp(0.0, (n - 1) as f32);
    let i = (x as usize).min(n - 2);
    (i, x - i as f32)
}

impl<T: Scalar> Field for Trilinear<'_, T> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    #[inline(always)]
    fn sample(&self, p: Vec3) -> Option<f32> {
        let r = self.sample_raw(p);
        r.is_finite().then_some(r)
    }

    #[inline(always)]
    fn sample4(&self, x: [f32; 4], y: [f32; 4], z: [f32; 4]) -> [f32; 4] {
        let r = self.sample_raw4(x, y, z);
        r.map(|v| if v.is_finite() { v } else { f32::NAN })
    }

    fn sample64(&self, p: DVec3) -> Option<f64> {
        let [nx, ny, nz] = self.dims;
        let axis64 = |x: f64, n: usize| -> (usize, f64) {
            if n < 2 {
                return (0, 0.0);
            }
            let x = x.clamp(0.0, (n - 1) as f64);
            let i = (x as usize).min(n - 2);
            (i, x - i as f64)
        };
        let (i, fx) = axis64(p.x, nx);
        let (j, fy) = axis64(p.y, ny);
        let (k, fz) = axis64(p.z, nz);
        let dx = usize::from(nx > 1);
        let sy = if ny > 1 { nx } else { 0 };
        let sz = if nz > 1 { nx * ny } else { 0 };
        let b = i + nx * (j + ny * k);
        let v = |o: usize| self.values[b + o].to_f32() as f64;
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c0 = lerp(lerp(v(0), v(dx), fx), lerp(v(sy), v(sy + dx), fx), fy);
        let c1 = lerp(
            lerp(v(sz), v(sz + dx), fx),
            lerp(v(sz + sy), v(sz + sy + dx), fx),
            fy,
        );
        let r = lerp(c0, c1, fz);
        r.is_finite().then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trilinear_reproduces_linear_fields() {
        let dims = [4, 5, 6];
        let f = |x: f32, y: f32, z: f32| 1.0 + 2.0 * x - 0.5 * y + 3.0 * z;
        let mut v = Vec::new();
        for k in 0..6 {
            for j in 0..5 {
                for i in 0..4 {
                    v.push(f(i as f32, j as f32, k as f32));
                }
            }
        }
        let s = Trilinear::new(&v, dims);
        for p in [
            Vec3::new(0.3, 1.7, 2.2),
            Vec3::new(3.0, 4.0, 5.0),
            Vec3::ZERO,
        ] {
            let got = s.sample(p).unwrap();
            assert!((got - f(p.x, p.y, p.z)).abs() < 1e-4, "{p}: {got}");
        }
    }

    #[test]
    fn four_lanes_equal_single_samples() {
        let dims = [5, 4, 3];
        let v: Vec<u16> = (0..60).map(|i| (i * 37 % 101) as u16).collect();
        let s = Trilinear::new(&v, dims);
        let (x, y, z) = (
            [0.3, 4.0, -1.0, 2.7],
            [1.1, 3.0, 0.5, 9.0],
            [0.0, 2.0, 1.9, 0.4],
        );
        let four = s.sample4(x, y, z);
        for l in 0..4 {
            let one = s.sample(Vec3::new(x[l], y[l], z[l])).unwrap();
            assert_eq!(four[l].to_bits(), one.to_bits(), "lane {l}");
        }
    }

    #[test]
    fn nan_corners_are_undefined() {
        let v = vec![0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let s = Trilinear::new(&v, [2, 2, 2]);
        assert!(s.sample(Vec3::splat(0.5)).is_none());
    }
}

/// The reconstruction filter of a grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Reconstruction {
    /// Trilinear interpolation (C0, interpolating; 8 samples).
    #[default]
    Trilinear,
    /// Tricubic Catmull-Rom (C1, interpolating; 64 samples; may overshoot).
    CatmullRom,
    /// Tricubic uniform B-spline (C2, approximating: smooths; 64 samples).
    BSpline,
}

/// Tricubic reconstruction (Catmull-Rom or B-spline) of native-type samples; borders are
/// handled by clamping indices (the data repeats its edge).
#[derive(Clone, Copy, Debug)]
pub struct Tricubic<'a, T> {
    values: &'a [T],
    dims: [usize; 3],
    bspline: bool,
}

impl<'a, T: Scalar> Tricubic<'a, T> {
    /// A Catmull-Rom (`bspline == false`) or B-spline sampler over `values` with `dims`.
    pub fn new(values: &'a [T], dims: [usize; 3], bspline: bool) -> Self {
        Self {
            values,
            dims,
            bspline,
        }
    }
}

/// The four cubic weights for fraction `t` of the cell between samples 1 and 2 of 0..3.
#[inline]
fn cubic_weights(t: f32, bspline: bool) -> [f32; 4] {
    let (t2, t3) = (t * t, t * t * t);
    if bspline {
        [
            (1.0 - t).powi(3) / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ]
    } else {
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ]
    }
}

impl<T: Scalar> Field for Tricubic<'_, T> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    fn sample(&self, p: Vec3) -> Option<f32> {
        let [nx, ny, nz] = self.dims;
        let (i, fx) = axis(p.x, nx);
        let (j, fy) = axis(p.y, ny);
        let (k, fz) = axis(p.z, nz);
        let (wx, wy, wz) = (
            cubic_weights(fx, self.bspline),
            cubic_weights(fy, self.bspline),
            cubic_weights(fz, self.bspline),
        );
        let idx = |c: usize, o: usize, n: usize| (c + o).saturating_sub(1).min(n - 1);
        let mut sum = 0.0f32;
        for (c, wk) in wz.iter().enumerate() {
            let kk = idx(k, c, nz);
            for (b, wj) in wy.iter().enumerate() {
                let row = nx * (idx(j, b, ny) + ny * kk);
                let mut line = 0.0;
                for (a, wi) in wx.iter().enumerate() {
                    line += wi * self.values[row + idx(i, a, nx)].to_f32();
                }
                sum += wk * wj * line;
            }
        }
        sum.is_finite().then_some(sum)
    }
}

#[cfg(test)]
mod tricubic_tests {
    use super::*;

    fn grid(f: impl Fn(f32, f32, f32) -> f32) -> (Vec<f32>, [usize; 3]) {
        let dims = [8, 7, 6];
        let mut v = Vec::new();
        for k in 0..6 {
            for j in 0..7 {
                for i in 0..8 {
                    v.push(f(i as f32, j as f32, k as f32));
                }
            }
        }
        (v, dims)
    }

    #[test]
    fn catmull_rom_interpolates_and_reproduces_quadratics_inside() {
        let f = |x: f32, y: f32, z: f32| 0.5 * x * x - y * z + 2.0 * z + 1.0;
        let (v, dims) = grid(f);
        let s = Tricubic::new(&v, dims, false);
        assert!((s.sample(Vec3::new(3.0, 2.0, 4.0)).unwrap() - f(3.0, 2.0, 4.0)).abs() < 1e-4);
        let p = Vec3::new(3.3, 2.6, 2.4);
        assert!(
            (s.sample(p).unwrap() - f(p.x, p.y, p.z)).abs() < 1e-3,
            "{}",
            s.sample(p).unwrap()
        );
    }

    #[test]
    fn bspline_reproduces_linear_fields_and_weights_sum_to_one() {
        for t in [0.0, 0.3, 0.77, 1.0] {
            for b in [false, true] {
                let w = cubic_weights(t, b);
                assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            }
        }
        let f = |x: f32, y: f32, z: f32| 2.0 * x - y + 0.5 * z;
        let (v, dims) = grid(f);
        let s = Tricubic::new(&v, dims, true);
        let p = Vec3::new(3.4, 2.2, 2.9);
        assert!((s.sample(p).unwrap() - f(p.x, p.y, p.z)).abs() < 1e-4);
    }
}
