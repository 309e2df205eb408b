//! Field reconstruction: trilinear sampling of a regular grid in its native scalar type.
//!
//! The sampler reads `u8`/`u16`/`i16`/`f32` samples directly (no f32 copy of the volume) and
//! works in voxel coordinates, where sample (i, j, k) sits at (i, j, k).
use glam::{DVec3, Vec3};
use volux_core::grid::Scalar;

/// Samples computed together by [`Field::sample_lanes`]: the rays the grid ray caster's lane
/// stream advances together. Sixteen hide the latency of one lane's compositing chain and
/// corner loads behind the others' work: Marschner-Lobb 256^3 at 512x512, Riemann 0.5, took
/// 290 ms with 4 lanes, 210 with 8, 186 with 16, 190-200 with 24 or 32.
pub const LANES: usize = 16;

/// A regular scalar field that can be sampled in voxel coordinates.
pub trait Field: Sync {
    /// Samples per axis.
    fn dims(&self) -> [usize; 3];
    /// Trilinear value at voxel coordinates `p` (each in `[0, dims - 1]`), or `None` where the
    /// field is undefined (e.g. outside a resampled mesh).
    fn sample(&self, p: Vec3) -> Option<f32>;
    /// [`LANES`] samples at once, lane `l` at (`p[0][l]`, `p[1][l]`, `p[2][l]`), NaN where
    /// undefined; each lane equals [`Field::sample`] exactly. Fields override it to compute
    /// the lanes together (the ray casters' lane streams call it once per step).
    #[inline]
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        std::array::from_fn(|l| {
            self.sample(Vec3::new(p[0][l], p[1][l], p[2][l]))
                .unwrap_or(f32::NAN)
        })
    }
    /// [`Field::sample_lanes`] of the data this field wraps, without what it hides (a masked
    /// field's data, mask unread): exact at points where the caller knows the field hides
    /// nothing ([`CellClass::Sample`](crate::macrocell::CellClass) macrocells), and with
    /// [`Field::hide_lanes`] for the others. The same as `sample_lanes` by default.
    #[inline(always)]
    fn sample_lanes_unhidden(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        self.sample_lanes(p)
    }
    /// Sets to NaN the samples `v` of the lanes in the bit mask `lanes` whose points `p` this
    /// field hides (after [`Field::sample_lanes_unhidden`]). Nothing by default.
    #[inline(always)]
    fn hide_lanes(&self, _p: &[[f32; LANES]; 3], _v: &mut [f32; LANES], _lanes: u32) {}
    /// Four samples at once, as [`Field::sample_lanes`] (for integrators that sample a ray at
    /// four points together).
    #[inline]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        std::array::from_fn(|l| {
            self.sample(Vec3::new(p[0][l], p[1][l], p[2][l]))
                .unwrap_or(f32::NAN)
        })
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
    /// Offsets of the eight corners of a cell from its first, x fastest.
    corners: [usize; 8],
    /// `values` holds exactly `dims[0] dims[1] dims[2] >= 1` samples and every axis has fewer
    /// than 2^22: the lane sampler's clamped cells then have all their corners inside
    /// `values`, which its unchecked loads rely on (see [`Self::interpolate4`]).
    lanes_in_bounds: bool,
}

