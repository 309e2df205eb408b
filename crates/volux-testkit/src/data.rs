//! The shared datasets of `../shared/data` (next to the repository), which tests use when
//! present and skip, with a message, when absent, unless `VOLUX_DATA_REQUIRED=1` (set by
//! `.ci/run`): then a missing dataset fails the test.
use std::path::{Path, PathBuf};

/// The folder of the shared datasets.
pub fn shared_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}

/// A file of `../shared/data`, or `None` (printing that the test skips it) when absent;
/// `shared("")` is the folder itself. Panics instead of skipping when
/// [`data_required`].
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_root().join(rel);
    if p.exists() {
        return Some(p);
    }
    skip_or_fail(&format!("{} is absent", p.display()));
    None
}

/// Whether `VOLUX_DATA_REQUIRED` is set: a test that needs `../shared/data` fails instead of
/// skipping.
pub fn data_required() -> bool {
    std::env::var_os("VOLUX_DATA_REQUIRED").is_some_and(|v| v != "0")
}

/// Says that a test skips for `why`, or panics with it when [`data_required`].
pub fn skip_or_fail(why: &str) {
    if data_required() {
        panic!("VOLUX_DATA_REQUIRED is set and {why}");
    }
    eprintln!("skipping: {why}");
}
