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
    /// A path that is neither a regular file nor a folder (a FIFO, a device, a socket), or a
    /// folder where a file is needed; the field says which, e.g. `"a FIFO"`.
    #[error("not a regular file ({0}); Volux reads regular files and DICOM folders")]
    NotRegular(&'static str),
    /// A loop of symbolic links (`ELOOP`).
    #[error("a loop of symbolic links (each link leads back to another); Volux reads regular files and DICOM folders")]
    SymlinkLoop,
    /// A file larger than anything of its kind can be (e.g. a sidecar of several MiB).
    #[error("the file is {bytes} bytes, more than the {limit} bytes read for it")]
    FileTooLarge {
        /// Bytes in the file (or read so far).
        bytes: u64,
        /// Most bytes read.
        limit: u64,
    },
    /// The header declares more data than the rest of the file can deliver, even encoded as
    /// densely as the encoding allows (run-length, deflate): refused before allocating.
    #[error(
        "the header declares {declared} bytes of data, but the {available} bytes left in the \
         file can hold at most {max} ({how})"
    )]
    Undeliverable {
        /// Bytes the header declares.
        declared: u64,
        /// Encoded bytes present.
        available: u64,
        /// Most bytes those can decode to.
        max: u64,
        /// The encoding's densest expansion, in words.
        how: &'static str,
    },
    /// Compressed data that inflates to more than its limit (a decompression bomb, or data
    /// longer than the header says): decoding stopped there.
    #[error("{what} inflates to more than {limit} bytes ({why}); decoding stopped there")]
    Inflates {
        /// What was being decompressed.
        what: &'static str,
        /// Bytes allowed.
        limit: u64,
        /// Where the limit comes from.
        why: String,
    },
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
