//! Shared reading and writing helpers: opening only regular files, gzip, bounded reads, size
//! checks, chunked writes with progress.
//!
//! Every data, header, sidecar and companion file is opened through [`open_regular`] or
//! [`read_regular`] (or [`open_maybe_gz`], which uses them): a FIFO, a device or a socket is
//! refused by its type before it is opened (opening a FIFO blocks, and `/dev/zero` never
//! ends), and a loop of symbolic links is a clean [`ErrorKind::SymlinkLoop`].
use std::fs::{File, Metadata};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use flate2::read::MultiGzDecoder;

use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;

/// Deflate (zlib, gzip) expands at most 1032:1 (a 258-byte match coded in about 2 bits), so
/// `n` compressed bytes never inflate to more than `n * MAX_DEFLATE_RATIO` bytes (plus
/// `DEFLATE_SLACK`). A header declaring more is refused before anything is inflated.
pub const MAX_DEFLATE_RATIO: u64 = 1032;

/// Bytes of output allowed on top of [`MAX_DEFLATE_RATIO`] times the input, for tiny streams.
const DEFLATE_SLACK: u64 = 4096;

/// The first capacity of buffers filled from a stream; they grow as data actually arrives, so
/// a lying header costs no more than this up front. 32 MiB holds the typical scan whole (no
/// regrowth and copy: a 14 MiB CT read 3 % slower from a 4 MiB start).
const FIRST_CHUNK: u64 = 32 << 20;

/// `ELOOP` ("too many levels of symbolic links") on this system.
#[cfg(any(target_os = "linux", target_os = "android"))]
const ELOOP: i32 = 40;
/// `ELOOP` ("too many levels of symbolic links") on this system.
#[cfg(not(any(target_os = "linux", target_os = "android")))]
const ELOOP: i32 = 62;

/// A read error for `path` from an operating-system error; a loop of symbolic links becomes
/// [`ErrorKind::SymlinkLoop`].
pub fn io_error(path: &Path, e: std::io::Error) -> ReadError {
    if e.raw_os_error() == Some(ELOOP) {
        ReadError::new(path, ErrorKind::SymlinkLoop)
    } else {
        ReadError::new(path, e)
    }
}

/// What a file type is when it is neither a regular file nor a folder: `"a FIFO"`, ...
#[cfg(unix)]
fn special_kind(t: std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    [
        (t.is_fifo(), "a FIFO"),
        (t.is_char_device(), "a character device"),
        (t.is_block_device(), "a block device"),
        (t.is_socket(), "a socket"),
    ]
    .into_iter()
    .find_map(|(is, name)| is.then_some(name))
}

/// What a file type is when it is neither a regular file nor a folder.
#[cfg(not(unix))]
fn special_kind(t: std::fs::FileType) -> Option<&'static str> {
    (!t.is_file() && !t.is_dir()).then_some("not a file or folder")
}

/// The metadata of `path` (symbolic links followed) when it is a regular file or a folder;
/// FIFOs, devices and sockets are [`ErrorKind::NotRegular`], symlink loops
/// [`ErrorKind::SymlinkLoop`]. Nothing is opened.
pub fn data_metadata(path: &Path) -> Result<Metadata> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    match special_kind(meta.file_type()) {
        Some(kind) => Err(ReadError::new(path, ErrorKind::NotRegular(kind))),
        None => Ok(meta),
    }
}

/// The metadata of `path` when it is a regular file (see [`data_metadata`]); a folder is
/// [`ErrorKind::NotRegular`] too.
pub fn regular_metadata(path: &Path) -> Result<Metadata> {
    let meta = data_metadata(path)?;
    if meta.is_dir() {
        return Err(ReadError::new(path, ErrorKind::NotRegular("a folder")));
    }
    Ok(meta)
}

/// Opens `path` for reading after checking that it is a regular file: FIFOs (whose opening
/// blocks), devices, sockets and folders are refused by type before opening, and the opened
/// file is checked again (in case the path changed in between).
pub fn open_regular(path: &Path) -> Result<File> {
    regular_metadata(path)?;
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let meta = file.metadata().map_err(|e| io_error(path, e))?;
    if !meta.is_file() {
        let kind = special_kind(meta.file_type()).unwrap_or("a folder");
        return Err(ReadError::new(path, ErrorKind::NotRegular(kind)));
    }
    Ok(file)
}

/// The length of an opened regular file.
pub fn file_len(path: &Path, file: &File) -> Result<u64> {
    Ok(file.metadata().map_err(|e| io_error(path, e))?.len())
}

