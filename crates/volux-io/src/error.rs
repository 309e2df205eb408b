//! The readers' and writers' errors.
use std::path::{Path, PathBuf};

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct ReadError {
    /// The file (or folder) being read.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: ErrorKind,
}

/// What went wrong while reading.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ErrorKind {
    /// An operating-system error.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The data section is shorter than the header says.
    #[error("truncated: expected {expected} bytes of data, found {found}")]
    Truncated {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// A header or sidecar that cannot be parsed or is inconsistent.
    #[error("malformed header: {0}")]
    Header(String),
    /// A valid file using a feature Volux does not read.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// Neither the magic bytes nor the extension name a known format.
    #[error("unknown format (neither the magic bytes nor the extension are recognised)")]
    UnknownFormat,
    /// The data model rejected what was read (dims, sizes, mesh validity, memory).
    #[error("{0}")]
    Data(#[from] volux_core::Error),
    /// Data that is syntactically readable but wrong (e.g. inconsistent DICOM slices).
    #[error("{0}")]
    Invalid(String),
}

impl ReadError {
    /// A read error for `path`.
    pub fn new(path: impl AsRef<Path>, kind: impl Into<ErrorKind>) -> Self {
        Self {
            path: path.as_ref().to_path_buf(),
            kind: kind.into(),
        }
    }
}

/// Result of the readers.
pub type Result<T, E = ReadError> = std::result::Result<T, E>;

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file being written.
    pub path: PathBuf,
    /// What went wrong.
    #[source]
    pub source: volux_core::Error,
}
