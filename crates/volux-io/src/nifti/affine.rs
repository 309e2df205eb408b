//! The NIfTI voxel-to-world affine (`nifti1.h`, the same in `nifti2.h`, "3D IMAGE (VOLUME) ORIENTATION AND
//! LOCATION IN SPACE"), turned into Volux's LPS placement: spacing, origin and direction.
//!
//! Method 3 (`sform_code > 0`): the `srow_x/y/z` matrix; its column lengths are the spacing
//! and its unit columns the directions. Method 2 (`qform_code > 0`): the quaternion
//! `quatern_b/c/d` (with `a = sqrt(1 - b² - c² - d²)`), the third column times `qfac`
//! (`pixdim[0]`, -1 or 1), spacing from `pixdim`, origin `qoffset`. Otherwise (method 1) the
//! grid is axis-aligned at the origin. NIfTI world coordinates are RAS; x and y are negated
//! to give LPS ([`volux_core::orientation::ras_to_lps`]).
//!
//! Analyze 7.5 has no orientation field: [`analyze_placement`] places it as SPM and nibabel's
//! `Spm99AnalyzeHeader.get_origin_affine` do (nibabel reads every Analyze pair as SPM2's):
//! x flipped (the radiological storage Analyze files were written in), spacing `pixdim`,
//! and the origin at SPM's `originator` voxel (1-based) when it lies within the image's
//! reach, else at the image's centre.
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

/// The placement nibabel gives an Analyze 7.5 image (`Spm99AnalyzeHeader.get_origin_affine`):
/// the RAS affine `diag(-sx, sy, sz)` (x flipped; `sx..sz` are `pixdim[1..=3]` with their
/// signs, zero or non-finite ones 1 as `spacing` says), translated so that the origin voxel
/// `o` lies at 0: `o` is SPM's `originator` minus 1 when one of its three first values is
/// non-zero and each lies strictly between `-dim` and `2 dim`, else `(dim - 1) / 2`. A note
/// says which.
pub(super) fn analyze_placement(
    hdr: &Header,
    spacing: [f64; 3],
    notes: &mut Vec<String>,
) -> Placement {
    let sign = |p: f64| if p < 0.0 { -1.0 } else { 1.0 };
    let mut zooms: [f64; 3] = std::array::from_fn(|i| spacing[i] * sign(hdr.pixdim[i]));
    zooms[0] = -zooms[0];
    let dims = hdr.dims.map(|d| d as f64);
    let orig = [0, 1, 2].map(|i| f64::from(hdr.originator[i]));
    let spm = orig.iter().any(|&o| o != 0.0)
        && (0..3).all(|i| orig[i] > -dims[i] && orig[i] < 2.0 * dims[i]);
    let (voxel, where_) = if spm {
        (
            orig.map(|o| o - 1.0),
            format!(
                "origin at SPM's originator voxel ({}, {}, {})",
                orig[0], orig[1], orig[2]
            ),
        )
    } else {
        (
            dims.map(|d| (d - 1.0) / 2.0),
            "origin at the image's centre (no SPM originator)".to_string(),
        )
    };
    notes.push(format!(
        "Analyze 7.5 has no orientation: placed as SPM and nibabel do, x flipped \
         (radiological storage, right to left), {where_}"
    ));
    let cols = [0, 1, 2].map(|i| {
        let mut c = DVec3::ZERO;
        c[i] = zooms[i];
        ras_to_lps(c)
    });
    let origin = ras_to_lps(DVec3::from(std::array::from_fn::<f64, 3, _>(|i| {
        -voxel[i] * zooms[i]
    })));
    match split_scaled_axes(DMat3::from_cols(cols[0], cols[1], cols[2])) {
        Ok((spacing, direction)) => Placement {
            spacing,
            origin: origin.to_array(),
            direction,
        },
        Err(_) => Placement {
            spacing,
            origin: [0.0; 3],
            direction: DMat3::IDENTITY,
        },
    }
}