impl<'a, T: Scalar> Trilinear<'a, T> {
    /// A sampler over `values` laid out x fastest with `dims` samples per axis (a
    /// [`volux_core::Grid`] guarantees `values.len() == dims[0] dims[1] dims[2]`; a slice of
    /// another length is sampled only by the bounds-checked path).
    pub fn new(values: &'a [T], dims: [usize; 3]) -> Self {
        let count = dims[0]
            .checked_mul(dims[1])
            .and_then(|n| n.checked_mul(dims[2]));
        let lanes_in_bounds = count == Some(values.len())
            && !values.is_empty()
            && dims
                .iter()
                .all(|&n| (n as f64) < f64::from(FLOOR_SMALL_LIMIT));
        let stride = [1, dims[0], dims[0] * dims[1]];
        let step: [usize; 3] = std::array::from_fn(|a| if dims[a] > 1 { stride[a] } else { 0 });
        Self {
            values,
            dims,
            step,
            corners: std::array::from_fn(|q| {
                (0..3)
                    .map(|a| if q >> a & 1 == 1 { step[a] } else { 0 })
                    .sum()
            }),
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| u32::try_from(n.saturating_sub(2)).unwrap_or(u32::MAX)),
            lanes_in_bounds,
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
    /// [`Self::sample_raw`] of `N` points; each lane is bit-identical to `sample_raw`.
    ///
    /// The clamping, cell indices and fractions are computed lane-wise (SIMD); the corner
    /// loads and the interpolation per lane, in registers: assembling vectors from scalar
    /// loads would go through the stack, where wide loads of narrow stores stall.
    #[inline(always)]
    pub fn sample_raw_lanes<const N: usize>(&self, p: &[[f32; N]; 3]) -> [f32; N] {
        if !self.lanes_in_bounds {
            return std::array::from_fn(|l| self.sample_raw(Vec3::new(p[0][l], p[1][l], p[2][l])));
        }
        let mut cell = [[0i32; N]; 3];
        let mut frac = [[0.0f32; N]; 3];
        for a in 0..3 {
            let (hi, cmax) = (self.hi[a], self.cell_max[a].min(i32::MAX as u32) as i32);
            for l in 0..N {
                (cell[a][l], frac[a][l]) = clamped_cell(p[a][l], hi, cmax);
            }
        }
        let mut out = [0.0f32; N];
        let mut g = 0;
        while g + 4 <= N {
            let lanes = |a: &[f32; N]| -> [f32; 4] { [a[g], a[g + 1], a[g + 2], a[g + 3]] };
            let mut b = [0usize; 4];
            for (k, b) in b.iter_mut().enumerate() {
                let l = g + k;
                *b = cell[0][l] as usize
                    + self.dims[0] * (cell[1][l] as usize + self.dims[1] * cell[2][l] as usize);
            }
            out[g..g + 4].copy_from_slice(&self.interpolate4(
                b,
                lanes(&frac[0]),
                lanes(&frac[1]),
                lanes(&frac[2]),
            ));
            g += 4;
        }
        for l in g..N {
            out[l] = self.interpolate_cell([cell[0][l], cell[1][l], cell[2][l]], frac, l);
        }
        out
    }

    /// Trilinear interpolation in four cells (first samples `b`) at fractions `fx`, `fy`,
    /// `fz`: each corner is gathered into a four-lane array and the lerps run lane-wise.
    ///
    /// The corner loads skip bounds checks: 32 compare-and-branch pairs per call, and 10 % of
    /// a frame (`BENCHMARKS.md`: Riemann 0.5 on Marschner-Lobb 256^3 at 512x512, 167 ms with
    /// checks, 151 ms without).
    #[inline(always)]
    #[allow(unsafe_code)]
    fn interpolate4(&self, b: [usize; 4], fx: [f32; 4], fy: [f32; 4], fz: [f32; 4]) -> [f32; 4] {
        debug_assert!(self.lanes_in_bounds);
        let corner = |q: usize| -> [f32; 4] {
            let o = self.corners[q];
            debug_assert!(b.iter().all(|&b| b + o < self.values.len()));
            // SAFETY: only called from `sample_raw_lanes` when `lanes_in_bounds` holds, with
            // `b` from cell indices clamped to `[0, cell_max]` per axis (`cell_max = n - 2`, or
            // 0 for an axis of one sample). A corner adds at most one `step` per axis, which is
            // the stride where the axis has two or more samples and 0 otherwise, so along each
            // axis the corner's index is at most `n - 1`, and `b + o` is at most
            // `(nx - 1) + nx ((ny - 1) + ny (nz - 1)) = nx ny nz - 1 < values.len()`.
            unsafe {
                [
                    self.values.get_unchecked(b[0] + o).to_f32(),
                    self.values.get_unchecked(b[1] + o).to_f32(),
                    self.values.get_unchecked(b[2] + o).to_f32(),
                    self.values.get_unchecked(b[3] + o).to_f32(),
                ]
            }
        };
        let lerp = |a: [f32; 4], c: [f32; 4], f: [f32; 4]| -> [f32; 4] {
            [
                a[0] + (c[0] - a[0]) * f[0],
                a[1] + (c[1] - a[1]) * f[1],
                a[2] + (c[2] - a[2]) * f[2],
                a[3] + (c[3] - a[3]) * f[3],
            ]
        };
        let c00 = lerp(corner(0), corner(1), fx);
        let c10 = lerp(corner(2), corner(3), fx);
        let c01 = lerp(corner(4), corner(5), fx);
        let c11 = lerp(corner(6), corner(7), fx);
        let c0 = lerp(c00, c10, fy);
        let c1 = lerp(c01, c11, fy);
        lerp(c0, c1, fz)
    }

    /// The trilinear interpolation in `cell` at the fractions of lane `l`.
    #[inline(always)]
    fn interpolate_cell<const N: usize>(
        &self,
        cell: [i32; 3],
        frac: [[f32; N]; 3],
        l: usize,
    ) -> f32 {
        let [nx, ny, _] = self.dims;
        let b = cell[0] as usize + nx * (cell[1] as usize + ny * cell[2] as usize);
        let mut c = [0.0f32; 8];
        for (q, c) in c.iter_mut().enumerate() {
            *c = self.values[b + self.corners[q]].to_f32();
        }
        let (fx, fy, fz) = (frac[0][l], frac[1][l], frac[2][l]);
        let c00 = c[0] + (c[1] - c[0]) * fx;
        let c10 = c[2] + (c[3] - c[2]) * fx;
        let c01 = c[4] + (c[5] - c[4]) * fx;
        let c11 = c[6] + (c[7] - c[6]) * fx;
        let c0 = c00 + (c10 - c00) * fy;
        let c1 = c01 + (c11 - c01) * fy;
        c0 + (c1 - c0) * fz
    }
}

/// NaN for every non-finite value (undefined samples).
#[inline(always)]
fn undefined_to_nan<const N: usize>(mut r: [f32; N]) -> [f32; N] {
    for v in r.iter_mut() {
        if !v.is_finite() {
            *v = f32::NAN;
        }
    }
    r
}

/// The cell along one axis of voxel coordinate `v` and the fraction into it, for coordinates
/// clamped to `[0, hi]` (NaN going to 0) and cells to `[0, last_cell]` (`hi <= last_cell + 1`,
/// `hi < 2^22`): selects (one `maxps`/`minps` each) and [`floor_small`], no float-to-int cast,
/// so lanes compute it together; the cell is clamped by subtracting one where it passes
/// `last_cell`.
#[inline(always)]
pub(crate) fn clamped_cell(v: f32, hi: f32, last_cell: i32) -> (i32, f32) {
    let v = if v > 0.0 { v } else { 0.0 };
    let v = if v < hi { v } else { hi };
    let i = floor_small(v);
    let i = i - i32::from(i > last_cell);
    (i, v - i as f32)
}

/// Values below which [`floor_small`] is exact.
pub(crate) const FLOOR_SMALL_LIMIT: f32 = 4_194_304.0;

/// `floor(v)` for `0 <= v < 2^22`, computed without a float-to-int cast: Rust's casts
/// saturate, which x86-64's baseline SIMD cannot do lane-wise, so a loop of casts is
/// scalarized, while these adds, compares and bit moves stay in vector registers. Adding
/// `2^23` rounds `v` to the nearest integer (in the default rounding mode), whose value is
/// then in the low mantissa bits; one is taken off where rounding went up.
#[inline(always)]
pub(crate) fn floor_small(v: f32) -> i32 {
    const MAGIC: f32 = 8_388_608.0;
    let m = v + MAGIC;
    let rounded = m - MAGIC;
    (m.to_bits() as i32 - MAGIC.to_bits() as i32) - i32::from(rounded > v)
}

/// Cell index and fraction along one axis of `n` samples, clamped to the grid, in f64 (the
/// reference path's sampling, shared by every field with an f64 path).
pub(crate) fn axis64(x: f64, n: usize) -> (usize, f64) {
    if n < 2 {
        return (0, 0.0);
    }
    let x = x.clamp(0.0, (n - 1) as f64);
    let i = (x as usize).min(n - 2);
    (i, x - i as f64)
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
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        undefined_to_nan(self.sample_raw_lanes(p))
    }

