//! Which 3-D volume of a 4-D or 5-D NIfTI file is read (`nifti1.h`, "DATA DIMENSIONALITY":
//! `dim[4]` is time, or another list of volumes when the intent says so, and `dim[5]` holds the
//! several values per voxel of an intent such as `NIFTI_INTENT_VECTOR`), and what the axes
//! along which it was chosen mean (`xyzt_units`, `pixdim[4]`, `intent_code`, and an FSL
//! `.bval` file beside the image for diffusion series).
use std::path::Path;

use volux_core::volume_axes::{choose, AxisKind, ExtraAxis};

use super::header::{show, Header};
use crate::dataset::VolumeChoice;
use crate::error::{ErrorKind, ReadError, Result};

/// The largest `.bval` file read (a few numbers per volume).
const MAX_BVAL_BYTES: u64 = 1 << 20;

/// The volume chosen: its place among the file's volumes, and the axes it was chosen along.
#[derive(Debug)]
pub(super) struct Pick {
    /// The volume's index in the file: `component * dim[4] + timepoint` (`dim[4]` varies
    /// fastest after x, y, z).
    pub index: u64,
    /// How many 3-D volumes the file holds (`dim[4] * dim[5]`).
    pub count: u64,
    /// The axes beyond x, y, z, with what was chosen along each.
    pub axes: Vec<ExtraAxis>,
    /// For colour voxels: the one channel asked for (`None`: the colour).
    pub channel: Option<usize>,
}

/// Chooses the volume of `choice` in the file `hdr` describes; `path` names the file for
/// errors and locates an FSL `.bval` beside it.
pub(super) fn pick(
    path: &Path,
    hdr: &Header,
    choice: VolumeChoice,
    notes: &mut Vec<String>,
) -> Result<Pick> {
    let err = |e| ReadError::new(path, e);
    let nt = usize::try_from(hdr.volumes).map_err(|_| too_many(path, "dim[4]"))?;
    let nc = usize::try_from(hdr.components).map_err(|_| too_many(path, "dim[5]"))?;
    let mut axes = Vec::new();
    let t = if nt > 1 {
        let t = choose("timepoint", choice.timepoint, nt).map_err(err)?;
        axes.push(volume_axis(path, hdr, nt, t, notes));
        t
    } else {
        0
    };
    let (c, channel) = match (hdr.dtype.channels(), nc > 1) {
        (Some(_), true) => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!(
                    "{} voxels with {nc} components along dim[5]",
                    hdr.dtype.name()
                )),
            ))
        }
        (Some(k), false) => match choice.component {
            Some(c) => {
                let c = choose("component", c, k).map_err(err)?;
                axes.push(ExtraAxis::new(AxisKind::Color, k, Some(c)));
                (0, Some(c))
            }
            None => (0, None),
        },
        (None, true) => {
            let c = choose("component", choice.component.unwrap_or(0), nc).map_err(err)?;
            let axis = ExtraAxis::new(AxisKind::Component, nc, Some(c));
            axes.push(match intent_name(hdr.intent_code) {
                Some(name) => axis.with_meaning(format!("intent {name}")),
                None => axis,
            });
            (c, None)
        }
        (None, false) => (0, None),
    };
    Ok(Pick {
        index: (c as u64) * (nt as u64) + t as u64,
        count: (nt as u64) * (nc as u64),
        axes,
        channel,
    })
}

fn too_many(path: &Path, what: &str) -> ReadError {
    crate::util::header_err(path, format!("{what} is too large"))
}

