//! Background work of the window besides rendering: loading a dataset, splitting a grid
//! into tetrahedra, writing a large screenshot. A [`Job`] runs on its own thread; the window
//! polls it each frame and never waits. Cancelling drops the job's result: the window is
//! free at once, the thread finishes in the background and its result is discarded (the
//! readers are bounded, so it ends).
use std::sync::mpsc::{channel, Receiver, TryRecvError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// One piece of background work.
pub struct Job<T> {
    /// What the window shows while it runs.
    pub label: String,
    started: Instant,
    result: Receiver<Result<T, String>>,
    thread: Option<JoinHandle<()>>,
}

/// How a job stands.
#[derive(Debug)]
pub enum Poll<T> {
    /// Still running.
    Running,
    /// Done.
    Done(Result<T, String>),
}

impl<T: Send + 'static> Job<T> {
    /// Runs `work` on a new thread; a panic in it becomes an error, never a crash of the
    /// window.
    pub fn spawn(
        label: impl Into<String>,
        work: impl FnOnce() -> Result<T, String> + Send + 'static,
    ) -> Self {
        let (tx, result) = channel();
        let thread = std::thread::spawn(move || {
            let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
                .unwrap_or_else(|p| Err(panic_message(p)));
            let _ = tx.send(out);
        });
        Self {
            label: label.into(),
            started: Instant::now(),
            result,
            thread: Some(thread),
        }
    }

    /// The result when the job is done.
    pub fn poll(&mut self) -> Poll<T> {
        match self.result.try_recv() {
            Ok(r) => {
                if let Some(t) = self.thread.take() {
                    let _ = t.join();
                }
                Poll::Done(r)
            }
            Err(TryRecvError::Empty) => Poll::Running,
            Err(TryRecvError::Disconnected) => Poll::Done(Err("the job stopped".into())),
        }
    }

    /// Waits for the result (tests, `--screenshot` set-up).
    pub fn wait(mut self, timeout: Duration) -> Result<T, String> {
        match self.result.recv_timeout(timeout) {
            Ok(r) => {
                if let Some(t) = self.thread.take() {
                    let _ = t.join();
                }
                r
            }
            Err(_) => Err(format!("{} did not finish in {timeout:?}", self.label)),
        }
    }

    /// Time since it started.
    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    let what = p
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown".into());
    format!("internal error (please report it): {what}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_and_panics_come_back() {
        let ok = Job::spawn("sum", || Ok(2 + 2));
        assert_eq!(ok.wait(Duration::from_secs(5)), Ok(4));
        let bad: Job<()> = Job::spawn("boom", || panic!("no"));
        let err = bad.wait(Duration::from_secs(5)).unwrap_err();
        assert!(err.contains("no"), "{err}");
    }
}
