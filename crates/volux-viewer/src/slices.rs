//! The slice views: three orthogonal planes of the data through the crosshair point, grey
//! through a window, with the patient or axis letters on their edges. Axial, coronal and
//! sagittal are the world's (LPS) planes: each is cut along the grid's index plane nearest to
//! it, whatever the acquisition (a sagittally acquired scan shows its slices in the sagittal
//! view), laid out as radiologists read them (axial: patient left on the right, anterior at
//! the top; coronal: left on the right, superior at the top; sagittal: posterior on the
//! right, superior at the top). For an oblique acquisition the planes are the nearest index
//! planes, and the letters say where they point. Meshes are resampled onto a grid once
//! ([`volux_render::resample::resample_mesh`]); outside the mesh a slice is dark blue.
use std::sync::Arc;

use glam::{DMat3, DVec3};
use volux_core::{orientation, Grid, TetMesh};
use volux_render::resample::resample_mesh;

/// Samples along the longest side of a mesh's resampled slice grid.
pub const MESH_SLICE_SAMPLES: usize = 256;

/// What the slices are cut from.
#[derive(Clone, Debug)]
enum Values {
    Grid(Arc<Grid>),
    Resampled(Arc<Vec<f32>>),
}

/// A grid to slice: the data's own, or a mesh resampled.
#[derive(Clone, Debug)]
pub struct SliceVolume {
    dims: [usize; 3],
    origin: DVec3,
    spacing: DVec3,
    /// World directions of the index axes (a grid's direction cosines; identity for meshes).
    direction: DMat3,
    values: Values,
}

/// The three planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    /// Across the feet-head axis (world z).
    Axial,
    /// Across the front-back axis (world y).
    Coronal,
    /// Across the left-right axis (world x).
    Sagittal,
}

/// How a plane is cut from the grid: the index axis held fixed, the one across the image
/// (reversed: column 0 is its last index) and the one down it (upward: row 0 is its last
/// index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    fixed: usize,
    across: usize,
    across_reversed: bool,
    down: usize,
    upward: bool,
}

impl Layout {
    /// The index along `across` of column `c` (of `n`).
    fn column(&self, c: usize, n: usize) -> usize {
        if self.across_reversed {
            n - 1 - c
        } else {
            c
        }
    }

    /// The index along `down` of row `r` (of `n`).
    fn row(&self, r: usize, n: usize) -> usize {
        if self.upward {
            n - 1 - r
        } else {
            r
        }
    }
}

impl Plane {
    /// The three, in display order.
    pub const ALL: [Plane; 3] = [Plane::Axial, Plane::Coronal, Plane::Sagittal];

    /// The world directions of the image's right and top.
    fn screen(self) -> (DVec3, DVec3) {
        match self {
            Plane::Axial => (DVec3::X, -DVec3::Y),
            Plane::Coronal => (DVec3::X, DVec3::Z),
            Plane::Sagittal => (DVec3::Y, DVec3::Z),
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Plane::Axial => "axial",
            Plane::Coronal => "coronal",
            Plane::Sagittal => "sagittal",
        }
    }
}

/// The LPS patient letter of a world direction ([`orientation::patient_letter`]; `?` for
/// a zero vector).
pub fn patient_letter(d: DVec3) -> char {
    orientation::patient_letter(d).unwrap_or('?')
}

/// How the views name a world direction: its patient letter for medical data, its axis
/// (`+X` ... `-Z`) otherwise.
pub fn direction_name(d: DVec3, medical: bool) -> String {
    if medical {
        patient_letter(d).to_string()
    } else {
        axis_label(d).to_string()
    }
}

/// The axis name of a world direction (`+X` ... `-Z`) for data without patient axes.
pub fn axis_label(d: DVec3) -> &'static str {
    let a = d.abs();
    match (
        a.x >= a.y && a.x >= a.z,
        a.y >= a.z,
        d.max_element() >= -d.min_element(),
    ) {
        (true, _, true) => "+X",
        (true, _, false) => "-X",
        (false, true, true) => "+Y",
        (false, true, false) => "-Y",
        (false, false, true) => "+Z",
        (false, false, false) => "-Z",
    }
}