/// The axis along `dim[4]`: b-values from an FSL `.bval` beside the image (a diffusion
/// series), else time when the intent is none or a time series (or describes `dim[5]`) and
/// the units do not say otherwise (step `pixdim[4]` in the time unit of `xyzt_units`), else a
/// list of volumes (a statistic or label intent: a list of maps; a spectral unit).
fn volume_axis(
    path: &Path,
    hdr: &Header,
    len: usize,
    chosen: usize,
    notes: &mut Vec<String>,
) -> ExtraAxis {
    if let Some(b) = bvals(path, len, notes) {
        return ExtraAxis::new(AxisKind::Volume, len, Some(chosen))
            .with_values(b, "b-value (s/mm²) from the .bval file");
    }
    let step = hdr.step;
    let unit = time_unit(hdr.xyzt_units);
    let stepped = |u: &str| {
        if step.is_finite() && step > 0.0 {
            format!("step {} {u}", show(step))
        } else {
            String::new()
        }
    };
    // With dim[5] > 1 the intent describes the components there, not dim[4].
    let timed = matches!(hdr.intent_code, 0 | 2001) || hdr.components > 1;
    match (timed, unit) {
        (false, _) => {
            let axis = ExtraAxis::new(AxisKind::Volume, len, Some(chosen));
            match intent_name(hdr.intent_code) {
                Some(name) => axis.with_meaning(format!("intent {name}")),
                None => axis,
            }
        }
        (true, Some((u, true))) => {
            ExtraAxis::new(AxisKind::Time, len, Some(chosen)).with_meaning(stepped(u))
        }
        (true, Some((u, false))) => {
            ExtraAxis::new(AxisKind::Volume, len, Some(chosen)).with_meaning(stepped(u))
        }
        (true, None) if step.is_finite() && step > 0.0 => {
            ExtraAxis::new(AxisKind::Time, len, Some(chosen))
                .with_meaning(format!("step {} (no unit given)", show(step)))
        }
        (true, None) => ExtraAxis::new(AxisKind::Volume, len, Some(chosen)),
    }
}

/// The unit of `dim[4]` in `xyzt_units` (bits 3 to 5), and whether it is a time (the others are
/// spectral: Hz, ppm, rad/s).
fn time_unit(xyzt_units: i32) -> Option<(&'static str, bool)> {
    Some(match xyzt_units & 0x38 {
        8 => ("s", true),
        16 => ("ms", true),
        24 => ("µs", true),
        32 => ("Hz", false),
        40 => ("ppm", false),
        48 => ("rad/s", false),
        _ => return None,
    })
}

/// The `nifti1.h` name of an intent code (`None` for 0 and unknown codes).
fn intent_name(code: i32) -> Option<&'static str> {
    Some(match code {
        2..=24 => "statistic",
        1001 => "estimate",
        1002 => "label",
        1003 => "neuroname",
        1004 => "general matrix",
        1005 => "symmetric matrix",
        1006 => "displacement vector",
        1007 => "vector",
        1008 => "point set",
        1009 => "triangle",
        1010 => "quaternion",
        1011 => "dimensionless",
        2001 => "time series",
        2002 => "node index",
        2003 => "RGB vector",
        2004 => "RGBA vector",
        2005 => "shape",
        _ => return None,
    })
}

/// The b-values of an FSL `.bval` file beside the image (`x.bval` for `x.nii.gz`), when it
/// holds one number per volume; a file that does not is noted and not used.
fn bvals(path: &Path, len: usize, notes: &mut Vec<String>) -> Option<Vec<f64>> {
    let name = path.file_name()?.to_string_lossy().into_owned();
    let lower = name.to_ascii_lowercase();
    let stem_len = [".nii.gz", ".nii", ".hdr", ".img"]
        .iter()
        .find(|s| lower.ends_with(*s))
        .map(|s| name.len() - s.len())?;
    let bval = path.with_file_name(format!("{}.bval", name.get(..stem_len)?));
    if !bval.is_file() {
        return None;
    }
    let shown = bval.file_name()?.to_string_lossy().into_owned();
    let text = match crate::util::read_regular(&bval, MAX_BVAL_BYTES) {
        Ok(t) => t,
        Err(e) => {
            notes.push(format!("{shown} beside the image was not read: {e}"));
            return None;
        }
    };
    let values: Option<Vec<f64>> = String::from_utf8_lossy(&text)
        .split_whitespace()
        .map(|v| v.parse().ok().filter(|x: &f64| x.is_finite()))
        .collect();
    match values {
        Some(v) if v.len() == len => Some(v),
        Some(v) => {
            notes.push(format!(
                "{shown} holds {} values for {len} volumes; it was not used",
                v.len()
            ));
            None
        }
        None => {
            notes.push(format!(
                "{shown} holds something else than numbers; it was not used"
            ));
            None
        }
    }
}
