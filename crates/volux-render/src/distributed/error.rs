//! The errors of distributed rendering.
use crate::error::RenderError;

/// What can go wrong in a distributed render.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DistributedError {
    /// More ranks than chunks, or no rank: every rank needs at least one chunk.
    #[error("cannot split {chunks} chunks among {ranks} ranks: every rank needs at least one chunk (use fewer ranks or smaller chunks)")]
    Split {
        /// The ranks asked for.
        ranks: usize,
        /// The chunks of the level.
        chunks: usize,
    },
    /// A render option a split render cannot honour exactly.
    #[error("distributed rendering does not support {0}")]
    Unsupported(String),
    /// A message that could not be sent or received, or of the wrong size.
    #[error("message passing: {0}")]
    Exchange(String),
    /// The region's render failed.
    #[error("{0}")]
    Render(#[from] RenderError),
}
