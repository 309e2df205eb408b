//! The message passing the compositing needs ([`Exchange`]: rank, size, send, receive), the
//! few collectives a whole distributed frame needs around it ([`Collective`]: the plan
//! broadcast from rank 0, agreement that every rank succeeded, the figures gathered to rank
//! 0), and an in-process implementation over threads and channels ([`ThreadExchange`]) for
//! tests. `volux-mpi` implements both over MPI.
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

/// The collectives of a distributed frame, over bytes. The provided methods build them from
/// [`Exchange`]'s messages (the bytes packed four to an `f32`'s bits, after their length),
/// which a transport with its own collectives (MPI) overrides. Every rank must call each
/// collective, in the same order, while no other message is in flight.
pub trait Collective: Exchange {
    /// `bytes` of `root` on every rank (the others pass `None`).
    fn broadcast_bytes(
        &mut self,
        root: usize,
        bytes: Option<Vec<u8>>,
    ) -> Result<Vec<u8>, DistributedError> {
        if self.rank() != root {
            return unpack(&self.recv(root)?);
        }
        let bytes = bytes.unwrap_or_default();
        let packed = pack(&bytes);
        for r in (0..self.size()).filter(|&r| r != root) {
            self.send(r, &packed)?;
        }
        Ok(bytes)
    }

    /// Every rank's `bytes` on `root`, in rank order; `None` on the other ranks.
    fn gather_bytes(
        &mut self,
        root: usize,
        bytes: &[u8],
    ) -> Result<Option<Vec<Vec<u8>>>, DistributedError> {
        if self.rank() != root {
            self.send(root, &pack(bytes))?;
            return Ok(None);
        }
        (0..self.size())
            .map(|r| {
                if r == root {
                    Ok(bytes.to_vec())
                } else {
                    unpack(&self.recv(r)?)
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// Whether `ok` holds on every rank (the answer is the same on every rank).
    fn all(&mut self, ok: bool) -> Result<bool, DistributedError> {
        let votes = self.gather_bytes(0, &[u8::from(ok)])?;
        let all = votes.map(|v| v.iter().all(|b| b == &[1]));
        let answer = self.broadcast_bytes(0, all.map(|a| vec![u8::from(a)]))?;
        Ok(answer == [1])
    }
}

/// `bytes` as `f32`s for [`Exchange::send`]: the length, then four bytes to each `f32`'s
/// bits (little-endian, the last padded with zeros). Moving `f32`s copies their bits, so
/// [`unpack`] gives the bytes back exactly.
fn pack(bytes: &[u8]) -> Vec<f32> {
    let mut out = Vec::with_capacity(1 + bytes.len().div_ceil(4));
    out.push(f32::from_bits(bytes.len() as u32));
    out.extend(bytes.chunks(4).map(|c| {
        let mut word = [0u8; 4];
        word[..c.len()].copy_from_slice(c);
        f32::from_bits(u32::from_le_bytes(word))
    }));
    out
}

/// The bytes [`pack`] packed into `data`.
fn unpack(data: &[f32]) -> Result<Vec<u8>, DistributedError> {
    let bad =
        || DistributedError::Exchange(format!("a message of {} words is no bytes", data.len()));
    let (len, words) = data.split_first().ok_or_else(bad)?;
    let len = len.to_bits() as usize;
    if words.len() != len.div_ceil(4) {
        return Err(bad());
    }
    let mut out: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_bits().to_le_bytes())
        .collect();
    out.truncate(len);
    Ok(out)
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

impl Collective for ThreadExchange {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_survive_packing_whatever_their_bits() {
        let nan_bits: Vec<u8> = vec![0xff, 0xff, 0xff, 0x7f, 0x01, 0x00, 0xc0, 0xff, 7];
        for bytes in [vec![], vec![1u8], nan_bits, (0..=255).collect::<Vec<u8>>()] {
            assert_eq!(unpack(&pack(&bytes)).unwrap(), bytes);
        }
        assert!(unpack(&[]).is_err());
        assert!(unpack(&[f32::from_bits(9), 0.0]).is_err());
    }

    #[test]
    fn collectives_over_threads() {
        let handles: Vec<_> = ThreadExchange::group(3)
            .into_iter()
            .map(|mut ex| {
                std::thread::spawn(move || {
                    let r = ex.rank();
                    let plan = ex
                        .broadcast_bytes(0, (r == 0).then(|| b"plan".to_vec()))
                        .unwrap();
                    let gathered = ex.gather_bytes(0, &[r as u8; 5]).unwrap();
                    let all_ok = ex.all(true).unwrap();
                    let one_failed = ex.all(r != 2).unwrap();
                    (plan, gathered, all_ok, one_failed)
                })
            })
            .collect();
        for (r, h) in handles.into_iter().enumerate() {
            let (plan, gathered, all_ok, one_failed) = h.join().unwrap();
            assert_eq!(plan, b"plan");
            assert_eq!(gathered.is_some(), r == 0);
            if let Some(g) = gathered {
                assert_eq!(g, vec![vec![0u8; 5], vec![1u8; 5], vec![2u8; 5]]);
            }
            assert!(all_ok);
            assert!(!one_failed, "rank {r}");
        }
    }
}
