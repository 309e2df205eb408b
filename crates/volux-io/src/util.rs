//! Shared reading and writing helpers: gzip, bounded reads, size checks, chunked writes with
//! progress.
use std::io::{BufReader, Read, Write};
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

/// Bytes between two progress reports of the writers.
pub(crate) const PROGRESS_STEP: u64 = 4 << 20;

/// Values encoded per chunk by [`write_chunked`].
const CHUNK_ITEMS: usize = 16 * 1024;

/// A writer that counts the bytes passed through it and reports `(written, total)` to a
/// callback: once on creation, then whenever `step` more bytes went through, and when the
/// count reaches `total`.
pub(crate) struct Progress<'a, W> {
    inner: W,
    done: u64,
    total: u64,
    next: u64,
    step: u64,
    report: &'a dyn Fn(u64, u64),
}

impl<'a, W: Write> Progress<'a, W> {
    /// Wraps `inner`; reports `(0, total)` at once.
    pub(crate) fn new(inner: W, total: u64, step: u64, report: &'a dyn Fn(u64, u64)) -> Self {
        report(0, total);
        Self {
            inner,
            done: 0,
            total,
            next: step.max(1),
            step: step.max(1),
            report,
        }
    }

    /// The wrapped writer.
    pub(crate) fn into_inner(self) -> W {
        self.inner
    }
}

impl<W: Write> Write for Progress<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.done += n as u64;
        if n > 0 && (self.done >= self.next || self.done == self.total) {
            (self.report)(self.done, self.total);
            self.next = self.done + self.step;
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Encodes `items` in chunks with `encode` (which appends the bytes of one item) and writes
/// each chunk to `out`, showing it to `inspect` first (e.g. to update a checksum).
pub(crate) fn write_chunked<T>(
    out: &mut impl Write,
    items: &[T],
    encode: impl Fn(&T, &mut Vec<u8>),
    mut inspect: impl FnMut(&[u8]),
) -> std::io::Result<()> {
    let mut buf = Vec::new();
    for chunk in items.chunks(CHUNK_ITEMS) {
        buf.clear();
        chunk.iter().for_each(|item| encode(item, &mut buf));
        inspect(&buf);
        out.write_all(&buf)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    #[test]
    fn progress_reports_every_step_and_the_end() {
        let calls = RefCell::new(Vec::new());
        let report = |d, t| calls.borrow_mut().push((d, t));
        let mut w = Progress::new(Vec::new(), 25, 10, &report);
        for _ in 0..5 {
            w.write_all(&[7; 5]).unwrap();
        }
        w.flush().unwrap();
        assert_eq!(w.into_inner(), vec![7; 25]);
        assert_eq!(*calls.borrow(), vec![(0, 25), (10, 25), (20, 25), (25, 25)]);
    }

    #[test]
    fn chunked_writes_encode_and_inspect_everything() {
        let items: Vec<u32> = (0..40_000).collect();
        let mut out = Vec::new();
        let mut seen = 0;
        write_chunked(
            &mut out,
            &items,
            |v, b| b.extend_from_slice(&v.to_le_bytes()),
            |chunk| seen += chunk.len(),
        )
        .unwrap();
        assert_eq!((out.len(), seen), (160_000, 160_000));
        assert_eq!(&out[4..8], &1u32.to_le_bytes());
        assert_eq!(&out[159_996..], &39_999u32.to_le_bytes());
    }
}
