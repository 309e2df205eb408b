//! The NIfTI voxel-to-world affine (`nifti1.h`, the same in `nifti2.h`, "3D IMAGE (VOLUME) ORIENTATION AND
//! LOCATION IN SPACE"), turned into Volux's LPS placement: spacing, origin and direction.
//!
//! Method 3 (`sform_code > 0`): the `srow_x/y/z` matrix; its column lengths are the spacing
//! and its unit columns the directions. Method 2 (`qform_code > 0`): the quaternion
//! `quatern_b/c/d` (with `a = sqrt(1 - b² - c² - d²)`), the third column times `qfac`
//! (`pixdim[0]`, -1 or 1), spacing from `pixdim`, origin `qoffset`. Otherwise (method 1) the
//! grid is axis-aligned at the origin. NIfTI world coordinates are RAS; x and y are negated
//! to give LPS ([`volux_core::orientation::ras_to_lps`]).
use glam::{DMat3, DVec3};
use volux_core::orientation::{ras_to_lps, split_scaled_axes, validate_direction};

use super::header::Header;

/// Where the grid lies in LPS world coordinates.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placement {
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
    pub direction: DMat3,
}

/// The placement of `hdr`: the sform when `sform_code > 0` and usable, else the qform when
/// `qform_code > 0` and usable, else axis-aligned at 0; `spacing` is the spacing from
/// `pixdim`. An unusable sform or qform (non-finite, zero or sheared axes) is noted.
pub(super) fn placement(hdr: &Header, spacing: [f64; 3], notes: &mut Vec<String>) -> Placement {
    let plain = Placement {
        spacing,
        origin: [0.0; 3],
        direction: DMat3::IDENTITY,
    };
    if hdr.sform_code > 0 {
        match sform(hdr) {
            Ok(p) => return p,
            Err(why) => notes.push(format!("the sform is not usable ({why}); {}", next(hdr))),
        }
    }
    if hdr.qform_code > 0 {
        match qform(hdr, spacing) {
            Ok(p) => return p,
            Err(why) => notes.push(format!(
                "the qform is not usable ({why}); the grid was placed axis-aligned at (0, 0, 0)"
            )),
        }
    }
    plain
}

/// What is used when the sform is not.
fn next(hdr: &Header) -> &'static str {
    if hdr.qform_code > 0 {
        "the qform was used"
    } else {
        "the grid was placed axis-aligned at (0, 0, 0)"
    }
}

/// Method 3: the sform rows, RAS to LPS.
fn sform(hdr: &Header) -> Result<Placement, String> {
    let r = hdr.srow;
    let col = |j: usize| ras_to_lps(DVec3::new(r[0][j], r[1][j], r[2][j]));
    let (spacing, direction) =
        split_scaled_axes(DMat3::from_cols(col(0), col(1), col(2))).map_err(|e| e.to_string())?;
    let origin = ras_to_lps(DVec3::new(r[0][3], r[1][3], r[2][3]));
    if !origin.is_finite() {
        return Err(format!("its translation {origin} is not finite"));
    }
    Ok(Placement {
        spacing,
        origin: origin.to_array(),
        direction,
    })
}

/// Method 2: the quaternion rotation with `qfac`, RAS to LPS.
fn qform(hdr: &Header, spacing: [f64; 3]) -> Result<Placement, String> {
    let r = quaternion_matrix(hdr.quatern)?;
    let qfac = if hdr.qfac < 0.0 { -1.0 } else { 1.0 };
    let ras = DMat3::from_cols(r.x_axis, r.y_axis, r.z_axis * qfac);
    let lps = DMat3::from_cols(
        ras_to_lps(ras.x_axis),
        ras_to_lps(ras.y_axis),
        ras_to_lps(ras.z_axis),
    );
    let direction = validate_direction(lps).map_err(|e| e.to_string())?;
    let origin = ras_to_lps(DVec3::from(hdr.qoffset));
    if !origin.is_finite() {
        return Err(format!("its offset {origin} is not finite"));
    }
    Ok(Placement {
        spacing,
        origin: origin.to_array(),
        direction,
    })
}

/// The rotation of the unit quaternion (a, b, c, d) with `a = sqrt(1 - b² - c² - d²)`, as
/// `nifti1_io.c`'s `quatern_to_mat44` (a 180° turn, `a = 0`, when b² + c² + d² reaches 1).
fn quaternion_matrix([b, c, d]: [f64; 3]) -> Result<DMat3, String> {
    if !(b.is_finite() && c.is_finite() && d.is_finite()) {
        return Err(format!("quaternion ({b}, {c}, {d}) is not finite"));
    }
    let a2 = 1.0 - (b * b + c * c + d * d);
    let (a, b, c, d) = if a2 < 1e-7 {
        let n = (b * b + c * c + d * d).sqrt();
        (0.0, b / n, c / n, d / n)
    } else {
        (a2.sqrt(), b, c, d)
    };
    Ok(DMat3::from_cols(
        DVec3::new(
            a * a + b * b - c * c - d * d,
            2.0 * (b * c + a * d),
            2.0 * (b * d - a * c),
        ),
        DVec3::new(
            2.0 * (b * c - a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d + a * b),
        ),
        DVec3::new(
            2.0 * (b * d + a * c),
            2.0 * (c * d - a * b),
            a * a + d * d - c * c - b * b,
        ),
    ))
}
