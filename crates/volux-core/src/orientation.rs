//! Patient orientation of grids: direction matrices and their anatomical names.
//!
//! **World convention: LPS millimetres**, as DICOM (PS3.3 C.7.6.2.1.1, the patient coordinate
//! system) and ITK: +x points to the patient's **L**eft, +y to **P**osterior, +z to
//! **S**uperior. A grid's *direction matrix* `D` has as columns the unit world directions of
//! its index axes i, j, k (ITK's `Direction`, DICOM's ImageOrientationPatient row and column
//! cosines plus the slice normal), so sample (i, j, k) lies at
//! `origin + D * (spacing ∘ (i, j, k))`. NIfTI and 3D Slicer use RAS (+x Right, +y Anterior):
//! a RAS point or direction becomes LPS by negating x and y ([`ras_to_lps`]).
//!
//! An *orientation code* names, for each index axis, the direction it points **towards**
//! (the letter of the column of `D`), as nibabel's `aff2axcodes` and DICOM's patient
//! orientation labels do: an identity matrix is "LPS", a NIfTI-style RAS+ grid is "RAS".
//! (ITK's `SpatialOrientation` enum names the opposite, "from", letters: ITK's `RAI` is
//! "LPS" here.)
use glam::{DMat3, DVec3};

use crate::error::{Error, Result};

/// How far from unit length a column of a direction matrix may be before it is refused (it is
/// normalized when within).
pub const UNIT_TOLERANCE: f64 = 1e-3;

/// The largest |cosine| between two columns of a direction matrix that is still taken as
/// orthogonal.
pub const ORTHOGONAL_TOLERANCE: f64 = 1e-3;

/// Checks a direction matrix (columns = world directions of the index axes) and returns it with
/// unit columns: every entry finite, each column of length 1 within [`UNIT_TOLERANCE`], and
/// each pair of columns orthogonal within [`ORTHOGONAL_TOLERANCE`]; otherwise
/// [`Error::InvalidGeometry`] naming the column(s) and the figure. Reflections (determinant
/// -1, e.g. radiological NIfTI storage) are accepted.
pub fn validate_direction(d: DMat3) -> Result<DMat3> {
    let cols = [d.x_axis, d.y_axis, d.z_axis];
    let names = ["i", "j", "k"];
    let mut unit = [DVec3::ZERO; 3];
    for (a, c) in cols.iter().enumerate() {
        if !c.is_finite() {
            return Err(Error::InvalidGeometry(format!(
                "direction of axis {} is {c}, not finite",
                names[a]
            )));
        }
        let len = c.length();
        if (len - 1.0).abs() > UNIT_TOLERANCE {
            return Err(Error::InvalidGeometry(format!(
                "direction of axis {} ({c}) has length {len:.6}, not 1 within {UNIT_TOLERANCE}",
                names[a]
            )));
        }
        unit[a] = *c / len;
    }
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        let cos = unit[a].dot(unit[b]);
        if cos.abs() > ORTHOGONAL_TOLERANCE {
            return Err(Error::InvalidGeometry(format!(
                "directions of axes {} and {} are not orthogonal (cosine {cos:.6}, more than \
                 {ORTHOGONAL_TOLERANCE}): sheared grids are not supported",
                names[a], names[b]
            )));
        }
    }
    Ok(DMat3::from_cols(unit[0], unit[1], unit[2]))
}

/// The LPS patient letter a world direction points towards: its largest component picks the
/// axis, its sign the letter (+x `L`, -x `R`, +y `P`, -y `A`, +z `S`, -z `I`); `None` for a
/// zero or non-finite vector. For an oblique direction this is the nearest anatomical axis
/// (ties go to x, then y).
pub fn patient_letter(v: DVec3) -> Option<char> {
    if !v.is_finite() || v == DVec3::ZERO {
        return None;
    }
    let a = v.abs();
    let (axis, value) = if a.x >= a.y && a.x >= a.z {
        (0, v.x)
    } else if a.y >= a.z {
        (1, v.y)
    } else {
        (2, v.z)
    };
    let letters = [('L', 'R'), ('P', 'A'), ('S', 'I')];
    Some(if value > 0.0 {
        letters[axis].0
    } else {
        letters[axis].1
    })
}

