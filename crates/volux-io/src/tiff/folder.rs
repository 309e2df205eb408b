//! Folders of numbered single-page TIFF slices (`slice_1.tif`, `slice_2.tif`, ...,
//! `slice_10.tif`), as ImageJ's "Image Sequence" and many microscopes write them: the files
//! named `*.tif` / `*.tiff` (hidden files and other names ignored) in natural order (numbers
//! compared as numbers, so `slice2` comes before `slice10`), one z slice each. All slices must
//! agree on size and samples (grayscale or colour, as [`super::pages`] reads them); the first
//! one's metadata gives the spacing.
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

use volux_core::Grid;

use crate::dataset::VolumeChoice;
use crate::detect::is_tiff_name;
use crate::error::{ErrorKind, ReadError, Result};
use crate::util::io_error;

use super::imagej;
use super::layout::{choose, plain_spacing, Layout};
use super::pages::{self, resolution, tag_number, Volume};

/// Compares file names in natural order: runs of digits by their value, the rest
/// case-insensitively.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a, b);
    loop {
        let (Some(ca), Some(cb)) = (a.chars().next(), b.chars().next()) else {
            return a.len().cmp(&b.len());
        };
        let ord = if ca.is_ascii_digit() && cb.is_ascii_digit() {
            let da = a.len() - a.trim_start_matches(|c: char| c.is_ascii_digit()).len();
            let db = b.len() - b.trim_start_matches(|c: char| c.is_ascii_digit()).len();
            let (na, nb) = (
                a[..da].trim_start_matches('0'),
                b[..db].trim_start_matches('0'),
            );
            let ord = na.len().cmp(&nb.len()).then_with(|| na.cmp(nb));
            (a, b) = (&a[da..], &b[db..]);
            ord
        } else {
            let ord = ca.to_lowercase().cmp(cb.to_lowercase());
            (a, b) = (&a[ca.len_utf8()..], &b[cb.len_utf8()..]);
            ord
        };
        if ord != Ordering::Equal {
            return ord;
        }
    }
}

/// The TIFF files of folder `dir` in natural order, with their sizes.
pub fn slices(dir: &Path) -> Result<Vec<(PathBuf, u64)>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| io_error(dir, e))? {
        let entry = entry.map_err(|e| io_error(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || !is_tiff_name(&name) {
            continue;
        }
        let p = entry.path();
        match std::fs::metadata(&p) {
            Ok(m) if m.is_file() => out.push((name, p, m.len())),
            _ => continue,
        }
    }
    out.sort_by(|a, b| natural_cmp(&a.0, &b.0));
    Ok(out.into_iter().map(|(_, p, len)| (p, len)).collect())
}

/// Reads the folder `dir` of TIFF slices; it has one channel and one timepoint, and
/// `choice.component` picks a colour channel of colour slices.
pub fn read(dir: &Path, channel: usize, choice: VolumeChoice) -> Result<Grid> {
    choose(dir, "channel", channel, 1)?;
    choose(dir, "timepoint", choice.timepoint, 1)?;
    let files = slices(dir)?;
    let Some((first_path, _)) = files.first() else {
        return Err(ReadError::new(
            dir,
            ErrorKind::Invalid("the folder holds no .tif / .tiff files".into()),
        ));
    };
    let (mut dec, _) = pages::open(first_path)?;
    let first = pages::page_info(first_path, &mut dec, 0)?;
    let keep = pages::keep(first_path, &first, choice.component)?;
    let res = resolution(first_path, &mut dec)?;
    let (spacing, spacing_note) = match pages::description(first_path, &mut dec)? {
        Some(d) if imagej::is_imagej(&d) => {
            imagej::parse(first_path, &d)?.spacing(first_path, res)?
        }
        _ => {
            let unit = tag_number(first_path, &mut dec, ::tiff::tags::Tag::ResolutionUnit)?;
            plain_spacing(first_path, res, unit)?
        }
    };
    let encoded = files.iter().fold(0u64, |a, (_, l)| a.saturating_add(*l));
    pages::check_volume(dir, &first, keep, files.len(), encoded)?;
    let mut volume = Volume::new(first, keep, files.len());
    for (z, (file, _)) in files.iter().enumerate() {
        let (mut dec, _) = pages::open(file)?;
        volume.read_page(file, &mut dec, 0, z)?;
        if dec.more_images() {
            return Err(ReadError::new(
                file,
                ErrorKind::Invalid(
                    "this slice has several pages; a folder's slices must be single-page TIFF"
                        .into(),
                ),
            ));
        }
    }
    let layout = Layout {
        ifds: (0..files.len()).collect(),
        spacing,
        spacing_note,
        flavour: "folder",
        notes: Vec::new(),
        axes: Vec::new(),
    };
    let what = format!("TIFF folder: {} slices", files.len());
    volume.into_grid(dir, what, layout)
}

#[cfg(test)]
mod tests {
    use super::natural_cmp;

    #[test]
    fn numbers_sort_by_value() {
        let mut v = vec![
            "slice10.tif",
            "slice2.tif",
            "Slice1.tif",
            "slice002b.tif",
            "a.tif",
        ];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            v,
            [
                "a.tif",
                "Slice1.tif",
                "slice2.tif",
                "slice002b.tif",
                "slice10.tif"
            ]
        );
    }
}
