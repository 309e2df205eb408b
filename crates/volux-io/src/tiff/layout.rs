//! What the metadata of a TIFF file says about its volume: which pages (IFDs) hold the z
//! slices of the chosen channel and timepoint, the spacing and where it comes from, and the
//! unit conversions shared by the ImageJ, OME and plain-TIFF readers.
use std::path::Path;

use volux_core::volume_axes::ExtraAxis;

use crate::error::{ErrorKind, ReadError, Result};

/// The pages of the volume and its spacing, decided from the file's metadata.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The page (IFD index) of each z slice, in z order.
    pub ifds: Vec<usize>,
    /// Spacing along x, y, z (micrometres when the unit is known).
    pub spacing: [f64; 3],
    /// Where the spacing comes from, in words (a grid note).
    pub spacing_note: String,
    /// The metadata flavour: `ImageJ`, `OME`, `plain` or `folder`.
    pub flavour: &'static str,
    /// Further notes (channels and timepoints chosen, ...).
    pub notes: Vec<String>,
    /// The file's axes beyond x, y, z (channels, time) and the index read along each.
    pub axes: Vec<ExtraAxis>,
}

/// Micrometres per `unit` for the length units ImageJ and OME write (`micron`, `µm`, `um`,
/// `\u00B5m`, `nm`, `Å`, `mm`, `cm`, `m`, `inch`, ...); `None` for `pixel` and unknown units.
pub fn micrometres_per(unit: &str) -> Option<f64> {
    let u = unit.trim().to_ascii_lowercase();
    let u = u.replace("\\u00b5", "µ").replace('μ', "µ");
    Some(match u.as_str() {
        "micron" | "microns" | "µm" | "um" | "micrometer" | "micrometre" | "micrometers"
        | "micrometres" => 1.0,
        "nm" | "nanometer" | "nanometre" | "nanometers" | "nanometres" => 1e-3,
        "å" | "angstrom" | "ångström" => 1e-4,
        "pm" | "picometer" => 1e-6,
        "mm" | "millimeter" | "millimetre" | "millimeters" | "millimetres" => 1e3,
        "cm" | "centimeter" | "centimetre" | "centimeters" | "centimetres" => 1e4,
        "m" | "meter" | "metre" | "meters" | "metres" => 1e6,
        "inch" | "inches" | "in" => 25_400.0,
        _ => return None,
    })
}

/// Checks a spacing read from metadata: finite and positive, else a header error naming
/// `what`.
pub fn positive(path: &Path, what: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ReadError::new(
            path,
            ErrorKind::Header(format!("{what} is {v}; it must be a finite number > 0")),
        ))
    }
}

/// The index chosen among `count` channels or timepoints (`option` is `"channel"` or
/// `"timepoint"`), or [`volux_core::Error::NoSuchVolume`] naming how many there are.
pub fn choose(path: &Path, option: &'static str, index: usize, count: usize) -> Result<usize> {
    volux_core::volume_axes::choose(option, index, count).map_err(|e| ReadError::new(path, e))
}

/// Spacing from plain TIFF resolution tags (TIFF 6.0 section 8: `XResolution`,
/// `YResolution` in pixels per `ResolutionUnit`, 1 none, 2 inch (the default), 3 cm), in
/// micrometres for inch and cm; z, which plain TIFF does not store, is taken equal to x.
/// Without `XResolution`, or with a resolution of 1 and no unit: spacing 1.
pub fn plain_spacing(
    path: &Path,
    res: [Option<f64>; 2],
    unit: Option<f64>,
) -> Result<([f64; 3], String)> {
    let unit = unit.unwrap_or(2.0) as u16;
    let Some(xr) = res[0] else {
        return Ok((
            [1.0; 3],
            "no spacing information (no resolution tags): spacing 1".into(),
        ));
    };
    let xr = positive(path, "XResolution", xr)?;
    let yr = positive(path, "YResolution", res[1].unwrap_or(xr))?;
    if unit == 1 && xr == 1.0 && yr == 1.0 {
        return Ok((
            [1.0; 3],
            "no spacing information (resolution 1 without a unit): spacing 1".into(),
        ));
    }
    let (factor, words) = match unit {
        2 => (25_400.0, Some("inch")),
        3 => (10_000.0, Some("cm")),
        _ => (1.0, None),
    };
    let (x, y) = (factor / xr, factor / yr);
    let note = match words {
        Some(u) => format!(
            "spacing in micrometres, from the TIFF resolution tags (pixels per {u}); z taken \
             equal to x (plain TIFF has no z spacing)"
        ),
        None => "spacing from the TIFF resolution tags, without a unit; z taken equal to x \
                 (plain TIFF has no z spacing)"
            .to_string(),
    };
    Ok(([x, y, x], note))
}
