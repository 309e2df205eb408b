//! NIfTI-1 (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads NIfTI-1.
pub fn read(path: &Path) -> Result<volux_core::Grid> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("NIfTI-1 reader not yet written".into()),
    ))
}
