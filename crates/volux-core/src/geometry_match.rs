//! Whether two grids sample the same points: a mask, a label map or a second channel drawn
//! over a volume must lie on the volume's own lattice, or it would be applied by voxel index
//! to the wrong place.
use glam::{DMat3, DVec3};

use crate::error::{Error, Result};
use crate::grid::Grid;

/// Relative tolerance on spacing (files round to 6-7 significant digits).
pub const SPACING_TOLERANCE: f64 = 1e-4;

/// Tolerance on the origin, as a fraction of the smallest spacing.
pub const ORIGIN_TOLERANCE: f64 = 1e-3;

/// Tolerance on each entry of the direction matrix.
pub const DIRECTION_TOLERANCE: f64 = 1e-4;

/// Checks that `other` (a mask, labels) has `grid`'s geometry: dims, spacing, origin,
/// direction and unit, within the tolerances above. Otherwise
/// [`Error::GeometryMismatch`] names the first property that differs and both values.
pub fn check_same_geometry(grid: &Grid, other: &Grid) -> Result<()> {
    let mismatch = |what: &'static str, a: String, b: String| {
        Err(Error::GeometryMismatch {
            what,
            grid: a,
            other: b,
        })
    };
    let dims = |d: [usize; 3]| format!("{}x{}x{}", d[0], d[1], d[2]);
    if grid.dims() != other.dims() {
        return mismatch("dims", dims(grid.dims()), dims(other.dims()));
    }
    if grid.unit() != other.unit() {
        return mismatch("unit", grid.unit().into(), other.unit().into());
    }
    let v = |p: DVec3| format!("[{}, {}, {}]", p.x, p.y, p.z);
    let (s, t) = (grid.spacing(), other.spacing());
    let rel = ((s - t).abs() / s.abs().max(t.abs())).max_element();
    if rel > SPACING_TOLERANCE {
        return mismatch("spacing", v(s), v(t));
    }
    let (o, p) = (grid.origin(), other.origin());
    if (o - p).abs().max_element() > ORIGIN_TOLERANCE * s.min_element() {
        return mismatch("origin", v(o), v(p));
    }
    let (d, e) = (grid.direction(), other.direction());
    if max_entry(d - e) > DIRECTION_TOLERANCE {
        let m = |m: DMat3| format!("[{}, {}, {}]", v(m.x_axis), v(m.y_axis), v(m.z_axis));
        return mismatch("direction", m(d), m(e));
    }
    Ok(())
}

fn max_entry(m: DMat3) -> f64 {
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Buffer, Samples};

    fn grid(dims: [usize; 3], spacing: [f64; 3], origin: [f64; 3]) -> Grid {
        let n = dims.iter().product();
        Grid::new(
            dims,
            spacing,
            origin,
            Samples::U8(Buffer::owned(vec![0; n])),
        )
        .unwrap()
    }

    /// Each property is checked and named; rounding in the file's digits passes.
    #[test]
    fn each_difference_is_named() {
        let g = grid([4, 5, 6], [0.5, 0.5, 2.0], [1.0, 2.0, 3.0]);
        let same = grid([4, 5, 6], [0.500001, 0.5, 2.0], [1.0, 2.0, 3.0000001]);
        check_same_geometry(&g, &same).unwrap();
        let cases = [
            (grid([4, 5, 7], [0.5, 0.5, 2.0], [1.0, 2.0, 3.0]), "dims"),
            (grid([4, 5, 6], [0.5, 0.5, 1.0], [1.0, 2.0, 3.0]), "spacing"),
            (grid([4, 5, 6], [0.5, 0.5, 2.0], [1.0, 2.0, 13.0]), "origin"),
            (
                grid([4, 5, 6], [0.5, 0.5, 2.0], [1.0, 2.0, 3.0])
                    .with_direction(DMat3::from_cols(-DVec3::X, -DVec3::Y, DVec3::Z))
                    .unwrap(),
                "direction",
            ),
            (
                grid([4, 5, 6], [0.5, 0.5, 2.0], [1.0, 2.0, 3.0]).with_unit("µm"),
                "unit",
            ),
        ];
        for (other, what) in cases {
            let e = check_same_geometry(&g, &other).unwrap_err();
            assert!(
                matches!(&e, Error::GeometryMismatch { what: w, .. } if *w == what),
                "{what}: {e}"
            );
        }
    }
}
