//! PLOT3D (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads PLOT3D.
pub fn read(
    path: &Path,
    q_file: Option<&Path>,
    q_variable: Option<&str>,
) -> Result<volux_core::TetMesh> {
    let _ = (path, q_file, q_variable);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("PLOT3D reader not yet written".into()),
    ))
}
