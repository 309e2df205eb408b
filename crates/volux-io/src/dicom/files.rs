//! What the folder reader and the file reader share: the `DICM` marker test, the errors that
//! explain a file `dicom-object` cannot parse, and the note on skipped entries.
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::{pixels, ts};
use crate::error::{ErrorKind, ReadError, Result};

/// An [`ErrorKind::Invalid`] error about `path`.
pub(super) fn invalid(path: &Path, msg: impl Into<String>) -> ReadError {
    ReadError::new(path, ErrorKind::Invalid(msg.into()))
}

/// Whether the file has the `DICM` marker after the 128-byte preamble.
pub(super) fn has_dicm(path: &Path) -> Result<bool> {
    let mut head = [0u8; 132];
    let f = crate::util::open_regular(path)?;
    let n = f
        .take(132)
        .read(&mut head)
        .map_err(|e| ReadError::new(path, e))?;
    Ok(n == 132 && &head[128..] == b"DICM")
}

/// Explains why `dicom-object` could not read `path`: a file ending inside its pixel data, a
/// transfer syntax Volux does not read, or the parser's message.
pub(super) fn parse_error(path: &Path, e: &dyn std::error::Error) -> ReadError {
    if let Some(ts) = meta_transfer_syntax(path) {
        if let Some(why) = ts::unsupported(&ts) {
            return ReadError::new(path, ErrorKind::Unsupported(why));
        }
        if let Some((expected, found)) = pixels::truncation(path, &ts) {
            return ReadError::new(path, ErrorKind::Truncated { expected, found });
        }
    }
    let mut msg = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        msg.push_str(": ");
        msg.push_str(&s.to_string());
        src = s.source();
    }
    invalid(path, format!("cannot parse the DICOM file: {msg}"))
}

/// The transfer syntax from the file meta group, if readable.
fn meta_transfer_syntax(path: &Path) -> Option<String> {
    let mut f = std::io::BufReader::new(crate::util::open_regular(path).ok()?);
    f.seek(SeekFrom::Start(128)).ok()?;
    let meta = dicom_object::meta::FileMetaTable::from_reader(f).ok()?;
    Some(meta.transfer_syntax().to_string())
}

/// A note naming the empty files and folders among a series' files, so that a damaged
/// series is not read short without a word (other files, such as a JSON sidecar or a
/// DICOMDIR, are skipped quietly).
pub(super) fn skipped_note(skipped: &[&Path]) -> Option<String> {
    let (mut empty, mut folders) = (0, 0);
    for p in skipped {
        match std::fs::metadata(p) {
            Ok(m) if m.is_dir() => folders += 1,
            Ok(m) if m.is_file() && m.len() == 0 => empty += 1,
            _ => {}
        }
    }
    let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    match (empty, folders) {
        (0, 0) => None,
        (e, 0) => Some(format!(
            "skipped {} among the series' files",
            plural(e, "empty file")
        )),
        (0, f) => Some(format!(
            "skipped {} among the series' files",
            plural(f, "folder")
        )),
        (e, f) => Some(format!(
            "skipped {} and {} among the series' files",
            plural(e, "empty file"),
            plural(f, "folder")
        )),
    }
}
