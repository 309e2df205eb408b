//! # volux-mpi
//!
//! Volux's distributed rendering over MPI (the `mpi` crate, rsmpi, over OpenMPI): the
//! message passing of [`volux_render::distributed`] (its
//! [`Exchange`](volux_render::distributed::exchange::Exchange) trait) on an MPI
//! communicator, and the few collectives a distributed render needs around it (broadcast of
//! the job, agreement on success, gather of the per-rank figures).
//!
//! Seed `003` renders blocks of a volume separately and merges their images with the
//! opacity reset at every block boundary; here each rank renders the exact integral of its
//! part of every ray and the ranks composite front to back in visibility order (adaptive
//! Simpson passes its rays' states along that order instead), so the image equals the
//! single-process render.
//!
//! Modules:
//! - [`error`]: the errors of the MPI layer;
//! - `world` (with the `mpi` feature): `World`, MPI's world communicator as an
//!   `Exchange` and a `Collective` (byte broadcast and gather, agreement).
//!
//! The distributed frame itself (planning, regions, agreement, figures) is the application
//! layer's (`volux_app::distributed`), written over those traits.
//!
//! Without the `mpi` feature the crate has no MPI dependency (and no `World`).
#![deny(missing_docs)]
#![deny(unsafe_code)]

pub mod error;
#[cfg(feature = "mpi")]
pub mod world;

#[cfg(feature = "mpi")]
pub use world::{Mpi, World};

pub use error::MpiError;
