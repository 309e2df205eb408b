//! Progress and cancellation of a load, for front ends that show a bar with a Cancel button
//! (the viewer). A [`LoadProgress`] installed on the loading thread with [`with_progress`]
//! counts the bytes the readers consume of the data they expect (after decompression), and
//! once cancelled makes the next read fail, so the load ends with an error at once instead
//! of running to its end. Loads without one (the CLI) pay a thread-local lookup per read
//! call, not per byte.
use std::cell::RefCell;
use std::io::{self, Read};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// The bytes read so far of those expected, and the cancel flag.
#[derive(Debug, Default)]
pub struct LoadProgress {
    done: AtomicU64,
    total: AtomicU64,
    cancelled: AtomicBool,
}

impl LoadProgress {
    /// A fresh counter.
    pub fn new() -> Arc<Self> {
        Arc::new(Self::default())
    }

    /// The fraction read, when the readers know how much to expect.
    pub fn fraction(&self) -> Option<f64> {
        let total = self.total.load(Ordering::Relaxed);
        (total > 0).then(|| (self.done.load(Ordering::Relaxed) as f64 / total as f64).min(1.0))
    }

    /// Bytes read so far.
    pub fn bytes(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Makes the load's next read fail with "load cancelled".
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Arc<LoadProgress>>> = const { RefCell::new(None) };
}

/// Runs `load` with `progress` receiving the reads made on this thread.
pub fn with_progress<T>(progress: Arc<LoadProgress>, load: impl FnOnce() -> T) -> T {
    let previous = CURRENT.with(|c| c.replace(Some(progress)));
    let out = load();
    CURRENT.with(|c| *c.borrow_mut() = previous);
    out
}

/// `reader` counted into the thread's progress, `expected` more bytes announced (0 when
/// unknown).
pub(crate) fn counted<R: Read>(reader: R, expected: u64) -> Counted<R> {
    let progress = CURRENT.with(|c| c.borrow().clone());
    if let Some(p) = &progress {
        p.total.fetch_add(expected, Ordering::Relaxed);
    }
    Counted { reader, progress }
}

/// A reader whose reads are counted (and refused once cancelled).
pub(crate) struct Counted<R> {
    reader: R,
    progress: Option<Arc<LoadProgress>>,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let Some(p) = &self.progress else {
            return self.reader.read(buf);
        };
        if p.cancelled.load(Ordering::Relaxed) {
            return Err(io::Error::other("load cancelled"));
        }
        let n = self.reader.read(buf)?;
        p.done.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_reads_and_cancels() {
        let p = LoadProgress::new();
        let data = vec![7u8; 1000];
        with_progress(p.clone(), || {
            let mut r = counted(&data[..], 1000);
            let mut buf = [0u8; 400];
            r.read_exact(&mut buf).unwrap();
            assert_eq!(p.fraction(), Some(0.4));
            p.cancel();
            let e = r.read(&mut buf).unwrap_err();
            assert!(e.to_string().contains("cancelled"));
        });
        // outside `with_progress` nothing is counted
        let mut r = counted(&data[..], 1000);
        assert_eq!(r.read(&mut [0u8; 10]).unwrap(), 10);
        assert_eq!(p.bytes(), 400);
    }

    /// A real load reports all its bytes, and a cancelled one ends with the reason.
    #[test]
    fn loads_report_progress_and_stop_when_cancelled() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ml.raw.gz");
        crate::raw::write(&volux_core::synth::marschner_lobb(20).unwrap(), &path).unwrap();
        let opts = crate::LoadOptions::default();
        let p = LoadProgress::new();
        with_progress(p.clone(), || crate::load(&path, &opts)).unwrap();
        assert_eq!(p.fraction(), Some(1.0), "{} bytes", p.bytes());
        let p = LoadProgress::new();
        p.cancel();
        let e = with_progress(p, || crate::load(&path, &opts)).unwrap_err();
        assert!(e.to_string().contains("load cancelled"), "{e}");
    }
}
