//! The errors of the application layer: data that says what went wrong (which session,
//! which word of which option, which backend), phrased by each front end for its users.
use volux_render::RenderError;

/// Errors of the application layer.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AppError {
    /// A session file that cannot be read or written, or that describes no valid scene.
    #[error("session {path}: {reason}")]
    Session {
        /// The session file.
        path: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A store that cannot be opened out of core (its metadata, a chunk that cannot be
    /// read while finding its statistics).
    #[error("{}: {reason}", path.display())]
    Store {
        /// The store.
        path: std::path::PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A pyramid level past a store's last.
    #[error("{level}: {} has {levels} levels, 0 (full resolution) to {}", store.display(), levels - 1)]
    NoSuchLevel {
        /// The store.
        store: std::path::PathBuf,
        /// The level asked for.
        level: usize,
        /// How many levels it has.
        levels: usize,
    },
    /// A session's sculpt steps (a voxel mask) replayed on a tetrahedral mesh.
    #[error("the session's sculpt steps apply to grids; this dataset is a tetrahedral mesh")]
    SculptOnMesh,
    /// The GPU backend was asked for in a build without it (the `gpu` feature).
    #[error("this build has no GPU backend (the `gpu` feature)")]
    GpuNotBuilt,
    /// A word of an option that does not parse ([`crate::words`]).
    #[error(transparent)]
    Word(#[from] crate::words::WordError),
    /// A rank of a distributed frame failed ([`crate::distributed`]): which, and why.
    #[error("rank {rank}: {reason}")]
    Distributed {
        /// The rank that failed first.
        rank: usize,
        /// Why.
        reason: String,
    },
    /// The engine's error.
    #[error(transparent)]
    Render(#[from] RenderError),
}
