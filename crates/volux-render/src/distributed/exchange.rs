//! The message passing the compositing needs ([`Exchange`]: rank, size, send, receive), and
//! an in-process implementation over threads and channels ([`ThreadExchange`]) for tests.
//! `volux-mpi` implements it over MPI.
use std::sync::mpsc::{channel, Receiver, Sender};

use super::error::DistributedError;

/// Point-to-point messages of `f32` between the ranks `0..size()` of a group.
pub trait Exchange {
    /// This rank, in `0..size()`.
    fn rank(&self) -> usize;

    /// The number of ranks.
    fn size(&self) -> usize;

    /// Sends `data` to rank `to` (messages between two ranks arrive in the order sent).
    fn send(&mut self, to: usize, data: &[f32]) -> Result<(), DistributedError>;

    /// The next message from rank `from`.
    fn recv(&mut self, from: usize) -> Result<Vec<f32>, DistributedError>;

    /// Sends `data` to `partner` and receives its message (both send at once: an MPI
    /// implementation overrides this with one `sendrecv`, which cannot deadlock on large
    /// messages). By default a send, then a receive.
    fn exchange(&mut self, partner: usize, data: &[f32]) -> Result<Vec<f32>, DistributedError> {
        self.send(partner, data)?;
        self.recv(partner)
    }
}

/// One rank of a group of threads, connected to every other by channels (unbounded: sends
/// never block).
pub struct ThreadExchange {
    rank: usize,
    to: Vec<Sender<Vec<f32>>>,
    from: Vec<Receiver<Vec<f32>>>,
}

impl ThreadExchange {
    /// A group of `size` connected ranks, rank `r` at index `r` (hand each to a thread).
    pub fn group(size: usize) -> Vec<ThreadExchange> {
        // links[a][b]: a sends, b receives.
        let mut senders: Vec<Vec<Sender<Vec<f32>>>> = (0..size).map(|_| Vec::new()).collect();
        let mut receivers: Vec<Vec<Option<Receiver<Vec<f32>>>>> = (0..size)
            .map(|_| (0..size).map(|_| None).collect())
            .collect();
        for (a, s) in senders.iter_mut().enumerate() {
            for r in receivers.iter_mut() {
                let (tx, rx) = channel();
                s.push(tx);
                r[a] = Some(rx);
            }
        }
        senders
            .into_iter()
            .zip(receivers)
            .enumerate()
            .map(|(rank, (to, from))| ThreadExchange {
                rank,
                to,
                from: from.into_iter().flatten().collect(),
            })
            .collect()
    }

    fn check(&self, other: usize) -> Result<(), DistributedError> {
        if other >= self.to.len() {
            return Err(DistributedError::Exchange(format!(
                "rank {other} is outside the group of {}",
                self.to.len()
            )));
        }
        Ok(())
    }
}

impl Exchange for ThreadExchange {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.to.len()
    }

    fn send(&mut self, to: usize, data: &[f32]) -> Result<(), DistributedError> {
        self.check(to)?;
        self.to[to]
            .send(data.to_vec())
            .map_err(|_| DistributedError::Exchange(format!("rank {to} has left the group")))
    }

    fn recv(&mut self, from: usize) -> Result<Vec<f32>, DistributedError> {
        self.check(from)?;
        self.from[from].recv().map_err(|_| {
            DistributedError::Exchange(format!("rank {from} left the group before sending"))
        })
    }
}
