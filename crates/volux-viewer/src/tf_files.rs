//! Transfer functions from files, as `volux render --tf FILE` reads them.
use std::path::Path;

use volux_core::TransferFunction;

/// Largest TF file read.
pub const MAX_TF_BYTES: u64 = 16 << 20;

/// Reads a transfer function file: Volux TF JSON, a ParaView colour-map preset, or a 3D
/// Slicer volume property (`.vp`), as [`volux_core::transfer_import::import`] detects.
pub fn read(path: &Path) -> Result<TransferFunction, String> {
    let shown = path.display();
    let len = std::fs::metadata(path)
        .map_err(|e| format!("{shown}: {e}"))?
        .len();
    if len > MAX_TF_BYTES {
        return Err(format!(
            "{shown}: {len} bytes, more than a transfer function holds"
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{shown}: {e}"))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    volux_core::transfer_import::import(&name, &text)
        .map(|imported| imported.tf)
        .map_err(|e| format!("{shown}: {e}"))
}