/// The orientation code of a direction matrix: for each index axis i, j, k, the letter it
/// points towards ([`patient_letter`] of the column), e.g. "LPS" for the identity, "RAS" for
/// NIfTI's RAS+ storage, "PSL" for a sagittal stack. A degenerate column gives '?'.
pub fn orientation_code(d: &DMat3) -> String {
    [d.x_axis, d.y_axis, d.z_axis]
        .iter()
        .map(|c| patient_letter(*c).unwrap_or('?'))
        .collect()
}

/// A RAS vector (NIfTI, 3D Slicer) in LPS (DICOM, ITK, Volux): x and y negated. Its own
/// inverse.
pub fn ras_to_lps(v: DVec3) -> DVec3 {
    DVec3::new(-v.x, -v.y, v.z)
}

/// The direction matrix of a 3x3 matrix whose columns are axis vectors with their lengths
/// (NIfTI sform columns, NRRD `space directions`, an ITK `TransformMatrix` scaled by spacing):
/// the column lengths (the spacings) and the unit directions. Errors when a column is zero,
/// not finite, or the directions are not orthogonal (see [`validate_direction`]).
pub fn split_scaled_axes(m: DMat3) -> Result<([f64; 3], DMat3)> {
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let spacing = cols.map(|c| c.length());
    if let Some(a) = (0..3).find(|&a| !(spacing[a].is_finite() && spacing[a] > 0.0)) {
        return Err(Error::InvalidGeometry(format!(
            "axis {} vector {} has no usable length",
            ["i", "j", "k"][a],
            cols[a]
        )));
    }
    let unit = DMat3::from_cols(
        cols[0] / spacing[0],
        cols[1] / spacing[1],
        cols[2] / spacing[2],
    );
    Ok((spacing, validate_direction(unit)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn letters_follow_lps() {
        let cases = [
            (DVec3::X, 'L'),
            (-DVec3::X, 'R'),
            (DVec3::Y, 'P'),
            (-DVec3::Y, 'A'),
            (DVec3::Z, 'S'),
            (-DVec3::Z, 'I'),
            (DVec3::new(0.3, -0.9, 0.1), 'A'),
        ];
        for (v, c) in cases {
            assert_eq!(patient_letter(v), Some(c), "{v}");
        }
        assert_eq!(patient_letter(DVec3::ZERO), None);
        assert_eq!(patient_letter(DVec3::new(f64::NAN, 0.0, 0.0)), None);
    }

    #[test]
    fn codes_of_common_matrices() {
        assert_eq!(orientation_code(&DMat3::IDENTITY), "LPS");
        let ras = DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0));
        assert_eq!(orientation_code(&ras), "RAS");
        let sagittal = DMat3::from_cols(DVec3::Y, -DVec3::Z, DVec3::X);
        assert_eq!(orientation_code(&sagittal), "PIL");
    }

    #[test]
    fn non_orthogonal_and_non_unit_are_refused() {
        let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.1, 1.0, 0.0).normalize(), DVec3::Z);
        let e = validate_direction(shear).unwrap_err().to_string();
        assert!(e.contains("axes i and j are not orthogonal"), "{e}");
        let long = DMat3::from_cols(DVec3::X * 2.0, DVec3::Y, DVec3::Z);
        let e = validate_direction(long).unwrap_err().to_string();
        assert!(e.contains("axis i") && e.contains("length 2"), "{e}");
        let nan = DMat3::from_cols(DVec3::X, DVec3::Y, DVec3::new(0.0, f64::NAN, 1.0));
        assert!(validate_direction(nan).is_err());
    }

    #[test]
    fn nearly_unit_columns_are_normalized() {
        let d = DMat3::from_cols(DVec3::X * 1.0005, DVec3::Y, -DVec3::Z);
        let v = validate_direction(d).unwrap();
        assert!((v.x_axis.length() - 1.0).abs() < 1e-15);
        assert!(v.determinant() < 0.0, "reflections are kept");
    }

    #[test]
    fn scaled_axes_split_into_spacing_and_direction() {
        let m = DMat3::from_cols(
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.0, 0.0, -3.0),
            DVec3::X,
        );
        let (s, d) = split_scaled_axes(m).unwrap();
        assert_eq!(s, [2.0, 3.0, 1.0]);
        assert_eq!(d, DMat3::from_cols(DVec3::Y, -DVec3::Z, DVec3::X));
        let zero = DMat3::from_cols(DVec3::ZERO, DVec3::Y, DVec3::Z);
        assert!(split_scaled_axes(zero).is_err());
    }
}
