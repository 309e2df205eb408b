//! NRRD (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads NRRD.
pub fn read(path: &Path) -> Result<volux_core::Grid> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("NRRD reader not yet written".into()),
    ))
}
