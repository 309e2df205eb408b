//! The errors of the MPI layer.

/// Errors of the MPI layer.
#[derive(Debug, thiserror::Error)]
pub enum MpiError {
    /// MPI could not be started (it was already, or the library failed).
    #[error("MPI could not be initialised (is this process started by mpirun, and only once?)")]
    Init,
    /// A message that could not be decoded.
    #[error("rank {rank}: {reason}")]
    Message {
        /// The rank the message came from.
        rank: usize,
        /// What was wrong.
        reason: String,
    },
}
