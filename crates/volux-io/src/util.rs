//! Shared reading helpers: gzip, bounded reads, size checks.
use std::io::{BufReader, Read};
use std::path::Path;

use flate2::read::MultiGzDecoder;

use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;

/// Opens `path`, transparently decompressing gzip (detected by its magic bytes).
pub fn open_maybe_gz(path: &Path) -> Result<Box<dyn Read>> {
    let mut f = BufReader::new(std::fs::File::open(path).map_err(|e| ReadError::new(path, e))?);
    let is_gz = {
        use std::io::BufRead;
        let buf = f.fill_buf().map_err(|e| ReadError::new(path, e))?;
        buf.starts_with(&[0x1f, 0x8b])
    };
    Ok(if is_gz {
        Box::new(MultiGzDecoder::new(f))
    } else {
        Box::new(f)
    })
}

/// Reads exactly `expected` bytes from `reader` after checking that so much memory can be
/// allocated; a short stream is [`ErrorKind::Truncated`]. Memory grows with what is actually
/// read, so a lying header cannot make us allocate more than the data holds plus one chunk.
pub fn read_exact_checked(path: &Path, mut reader: impl Read, expected: u64) -> Result<Vec<u8>> {
    volux_core::limits::check_alloc("data", expected, 1).map_err(|e| ReadError::new(path, e))?;
    let mut out = Vec::with_capacity(expected.min(64 << 20) as usize);
    let got = (&mut reader)
        .take(expected)
        .read_to_end(&mut out)
        .map_err(|e| ReadError::new(path, e))? as u64;
    if got < expected {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected,
                found: got,
            },
        ));
    }
    Ok(out)
}

/// A header error for `path`.
pub fn header_err(path: &Path, msg: impl Into<String>) -> ReadError {
    ReadError::new(path, ErrorKind::Header(msg.into()))
}
