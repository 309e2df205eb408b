//! MPI's world communicator as an [`Exchange`] and a [`Collective`] (the collectives around
//! a distributed render: broadcast of bytes, gather of bytes to a root, agreement on
//! success), with MPI's own collectives in place of the trait's point-to-point ones.
use mpi::collective::SystemOperation;
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use volux_render::distributed::error::DistributedError;
use volux_render::distributed::exchange::{Collective, Exchange};

use crate::error::MpiError;

/// The tag of compositing messages.
const TAG_IMAGE: i32 = 17;
/// The tag of gathered figures.
const TAG_BYTES: i32 = 18;

/// MPI, started once per process (finalised when dropped).
pub struct Mpi {
    universe: Universe,
}

impl Mpi {
    /// Starts MPI.
    pub fn init() -> Result<Self, MpiError> {
        mpi::initialize()
            .map(|universe| Self { universe })
            .ok_or(MpiError::Init)
    }

    /// The world communicator.
    pub fn world(&self) -> World {
        World {
            comm: self.universe.world(),
        }
    }
}

/// The ranks of `mpirun`, as an [`Exchange`] and with the collectives of a render.
pub struct World {
    comm: SimpleCommunicator,
}

impl World {
    /// Rank `r`'s process.
    fn at(&self, r: usize) -> mpi::topology::Process<'_> {
        self.comm.process_at_rank(r as i32)
    }

    fn check(&self, r: usize) -> Result<(), DistributedError> {
        if r >= Exchange::size(self) {
            return Err(DistributedError::Exchange(format!(
                "rank {r} is outside the {} ranks",
                Exchange::size(self)
            )));
        }
        Ok(())
    }

    /// `bytes` of `root` on every rank (the others pass `None`).
    pub fn broadcast_bytes(&self, root: usize, bytes: Option<Vec<u8>>) -> Vec<u8> {
        let r = self.at(root);
        let mut buf = bytes.unwrap_or_default();
        let mut len = [buf.len() as u64];
        r.broadcast_into(&mut len[..]);
        buf.resize(len[0] as usize, 0);
        r.broadcast_into(&mut buf[..]);
        buf
    }

    /// Every rank's `bytes` on `root` (rank order), `None` elsewhere.
    pub fn gather_bytes(&self, root: usize, bytes: &[u8]) -> Option<Vec<Vec<u8>>> {
        if Exchange::rank(self) != root {
            self.at(root).send_with_tag(bytes, TAG_BYTES);
            return None;
        }
        Some(
            (0..Exchange::size(self))
                .map(|r| {
                    if r == root {
                        bytes.to_vec()
                    } else {
                        self.at(r).receive_vec_with_tag::<u8>(TAG_BYTES).0
                    }
                })
                .collect(),
        )
    }

    /// Whether `ok` holds on every rank.
    pub fn all(&self, ok: bool) -> bool {
        let mut all = 0i32;
        self.comm
            .all_reduce_into(&i32::from(ok), &mut all, SystemOperation::min());
        all == 1
    }

    /// Waits for every rank.
    pub fn barrier(&self) {
        self.comm.barrier();
    }
}

impl Exchange for World {
    fn rank(&self) -> usize {
        self.comm.rank() as usize
    }

    fn size(&self) -> usize {
        self.comm.size() as usize
    }

    fn send(&mut self, to: usize, data: &[f32]) -> Result<(), DistributedError> {
        self.check(to)?;
        self.at(to).send_with_tag(data, TAG_IMAGE);
        Ok(())
    }

    fn recv(&mut self, from: usize) -> Result<Vec<f32>, DistributedError> {
        self.check(from)?;
        Ok(self.at(from).receive_vec_with_tag::<f32>(TAG_IMAGE).0)
    }

    /// A non-blocking send under a blocking receive: two partners exchanging large pieces
    /// cannot both wait in a send.
    fn exchange(&mut self, partner: usize, data: &[f32]) -> Result<Vec<f32>, DistributedError> {
        self.check(partner)?;
        let p = self.at(partner);
        let got = mpi::request::scope(|scope| {
            let sent = p.immediate_send_with_tag(scope, data, TAG_IMAGE);
            let (got, _) = p.receive_vec_with_tag::<f32>(TAG_IMAGE);
            sent.wait();
            got
        });
        Ok(got)
    }
}

impl Collective for World {
    fn broadcast_bytes(
        &mut self,
        root: usize,
        bytes: Option<Vec<u8>>,
    ) -> Result<Vec<u8>, DistributedError> {
        self.check(root)?;
        Ok(World::broadcast_bytes(self, root, bytes))
    }

    fn gather_bytes(
        &mut self,
        root: usize,
        bytes: &[u8],
    ) -> Result<Option<Vec<Vec<u8>>>, DistributedError> {
        self.check(root)?;
        Ok(World::gather_bytes(self, root, bytes))
    }

    fn all(&mut self, ok: bool) -> Result<bool, DistributedError> {
        Ok(World::all(self, ok))
    }
}