/// Reads the whole regular file `path` ([`open_regular`]), refusing files over `limit` bytes
/// ([`ErrorKind::FileTooLarge`]) or over the memory limit before reading. The read itself is
/// capped too, so a file that grows meanwhile cannot exceed the limit.
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let file = open_regular(path)?;
    let len = file_len(path, &file)?;
    let too_large = |bytes| ReadError::new(path, ErrorKind::FileTooLarge { bytes, limit });
    if len > limit {
        return Err(too_large(len));
    }
    volux_core::limits::check_alloc("file", len, 1).map_err(|e| ReadError::new(path, e))?;
    let mut out = Vec::with_capacity(len as usize);
    let got = crate::progress::counted(file, len)
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| io_error(path, e))? as u64;
    if got > limit {
        return Err(too_large(got));
    }
    Ok(out)
}

/// A file opened by [`open_gz_input`]: its (decompressing) reader, its length, and whether
/// it is gzip.
pub struct GzInput {
    /// The bytes, decompressed when the file is gzip.
    pub reader: Box<dyn Read>,
    /// Length of the file on disk (compressed bytes for gzip).
    pub file_len: u64,
    /// Whether the file starts with the gzip magic bytes `1f 8b`.
    pub gzip: bool,
}

/// Opens the regular file `path` ([`open_regular`]), decompressing gzip (detected by its
/// magic bytes `1f 8b`).
pub fn open_gz_input(path: &Path) -> Result<GzInput> {
    let file = open_regular(path)?;
    let file_len = file_len(path, &file)?;
    let mut f = BufReader::new(file);
    let gzip = f
        .fill_buf()
        .map_err(|e| io_error(path, e))?
        .starts_with(&[0x1f, 0x8b]);
    let reader: Box<dyn Read> = if gzip {
        Box::new(MultiGzDecoder::new(f))
    } else {
        Box::new(f)
    };
    Ok(GzInput {
        reader,
        file_len,
        gzip,
    })
}

/// Opens `path`, transparently decompressing gzip (detected by its magic bytes); only
/// regular files are opened ([`open_regular`]).
pub fn open_maybe_gz(path: &Path) -> Result<Box<dyn Read>> {
    Ok(open_gz_input(path)?.reader)
}

/// Most bytes `compressed` bytes of deflate data can inflate to.
pub fn max_inflated(compressed: u64) -> u64 {
    compressed
        .saturating_mul(MAX_DEFLATE_RATIO)
        .saturating_add(DEFLATE_SLACK)
}

/// Checks, before inflating, that `compressed` bytes of deflate (zlib, gzip) data can hold
/// the `declared` bytes a header announces ([`ErrorKind::Undeliverable`] if not) and that so
/// much memory may be allocated.
pub fn check_inflatable(path: &Path, compressed: u64, declared: u64) -> Result<()> {
    volux_core::limits::check_alloc("data", declared, 1).map_err(|e| ReadError::new(path, e))?;
    let max = max_inflated(compressed);
    if declared > max {
        return Err(ReadError::new(
            path,
            ErrorKind::Undeliverable {
                declared,
                available: compressed,
                max,
                how: "deflate expands at most 1032:1",
            },
        ));
    }
    Ok(())
}

/// Reads all of `reader` into a growing buffer, stopping with [`ErrorKind::Inflates`] as
/// soon as more than `limit` bytes arrive (`why` says where the limit comes from). Nothing
/// is reserved up front beyond a first chunk.
pub fn read_to_limit(
    path: &Path,
    reader: impl Read,
    limit: u64,
    what: &'static str,
    why: impl FnOnce() -> String,
) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(limit.min(FIRST_CHUNK) as usize);
    let got = crate::progress::counted(reader, 0)
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| io_error(path, e))? as u64;
    if got > limit {
        let why = why();
        return Err(ReadError::new(
            path,
            ErrorKind::Inflates { what, limit, why },
        ));
    }
    Ok(out)
}

