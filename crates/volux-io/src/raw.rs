//! raw + JSON sidecar (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads a raw grid through its sidecar.
pub fn read(path: &Path) -> Result<volux_core::Grid> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("raw + JSON sidecar reader not yet written".into()),
    ))
}