/// A slice image: 8-bit RGBA rows, top first.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceImage {
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// RGBA bytes.
    pub rgba: Vec<u8>,
    /// World size of the image (for its aspect on screen).
    pub world_size: [f64; 2],
}

impl SliceVolume {
    /// Slices of a grid.
    pub fn of_grid(grid: Arc<Grid>) -> Self {
        Self {
            dims: grid.dims(),
            origin: grid.origin(),
            spacing: grid.spacing(),
            direction: grid.direction(),
            values: Values::Grid(grid),
        }
    }

    /// Slices of a mesh, resampled onto a grid of [`MESH_SLICE_SAMPLES`] along its longest
    /// side.
    pub fn of_mesh(mesh: &TetMesh) -> Result<Self, volux_core::Error> {
        let r = resample_mesh(mesh, MESH_SLICE_SAMPLES)?;
        Ok(Self {
            dims: r.place.dims,
            origin: r.place.origin,
            spacing: r.place.spacing,
            direction: r.place.direction,
            values: Values::Resampled(Arc::new(r.values)),
        })
    }

    /// Samples per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The value at an index (NaN outside a resampled mesh).
    pub fn value(&self, idx: [usize; 3]) -> f32 {
        match &self.values {
            Values::Grid(g) => g.value(idx[0], idx[1], idx[2]),
            Values::Resampled(v) => v[idx[0] + self.dims[0] * (idx[1] + self.dims[1] * idx[2])],
        }
    }

    /// How `plane` is cut: the index axes nearest to its right and top directions.
    fn layout(&self, plane: Plane) -> Layout {
        let (right, top) = plane.screen();
        let col = |a: usize| self.direction.col(a);
        let nearest = |d: DVec3, skip: Option<usize>| {
            (0..3)
                .filter(|a| Some(*a) != skip)
                .max_by(|a, b| col(*a).dot(d).abs().total_cmp(&col(*b).dot(d).abs()))
                .expect("three axes")
        };
        let across = nearest(right, None);
        let down = nearest(top, Some(across));
        Layout {
            fixed: 3 - across - down,
            across,
            across_reversed: col(across).dot(right) < 0.0,
            down,
            upward: col(down).dot(top) > 0.0,
        }
    }