/// Reads exactly `expected` bytes from `reader` after checking that so much memory can be
/// allocated; a short stream is [`ErrorKind::Truncated`]. Memory grows with what is actually
/// read (from a first chunk of a few MiB), so a lying header cannot make us allocate more than
/// the data holds plus one chunk.
pub fn read_exact_checked(path: &Path, reader: impl Read, expected: u64) -> Result<Vec<u8>> {
    volux_core::limits::check_alloc("data", expected, 1).map_err(|e| ReadError::new(path, e))?;
    let mut out = Vec::with_capacity(expected.min(FIRST_CHUNK) as usize);
    let got = crate::progress::counted(reader, expected)
        .take(expected)
        .read_to_end(&mut out)
        .map_err(|e| io_error(path, e))? as u64;
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

/// Hostile inputs for the readers' tests: a FIFO, a link to `/dev/zero`, a loop of links.
#[cfg(test)]
pub(crate) mod hostile {
    use std::path::{Path, PathBuf};

    /// A FIFO at `dir/name` made with `mkfifo`, or `None` (with a message) where that fails.
    /// A watchdog thread opens it for writing after a few seconds, so a reader that opens it
    /// anyway (a regression) fails on its empty data instead of blocking the tests forever.
    pub(crate) fn fifo(dir: &Path, name: &str) -> Option<PathBuf> {
        let p = dir.join(name);
        let made = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .is_ok_and(|s| s.success());
        if !made {
            eprintln!("skipped: mkfifo is not available");
            return None;
        }
        let writer = p.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_secs(5));
            let _ = std::fs::OpenOptions::new().write(true).open(writer);
        });
        Some(p)
    }

    /// A symbolic link `dir/name` to `/dev/zero`.
    pub(crate) fn zero_link(dir: &Path, name: &str) -> PathBuf {
        let p = dir.join(name);
        std::os::unix::fs::symlink("/dev/zero", &p).unwrap();
        p
    }

    /// Two symbolic links `dir/name` -> `dir/name.b` -> `dir/name`; returns the first.
    pub(crate) fn link_loop(dir: &Path, name: &str) -> PathBuf {
        let a = dir.join(name);
        let b = dir.join(format!("{name}.b"));
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        a
    }

    /// Asserts that `e` refuses a header declaring `declared` bytes the file cannot deliver
    /// (or the memory budget refuses it first).
    pub(crate) fn assert_undeliverable(e: &crate::error::ReadError, declared: u64) {
        use crate::error::ErrorKind;
        assert!(
            matches!(
                e.kind,
                ErrorKind::Undeliverable { declared: d, .. } if d == declared
            ) || matches!(e.kind, ErrorKind::Data(_)),
            "{e}"
        );
    }

    /// The message of an error that must be one about the path's type or a link loop.
    pub(crate) fn assert_refused<T>(r: crate::error::Result<T>, name: &str, expect: &str) {
        let e = match r {
            Ok(_) => panic!("{name}: a hostile file was read"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(name) && e.contains(expect), "{name}: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[cfg(test)]
mod tests {
    use super::hostile::*;
    use super::*;
    use std::cell::RefCell;

    #[test]
    fn only_regular_files_are_opened() {
        let dir = tempfile::tempdir().unwrap();
        let zero = zero_link(dir.path(), "zero.nrrd");
        assert_refused(open_regular(&zero), "zero.nrrd", "(a character device)");
        assert_refused(
            read_regular(&zero, 1 << 20),
            "zero.nrrd",
            "Volux reads regular",
        );
        assert_refused(open_maybe_gz(&zero), "zero.nrrd", "character device");
        let looped = link_loop(dir.path(), "a.raw");
        assert_refused(open_regular(&looped), "a.raw", "loop of symbolic links");
        assert_refused(data_metadata(&looped), "a.raw", "loop of symbolic links");
        assert_refused(open_regular(dir.path()), "", "(a folder)");
        assert!(data_metadata(dir.path()).is_ok());
        if let Some(fifo) = fifo(dir.path(), "t.nrrd") {
            // Refused by type: opening it would block until a writer comes.
            assert_refused(open_regular(&fifo), "t.nrrd", "not a regular file (a FIFO)");
        }
    }

    #[test]
    fn reads_are_capped() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.json");
        std::fs::write(&p, [b' '; 100]).unwrap();
        assert_eq!(read_regular(&p, 100).unwrap().len(), 100);
        let e = read_regular(&p, 99).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ErrorKind::FileTooLarge {
                    bytes: 100,
                    limit: 99
                }
            ),
            "{e}"
        );
        let e = read_to_limit(&p, &[0u8; 10][..], 9, "test", || "why".into()).unwrap_err();
        assert!(
            e.to_string()
                .contains("inflates to more than 9 bytes (why)"),
            "{e}"
        );
        assert!(check_inflatable(&p, 1000, 1000 * MAX_DEFLATE_RATIO).is_ok());
        let e = check_inflatable(&p, 10, 1 << 30).unwrap_err();
        assert!(matches!(e.kind, ErrorKind::Undeliverable { .. }), "{e}");
    }

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
