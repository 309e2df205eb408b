//! DICOM (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads DICOM.
pub fn read(path: &Path, series_uid: Option<&str>) -> Result<volux_core::Grid> {
    let _ = (path, series_uid);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("DICOM reader not yet written".into()),
    ))
}
