//! VTK legacy (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads VTK legacy.
pub fn read(path: &Path, array: Option<&str>) -> Result<crate::Dataset> {
    let _ = (path, array);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("VTK legacy reader not yet written".into()),
    ))
}
