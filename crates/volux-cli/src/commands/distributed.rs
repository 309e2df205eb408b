//! `mpirun -np N volux render STORE.ome.zarr --distributed`: sort-last rendering of a store
//! on the ranks of `mpirun` ([`volux_render::distributed`] over `volux-mpi`), with the
//! `mpi` feature; without it, one line saying how to build it.
use super::common::CmdError;
use crate::cli::RenderArgs;

#[cfg(feature = "mpi")]
mod ranks;

/// Runs a distributed render on this rank (rank 0 writes the PNG and the figures).
#[cfg(feature = "mpi")]
pub fn run(args: &RenderArgs) -> Result<(), CmdError> {
    ranks::run(args)
}

/// Without MPI support: the error that says how to get it.
#[cfg(not(feature = "mpi"))]
pub fn run(_args: &RenderArgs) -> Result<(), CmdError> {
    Err("--distributed needs MPI: build volux with `cargo build --release -p volux-cli --features mpi` (OpenMPI's libopenmpi-dev and libclang-dev installed), then run `mpirun -np N volux render STORE.ome.zarr --distributed -o out.png`".into())
}
