//! `--raw-out F.f32`: an image as raw little-endian f32 for exact comparisons.
use std::path::Path;

use volux_core::Image;

use super::common::CmdError;

/// Writes `image` as raw little-endian f32 RGBA (linear, premultiplied, no background),
/// through a temporary file renamed into place.
pub fn write_raw(image: &Image, path: &Path) -> Result<(), CmdError> {
    let bytes: Vec<u8> = image
        .pixels()
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    volux_core::image::write_atomically(path, &bytes)
        .map_err(|e| format!("{}: {e}", path.display()).into())
}