    #[inline(always)]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        undefined_to_nan(self.sample_raw_lanes(p))
    }

    fn sample64(&self, p: DVec3) -> Option<f64> {
        let [nx, ny, nz] = self.dims;
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
    fn lanes_equal_single_samples() {
        let dims = [5, 4, 3];
        let v: Vec<u16> = (0..60).map(|i| (i * 37 % 101) as u16).collect();
        let s = Trilinear::new(&v, dims);
        let points = [
            [0.3, 4.0, -1.0, 2.7, 3.999, 0.0, 1.5, f32::NAN],
            [1.1, 3.0, 0.5, 9.0, 2.5, 0.0, 1e9, 1.0],
            [0.0, 2.0, 1.9, 0.4, 1.999, 2.0, 1.0, 1.0],
        ];
        // Every lane count: the points repeat, shifted by a third of a voxel each round.
        let p: [[f32; LANES]; 3] = std::array::from_fn(|a| {
            std::array::from_fn(|l| points[a][l % 8] + (l / 8) as f32 / 3.0)
        });
        let lanes = s.sample_lanes(&p);
        let four = s.sample4(&std::array::from_fn(|a| {
            std::array::from_fn(|l| p[a][l + 4])
        }));
        for l in 0..4 {
            assert_eq!(
                four[l].to_bits(),
                lanes[l + 4].to_bits(),
                "lane {l} of four"
            );
        }
        for l in 0..LANES {
            let one = s.sample(Vec3::new(p[0][l], p[1][l], p[2][l])).unwrap();
            assert_eq!(lanes[l].to_bits(), one.to_bits(), "lane {l}");
        }
        // Flat axes (one sample) read the same corner twice.
        let flat = Trilinear::new(&v[..20], [5, 4, 1]);
        let p = [[1.5; LANES], [2.25; LANES], [0.7; LANES]];
        let one = flat.sample(Vec3::new(1.5, 2.25, 0.7)).unwrap();
        assert!(flat
            .sample_lanes(&p)
            .iter()
            .all(|x| x.to_bits() == one.to_bits()));
    }

    /// The lane sampler's unchecked loads on the smallest and flattest grids, at points far
    /// outside, on the far faces and NaN: every lane equals the bounds-checked sampler (the
    /// loads' own debug assertions check each index in test builds).
    #[test]
    fn lane_loads_stay_inside_tiny_and_flat_grids() {
        let far = [
            -1e9,
            -0.5,
            0.0,
            0.25,
            0.999,
            1.0,
            1.5,
            2.0,
            6.0,
            1e9,
            f32::NAN,
            3.0,
        ];
        for dims in [
            [1, 1, 1],
            [2, 2, 2],
            [1, 7, 1],
            [3, 1, 2],
            [2, 1, 1],
            [4, 3, 5],
        ] {
            let n = dims[0] * dims[1] * dims[2];
            let v: Vec<u8> = (0..n).map(|i| (i * 53 % 251) as u8).collect();
            let s = Trilinear::new(&v, dims);
            assert!(s.lanes_in_bounds);
            for shift in 0..far.len() {
                let p: [[f32; LANES]; 3] = std::array::from_fn(|a| {
                    std::array::from_fn(|l| far[(l * (a + 1) + shift) % far.len()])
                });
                let lanes = s.sample_lanes(&p);
                for l in 0..LANES {
                    let one = s.sample(Vec3::new(p[0][l], p[1][l], p[2][l])).unwrap();
                    assert_eq!(lanes[l].to_bits(), one.to_bits(), "{dims:?} lane {l}");
                }
            }
        }
        // A slice that does not match its dimensions never takes the unchecked path.
        let v = vec![1.0f32; 9];
        let s = Trilinear::new(&v, [2, 2, 2]);
        assert!(!s.lanes_in_bounds);
        assert_eq!(s.sample_lanes(&[[0.5; LANES]; 3]), [1.0; LANES]);
        assert!(!Trilinear::new(&v[..0], [0, 0, 0]).lanes_in_bounds);
    }

    #[test]
    fn floor_small_is_the_floor() {
        for v in [
            0.0f32,
            0.25,
            0.5,
            0.75,
            1.0,
            1.5,
            2.5,
            3.49,
            254.999,
            255.0,
            4_194_303.5,
        ] {
            assert_eq!(floor_small(v), v.floor() as i32, "{v}");
        }
        let mut v = 0.0f32;
        while v < 600.0 {
            assert_eq!(floor_small(v), v.floor() as i32, "{v}");
            v += 0.013;
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
