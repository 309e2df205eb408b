//! VTK XML (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads VTK XML.
pub fn read(path: &Path, array: Option<&str>) -> Result<crate::Dataset> {
    let _ = (path, array);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("VTK XML reader not yet written".into()),
    ))
}
