//! OFF (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads OFF.
pub fn read(path: &Path) -> Result<volux_core::TetMesh> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("OFF reader not yet written".into()),
    ))
}
