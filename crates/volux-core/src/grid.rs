//! Regular grids of scalars kept in their native type.
//!
//! Samples are stored as `u8`, `u16`, `i16` or `f32` (other types are converted by the readers,
//! with a note), either owned or memory-mapped straight from an uncompressed little-endian file.
//! Index order is x fastest, then y, then z (C array `[z][y][x]`).
use std::sync::Arc;

use glam::{DMat3, DVec3};

use crate::aabb::Aabb;
use crate::color::Rgb;
use crate::error::{Error, Result};
use crate::limits::{check_alloc, checked_dims};
pub use crate::samples::{Buffer, Samples, Scalar, ScalarType};
use crate::volume_axes::{AxisKind, ExtraAxis};

/// The largest magnitude a grid coordinate (origin, far corner) or spacing may have: beyond it
/// the bounds, camera distances and their squares stop being usable numbers.
pub const MAX_COORDINATE: f64 = 1e30;

/// The smallest spacing accepted: below it, voxel sizes and their cubes lose all precision.
pub const MIN_SPACING: f64 = 1e-30;

const AXES: [&str; 3] = ["x", "y", "z"];

/// A number for a message: plain when moderate, in exponent form when tiny or huge (so 1e308
/// does not print 309 digits).
fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Checks spacing and origin, axis by axis: spacing finite and > 0 ([`Error::InvalidSpacing`]),
/// then spacing a normal number in [[`MIN_SPACING`], [`MAX_COORDINATE`]], origin finite, and
/// the origin and far corner within ±[`MAX_COORDINATE`] with the spacing not lost beside the
/// origin ([`Error::InvalidGeometry`] naming the field and the value).
fn check_geometry(dims: [usize; 3], spacing: [f64; 3], origin: [f64; 3]) -> Result<()> {
    if spacing.iter().any(|s| !s.is_finite() || *s <= 0.0) {
        return Err(Error::InvalidSpacing(spacing));
    }
    for axis in 0..3 {
        axis_geometry(AXES[axis], dims[axis], spacing[axis], origin[axis])
            .map_err(Error::InvalidGeometry)?;
    }
    Ok(())
}

/// The checks of [`check_geometry`] on one axis; the reason of a failure.
fn axis_geometry(
    axis: &str,
    dim: usize,
    spacing: f64,
    origin: f64,
) -> std::result::Result<(), String> {
    let (lo, hi) = (num(MIN_SPACING), num(MAX_COORDINATE));
    if !spacing.is_normal() || !(MIN_SPACING..=MAX_COORDINATE).contains(&spacing) {
        return Err(format!(
            "spacing along {axis} is {}, outside [{lo}, {hi}]",
            num(spacing)
        ));
    }
    if !origin.is_finite() || origin.abs() > MAX_COORDINATE {
        return Err(format!(
            "origin along {axis} is {}, not a finite number within ±{hi}",
            num(origin)
        ));
    }
    let steps = dim.saturating_sub(1);
    let far = origin + spacing * steps as f64;
    if !far.is_finite() || far.abs() > MAX_COORDINATE {
        return Err(format!(
            "the far corner along {axis} is at {} (origin {} + spacing {} x {steps} steps), beyond ±{hi}",
            num(far),
            num(origin),
            num(spacing)
        ));
    }
    if origin + spacing == origin {
        return Err(format!(
            "spacing along {axis} ({}) is lost beside the origin {} (below the precision of a 64-bit float)",
            num(spacing),
            num(origin)
        ));
    }
    Ok(())
}

/// A regular grid: dims, anisotropic spacing, origin, direction and native-type samples.
///
/// Built only through [`Grid::new`], which validates sizes, computes the value range, and
/// replaces non-finite values (reported in [`Grid::notes`]) so renderers never see NaN.
///
/// World coordinates are LPS millimetres (DICOM, ITK; see [`crate::orientation`]): sample
/// (i, j, k) lies at `origin + D * (spacing ∘ (i, j, k))`, where `D` is the
/// [direction matrix](Grid::direction) (identity unless set by [`Grid::with_direction`]).
#[derive(Clone, Debug)]
pub struct Grid {
    dims: [usize; 3],
    spacing: DVec3,
    origin: DVec3,
    direction: DMat3,
    samples: Samples,
    range: [f64; 2],
    notes: Vec<String>,
    /// Axes beyond x, y, z of the file this grid is one volume of.
    extra_axes: Vec<ExtraAxis>,
    /// The voxels' colour, for an RGB grid (whose samples are then its luminance).
    color: Option<Arc<Rgb>>,
    /// The unit of spacing and origin when the file says it is not the millimetre.
    unit: Option<String>,
}

