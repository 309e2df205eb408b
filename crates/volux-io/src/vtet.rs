//! Volux binary tet mesh (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Magic bytes of the format.
pub const MAGIC: &[u8] = b"VOLUXTET";

/// Reads a .vtet mesh.
pub fn read(path: &Path) -> Result<volux_core::TetMesh> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("Volux binary tet mesh reader not yet written".into()),
    ))
}