    /// The sample nearest to a world point, clamped into the grid.
    pub fn index_of(&self, p: DVec3) -> [usize; 3] {
        let t = self.direction.transpose() * (p - self.origin) / self.spacing;
        [0, 1, 2].map(|a| (t[a].round().max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// The world position of a sample.
    pub fn world_of(&self, idx: [usize; 3]) -> DVec3 {
        let local = self.spacing * DVec3::new(idx[0] as f64, idx[1] as f64, idx[2] as f64);
        self.origin + self.direction * local
    }

    /// The centre sample's position (the first crosshair).
    pub fn centre(&self) -> DVec3 {
        self.world_of(self.dims.map(|d| d / 2))
    }

    /// The world width and height of a slice of `plane`.
    pub fn world_size(&self, plane: Plane) -> [f64; 2] {
        let Layout { across, down, .. } = self.layout(plane);
        [
            self.spacing[across] * self.dims[across] as f64,
            self.spacing[down] * self.dims[down] as f64,
        ]
    }

    /// The plane through `crosshair`, grey from `window[0]` (black) to `window[1]` (white).
    pub fn slice(&self, plane: Plane, crosshair: DVec3, window: [f64; 2]) -> SliceImage {
        let l = self.layout(plane);
        let at = self.index_of(crosshair);
        let (w, h) = (self.dims[l.across], self.dims[l.down]);
        let mut rgba = Vec::with_capacity(w * h * 4);
        let width = (window[1] - window[0]).max(1e-300);
        for row in 0..h {
            for col in 0..w {
                let mut idx = at;
                idx[l.across] = l.column(col, w);
                idx[l.down] = l.row(row, h);
                let v = self.value(idx);
                if v.is_nan() {
                    rgba.extend([10, 14, 40, 255]);
                } else {
                    let g = (((v as f64 - window[0]) / width).clamp(0.0, 1.0) * 255.0).round();
                    rgba.extend([g as u8, g as u8, g as u8, 255]);
                }
            }
        }
        SliceImage {
            width: w,
            height: h,
            rgba,
            world_size: self.world_size(plane),
        }
    }

    /// The crosshair moved to the point at fraction (`u`, `v`) across and down a slice of
    /// `plane` (the fixed coordinate stays).
    pub fn pick(&self, plane: Plane, crosshair: DVec3, u: f64, v: f64) -> DVec3 {
        let l = self.layout(plane);
        let mut idx = self.index_of(crosshair);
        let cell = |f: f64, n: usize| ((f.clamp(0.0, 1.0) * n as f64) as usize).min(n - 1);
        let (w, h) = (self.dims[l.across], self.dims[l.down]);
        idx[l.across] = l.column(cell(u, w), w);
        idx[l.down] = l.row(cell(v, h), h);
        self.world_of(idx)
    }

    /// Where the crosshair sits in a slice of `plane`, as fractions across and down (the
    /// centre of its sample).
    pub fn crosshair_fraction(&self, plane: Plane, crosshair: DVec3) -> (f64, f64) {
        let l = self.layout(plane);
        let idx = self.index_of(crosshair);
        let (w, h) = (self.dims[l.across], self.dims[l.down]);
        let (c, r) = (l.column(idx[l.across], w), l.row(idx[l.down], h));
        ((c as f64 + 0.5) / w as f64, (r as f64 + 0.5) / h as f64)
    }

    /// The world directions the right and top edges of a slice of `plane` face (through
    /// the direction cosines).
    pub fn edge_directions(&self, plane: Plane) -> (DVec3, DVec3) {
        let l = self.layout(plane);
        let axis = |a: usize, towards: bool| {
            let d = self.direction.col(a);
            if towards {
                d
            } else {
                -d
            }
        };
        (axis(l.across, !l.across_reversed), axis(l.down, l.upward))
    }

    /// The patient sides (LPS letters) the right and top edges of a slice of `plane` face.
    pub fn edge_letters(&self, plane: Plane) -> (char, char) {
        let (right, top) = self.edge_directions(plane);
        (patient_letter(right), patient_letter(top))
    }

    /// The four world corners of a slice of `plane` through `crosshair` (for outlines in
    /// the 3D view).
    pub fn plane_corners(&self, plane: Plane, crosshair: DVec3) -> [DVec3; 4] {
        let l = self.layout(plane);
        let at = self.index_of(crosshair);
        let corner = |a: usize, d: usize| {
            let mut idx = at;
            idx[l.across] = a;
            idx[l.down] = d;
            self.world_of(idx)
        };
        let (na, nd) = (self.dims[l.across] - 1, self.dims[l.down] - 1);
        [corner(0, 0), corner(na, 0), corner(na, nd), corner(0, nd)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::grid::Samples;

    fn ramp() -> SliceVolume {
        // value = i + 10 j + 100 k on a 4 x 3 x 2 grid
        let v: Vec<f32> = (0..24)
            .map(|n| (n % 4 + 10 * ((n / 4) % 3) + 100 * (n / 12)) as f32)
            .collect();
        let g = Grid::new(
            [4, 3, 2],
            [1.0; 3],
            [0.0; 3],
            Samples::F32(volux_core::grid::Buffer::owned(v)),
        )
        .unwrap();
        SliceVolume::of_grid(Arc::new(g))
    }

    /// Each plane holds its fixed index and lays the others out as documented.
    #[test]
    fn planes_cut_where_the_crosshair_is() {
        let s = ramp();
        let c = s.world_of([2, 1, 1]);
        let ax = s.slice(Plane::Axial, c, [0.0, 255.0]);
        assert_eq!((ax.width, ax.height), (4, 3));
        // top-left of the axial slice: i = 0, j = 0, k = 1 -> 100
        assert_eq!(ax.rgba[0], 100);
        let sag = s.slice(Plane::Sagittal, c, [0.0, 255.0]);
        assert_eq!((sag.width, sag.height), (3, 2));
        // top-left of the sagittal slice: i = 2, j = 0, k = 1 (upward) -> 102
        assert_eq!(sag.rgba[0], 102);
        let p = s.pick(Plane::Coronal, c, 0.99, 0.99);
        assert_eq!(s.index_of(p), [3, 1, 0]);
    }

    /// LPS letters: +x left, -y anterior, +z superior.
    #[test]
    fn letters_follow_lps() {
        assert_eq!(patient_letter(DVec3::X), 'L');
        assert_eq!(patient_letter(-DVec3::Y), 'A');
        assert_eq!(patient_letter(DVec3::new(0.1, 0.2, -0.9)), 'I');
        assert_eq!(ramp().edge_letters(Plane::Axial), ('L', 'A'));
        assert_eq!(ramp().edge_letters(Plane::Coronal), ('L', 'S'));
        assert_eq!(axis_label(-DVec3::Z), "-Z");
    }

    /// A scan stored sagittally (index axes P, I, R: the direction matrix "PIR") shows the
    /// same slices, letters and crosshair as the axial storage of the same object.
    #[test]
    fn world_planes_whatever_the_storage() {
        let (n, axial) = (
            [4usize, 3, 2],
            (0..24).map(|v| v as f32).collect::<Vec<f32>>(),
        );
        // Axial storage: index (i, j, k) at world (i, j, k), value axial[i + 4 j + 12 k].
        // Sagittal storage: index (a, b, c) with a along +y, b along -z, c along -x.
        let dims_s = [n[1], n[2], n[0]];
        let mut sag = vec![0f32; 24];
        for (c, i) in (0..n[0]).rev().enumerate() {
            for (b, k) in (0..n[2]).rev().enumerate() {
                for j in 0..n[1] {
                    sag[j + dims_s[0] * (b + dims_s[1] * c)] = axial[i + 4 * j + 12 * k];
                }
            }
        }
        let grid = |dims: [usize; 3], v: Vec<f32>, origin: [f64; 3]| {
            Grid::new(
                dims,
                [1.0; 3],
                origin,
                Samples::F32(volux_core::grid::Buffer::owned(v)),
            )
            .unwrap()
        };
        let a = SliceVolume::of_grid(Arc::new(grid(n, axial, [0.0; 3])));
        let pir = DMat3::from_cols(DVec3::Y, -DVec3::Z, -DVec3::X);
        let s = grid(dims_s, sag, [3.0, 0.0, 1.0])
            .with_direction(pir)
            .unwrap();
        let s = SliceVolume::of_grid(Arc::new(s));
        let c = DVec3::new(1.0, 2.0, 1.0);
        for plane in Plane::ALL {
            assert_eq!(
                a.slice(plane, c, [0.0, 255.0]),
                s.slice(plane, c, [0.0, 255.0]),
                "{plane:?}"
            );
            assert_eq!(a.edge_letters(plane), s.edge_letters(plane), "{plane:?}");
            assert_eq!(
                a.crosshair_fraction(plane, c),
                s.crosshair_fraction(plane, c)
            );
            let p = s.pick(plane, c, 0.9, 0.1);
            assert!(
                (p - a.pick(plane, c, 0.9, 0.1)).length() < 1e-9,
                "{plane:?}"
            );
        }
        assert_eq!(s.edge_letters(Plane::Sagittal), ('P', 'S'));
    }
}
