//! The shared datasets of `../shared/data` (next to the repository), which tests use when
//! present and skip, with a message, when absent.
use std::path::{Path, PathBuf};

/// The folder of the shared datasets.
pub fn shared_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}

/// A file of `../shared/data`, or `None` (printing that the test skips it) when absent;
/// `shared("")` is the folder itself.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_root().join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} is absent", p.display());
        None
    }
}