impl Grid {
    /// Builds and validates a grid. Non-finite `f32` values are counted, noted, and replaced by
    /// the finite minimum (NaN, -Inf) or maximum (+Inf).
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        samples: Samples,
    ) -> Result<Self> {
        let (dims, count) = checked_dims(dims.map(|d| d as i64))?;
        check_geometry(dims, spacing, origin)?;
        if samples.len() as u64 != count {
            return Err(Error::SizeMismatch {
                expected: count,
                actual: samples.len() as u64,
            });
        }
        let mut grid = Self {
            dims,
            spacing: DVec3::from(spacing),
            origin: DVec3::from(origin),
            direction: DMat3::IDENTITY,
            samples,
            range: [0.0, 0.0],
            notes: Vec::new(),
            extra_axes: Vec::new(),
            color: None,
            unit: None,
        };
        grid.sanitize_and_range();
        Ok(grid)
    }

    /// Builds an RGB grid: its samples are the colour's luminance ([`Rgb::luminance`]), which
    /// classification and measurement use, and [`Grid::color`] keeps the colour.
    pub fn from_rgb(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        rgb: Rgb,
    ) -> Result<Self> {
        let mut grid = Self::new(dims, spacing, origin, rgb.luminance())?;
        grid.extra_axes
            .push(ExtraAxis::new(AxisKind::Color, 3, None));
        grid.color = Some(Arc::new(rgb));
        Ok(grid)
    }

    /// The voxels' colour when the grid is an RGB image (its samples are then the luminance).
    pub fn color(&self) -> Option<&Rgb> {
        self.color.as_deref()
    }

    /// [`Grid::color`], shared (renderers keep it beside their caches).
    pub fn color_shared(&self) -> Option<Arc<Rgb>> {
        self.color.clone()
    }

    /// This grid with a record of an axis beyond x, y, z along which its file holds other
    /// volumes (time, b-values, components), for `volux info` and the viewer.
    pub fn with_extra_axis(mut self, axis: ExtraAxis) -> Self {
        self.extra_axes.push(axis);
        self
    }

    /// This grid with its spacing and origin in `unit` (a symbol: `µm`, `nm`, `cm`, `m`; `mm`
    /// is the default and is not recorded), as microscopy files give them. Measurements and
    /// writers carry it.
    pub fn with_unit(mut self, unit: &str) -> Self {
        self.unit = (unit != "mm").then(|| unit.to_string());
        self
    }

    /// The unit of spacing, origin and every world distance: `"mm"` (the default, the
    /// patient coordinates of DICOM, NIfTI and NRRD) unless the file says otherwise.
    pub fn unit(&self) -> &str {
        self.unit.as_deref().unwrap_or("mm")
    }

    /// The axes beyond x, y, z of the file this grid comes from (the colour channels of an
    /// RGB grid among them); empty for a plain 3-D file.
    pub fn extra_axes(&self) -> &[ExtraAxis] {
        &self.extra_axes
    }

    fn sanitize_and_range(&mut self) {
        use rayon::prelude::*;
        let (lo, hi, bad) = crate::with_samples!(&self.samples, |s| s
            .par_chunks(1 << 16)
            .map(|c| {
                c.iter().fold(
                    (f64::INFINITY, f64::NEG_INFINITY, 0usize),
                    |(lo, hi, bad), v| {
                        let v = v.to_f32() as f64;
                        if v.is_finite() {
                            (lo.min(v), hi.max(v), bad)
                        } else {
                            (lo, hi, bad + 1)
                        }
                    },
                )
            })
            .reduce(
                || (f64::INFINITY, f64::NEG_INFINITY, 0),
                |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2),
            ));
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) };
        self.range = [lo, hi];
        if bad > 0 {
            if let Samples::F32(b) = &self.samples {
                let fixed: Vec<f32> = b
                    .iter()
                    .map(|&v| match v {
                        v if v.is_finite() => v,
                        v if v == f32::INFINITY => hi as f32,
                        _ => lo as f32,
                    })
                    .collect();
                self.samples = Samples::F32(Buffer::owned(fixed));
            }
            self.notes.push(format!(
                "{bad} non-finite values (NaN/Inf) replaced: NaN and -Inf by the minimum {lo}, +Inf by the maximum {hi}"
            ));
        }
    }

    /// Adds a note (e.g. "converted from float64 to float32") reported by `volux info`.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// Notes on conversions and repairs made while loading.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
    /// Number of samples along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// Distance between samples along x, y, z (world units, mm for medical data).
    pub fn spacing(&self) -> DVec3 {
        self.spacing
    }
    /// World position of sample (0, 0, 0).
    pub fn origin(&self) -> DVec3 {
        self.origin
    }
    /// The samples.
    pub fn samples(&self) -> &Samples {
        &self.samples
    }
    /// Native scalar type.
    pub fn scalar_type(&self) -> ScalarType {
        self.samples.scalar_type()
    }
    /// `[min, max]` of the (finite) values.
    pub fn range(&self) -> [f64; 2] {
        self.range
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }
    /// Always false: a valid grid has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }
    /// Linear index of sample (i, j, k).
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }
    /// Value of sample (i, j, k) as f32.
    #[inline]
    pub fn value(&self, i: usize, j: usize, k: usize) -> f32 {
        self.samples.get_f32(self.index(i, j, k))
    }
    /// World position (LPS mm) of sample (i, j, k).
    pub fn position(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.index_to_world(DVec3::new(i as f64, j as f64, k as f64))
    }
    /// This grid with the direction matrix `direction` (columns: the unit LPS world directions
    /// of the index axes i, j, k, as ITK's `Direction` and DICOM's direction cosines), about
    /// the same origin. Columns within 1e-3 of unit length are normalized; a non-finite,
    /// non-unit or non-orthogonal matrix is refused with [`Error::InvalidGeometry`]
    /// ([`crate::orientation::validate_direction`]); so is one that puts a corner beyond
    /// ±[`MAX_COORDINATE`].
    pub fn with_direction(mut self, direction: DMat3) -> Result<Self> {
        self.direction = crate::orientation::validate_direction(direction)?;
        let b = self.bounds();
        if !(b.min.abs().max_element() <= MAX_COORDINATE
            && b.max.abs().max_element() <= MAX_COORDINATE)
        {
            return Err(Error::InvalidGeometry(format!(
                "the rotated grid reaches {} .. {}, beyond ±{}",
                b.min,
                b.max,
                num(MAX_COORDINATE)
            )));
        }
        Ok(self)
    }
    /// The direction matrix: columns are the unit world (LPS) directions of the index axes.
    pub fn direction(&self) -> DMat3 {
        self.direction
    }
    /// Whether the direction is exactly the identity (index axes along world x, y, z).
    pub fn is_axis_aligned(&self) -> bool {
        self.direction == DMat3::IDENTITY
    }
    /// The orientation code ("LPS" for the identity, "RAS", "PIL", ...): the patient
    /// direction each index axis points towards ([`crate::orientation::orientation_code`]).
    pub fn orientation_code(&self) -> String {
        crate::orientation::orientation_code(&self.direction)
    }
    /// The world point (LPS mm) of a continuous index position:
    /// `origin + D * (spacing ∘ index)`.
    pub fn index_to_world(&self, index: DVec3) -> DVec3 {
        let local = self.spacing * index;
        if self.is_axis_aligned() {
            self.origin + local
        } else {
            self.origin + self.direction * local
        }
    }
    /// The continuous index position of a world point (LPS mm), the inverse of
    /// [`Grid::index_to_world`]: `(Dᵀ (p - origin)) / spacing` (D is orthonormal).
    pub fn world_to_index(&self, p: DVec3) -> DVec3 {
        let rel = p - self.origin;
        if self.is_axis_aligned() {
            rel / self.spacing
        } else {
            (self.direction.transpose() * rel) / self.spacing
        }
    }
    /// World (LPS) axis-aligned bounding box of the sample positions: the box of the eight
    /// corners of the index box, rotated by the direction matrix.
    pub fn bounds(&self) -> Aabb {
        let d = DVec3::new(
            (self.dims[0] - 1) as f64,
            (self.dims[1] - 1) as f64,
            (self.dims[2] - 1) as f64,
        );
        if self.is_axis_aligned() {
            return Aabb {
                min: self.origin,
                max: self.origin + d * self.spacing,
            };
        }
        let index_box = Aabb {
            min: DVec3::ZERO,
            max: d,
        };
        let corners = index_box.corners().map(|c| self.index_to_world(c));
        Aabb::from_points(corners).unwrap_or(Aabb {
            min: self.origin,
            max: self.origin,
        })
    }
    /// Bytes held by the samples.
    pub fn memory_bytes(&self) -> usize {
        self.len() * self.scalar_type().size() + self.color().map_or(0, Rgb::memory_bytes)
    }
    /// All values converted to f32 (a copy; used by writers and tests, not by renderers).
    pub fn to_f32_vec(&self) -> Result<Vec<f32>> {
        check_alloc("f32 copy of the grid", self.len() as u64, 4)?;
        Ok(crate::with_samples!(&self.samples, |s| s
            .iter()
            .map(|v| v.to_f32())
            .collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_replaced_and_noted() {
        let s = Samples::F32(Buffer::owned(vec![1.0, f32::NAN, 3.0, f32::INFINITY]));
        let g = Grid::new([2, 2, 1], [1.0; 3], [0.0; 3], s).unwrap();
        assert_eq!(g.range(), [1.0, 3.0]);
        assert_eq!(g.notes().len(), 1);
        assert_eq!(g.value(1, 0, 0), 1.0);
        assert_eq!(g.value(1, 1, 0), 3.0);
    }

    #[test]
    fn size_mismatch_is_error() {
        let s = Samples::U8(Buffer::owned(vec![0; 7]));
        assert!(matches!(
            Grid::new([2, 2, 2], [1.0; 3], [0.0; 3], s),
            Err(Error::SizeMismatch { .. })
        ));
    }

    #[test]
    fn bad_spacing_is_error() {
        let s = Samples::U8(Buffer::owned(vec![0; 8]));
        assert!(Grid::new([2, 2, 2], [1.0, 0.0, 1.0], [0.0; 3], s).is_err());
    }

    /// The message of the error `Grid::new` gives for this geometry on a 2x2x2 grid.
    fn geometry_error(spacing: [f64; 3], origin: [f64; 3]) -> String {
        let s = Samples::U8(Buffer::owned(vec![0; 8]));
        match Grid::new([2, 2, 2], spacing, origin, s) {
            Ok(_) => panic!("spacing {spacing:?} origin {origin:?} accepted"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn hostile_geometry_is_refused_with_the_field_and_value() {
        let m = geometry_error([1.0, f64::NAN, 1.0], [0.0; 3]);
        assert!(m.contains("spacing") && m.contains("NaN"), "{m}");
        let m = geometry_error([1.0, 1.0, -2.0], [0.0; 3]);
        assert!(m.contains("spacing") && m.contains("-2"), "{m}");
        let m = geometry_error([1e308, 1.0, 1.0], [0.0; 3]);
        assert!(m.contains("spacing along x is 1e308"), "{m}");
        let m = geometry_error([1.0, 1e-310, 1.0], [0.0; 3]);
        assert!(m.contains("spacing along y is 1e-310"), "{m}");
        let m = geometry_error([1.0, 1.0, 1e-31], [0.0; 3]);
        assert!(m.contains("spacing along z is 1e-31"), "{m}");
        let m = geometry_error([1.0; 3], [0.0, f64::INFINITY, 0.0]);
        assert!(m.contains("origin along y is inf"), "{m}");
        let m = geometry_error([1.0; 3], [-1e31, 0.0, 0.0]);
        assert!(m.contains("origin along x is -1e31"), "{m}");
        let m = geometry_error([1.0, 1.0, 6e29], [0.0, 0.0, 5e29]);
        assert!(m.contains("far corner along z is at 1.1e30"), "{m}");
        let m = geometry_error([1.0, 1.0, 1.0], [0.0, 1e20, 0.0]);
        assert!(
            m.contains("spacing along y (1) is lost beside the origin 1e20"),
            "{m}"
        );
        assert_eq!(m.lines().count(), 1, "{m}");
    }

    #[test]
    fn ordinary_geometry_is_kept() {
        for (spacing, origin) in [
            ([0.5, 0.75, 2.0], [-120.0, 30.5, 1e6]),
            ([1e-6; 3], [1e-3; 3]),
            ([1e29; 3], [-1e29; 3]),
        ] {
            let s = Samples::U8(Buffer::owned(vec![0; 8]));
            let g = Grid::new([2, 2, 2], spacing, origin, s).unwrap();
            assert_eq!(g.spacing().to_array(), spacing);
            assert_eq!(g.origin().to_array(), origin);
            assert!(g.bounds().diagonal().is_finite());
        }
    }

    #[test]
    fn mapped_file_reads_values() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.raw");
        let vals: Vec<u16> = (0..24).collect();
        std::fs::write(&p, bytemuck::cast_slice::<u16, u8>(&vals)).unwrap();
        let b = Buffer::<u16>::map_file(&p, 0, 24).unwrap().unwrap();
        assert!(b.is_mapped());
        assert_eq!(&b[..], &vals[..]);
        assert!(Buffer::<u16>::map_file(&p, 0, 25).is_err());
    }

    #[test]
    fn from_bytes_big_endian() {
        let s = Samples::from_bytes(ScalarType::I16, &[0xFF, 0xFE, 0x00, 0x01], false).unwrap();
        assert_eq!(s.get_f32(0), -2.0);
        assert_eq!(s.get_f32(1), 1.0);
    }

    fn grid_4x3x2() -> Grid {
        let s = Samples::U8(Buffer::owned(vec![0; 24]));
        Grid::new([4, 3, 2], [1.0, 2.0, 3.0], [10.0, 20.0, 30.0], s).unwrap()
    }

    #[test]
    fn oblique_direction_bounds_are_the_rotated_corners() {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let rot = DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z);
        let g = grid_4x3x2().with_direction(rot).unwrap();
        // Extents 3, 4, 3 along i, j, k; corners (3c, 3s), (-4s, 4c), (3c-4s, 3s+4c).
        let b = g.bounds();
        let want_min = DVec3::new(10.0 - 4.0 * s, 20.0, 30.0);
        let want_max = DVec3::new(10.0 + 3.0 * c, 20.0 + 3.0 * s + 4.0 * c, 33.0);
        assert!((b.min - want_min).abs().max_element() < 1e-12, "{b:?}");
        assert!((b.max - want_max).abs().max_element() < 1e-12, "{b:?}");
        let p = DVec3::new(1.5, 0.25, 1.0);
        let w = g.index_to_world(p);
        assert!((g.world_to_index(w) - p).abs().max_element() < 1e-12);
        assert_eq!(g.orientation_code(), "LPS");
    }

    #[test]
    fn identity_direction_changes_nothing() {
        let g = grid_4x3x2();
        assert!(g.is_axis_aligned());
        assert_eq!(g.direction(), DMat3::IDENTITY);
        assert_eq!(g.position(3, 2, 1), DVec3::new(13.0, 24.0, 33.0));
        assert_eq!(g.bounds().max, DVec3::new(13.0, 24.0, 33.0));
        let sag = DMat3::from_cols(DVec3::Y, -DVec3::Z, DVec3::X);
        let g = g.with_direction(sag).unwrap();
        assert_eq!(g.orientation_code(), "PIL");
        assert_eq!(g.position(3, 2, 1), DVec3::new(13.0, 23.0, 26.0));
    }

    #[test]
    fn non_orthogonal_direction_is_refused() {
        let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.05, 1.0, 0.0).normalize(), DVec3::Z);
        match grid_4x3x2().with_direction(shear) {
            Err(Error::InvalidGeometry(m)) => assert!(m.contains("not orthogonal"), "{m}"),
            other => panic!("accepted or wrong error: {other:?}"),
        }
    }
}
