//! MetaImage (being written).
use std::path::Path;

use crate::{ErrorKind, ReadError, Result};

/// Reads MetaImage.
pub fn read(path: &Path) -> Result<volux_core::Grid> {
    let _ = (path);
    Err(ReadError::new(
        path,
        ErrorKind::Unsupported("MetaImage reader not yet written".into()),
    ))
}
