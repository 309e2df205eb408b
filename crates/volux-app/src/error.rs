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
    /// A file that cannot be read.
    #[error(transparent)]
    Read(volux_io::ReadError),
    /// A reader option given for a file of a format it does not apply to.
    #[error("{} applies to {} files; this one is {}", option.word(), option.owners(), format.name())]
    MisplacedOption {
        /// The option.
        option: crate::reader_option::ReaderOption,
        /// The file's format.
        format: volux_io::Format,
    },
    /// A level of detail asked for a file that is not a store (read whole).
    #[error("the level of detail {} applies to OME-Zarr stores, rendered out of core level by level; {} is {}, read whole", crate::words::level_word(*lod), path.display(), format.map_or("not a store".to_string(), |f| format!("a {} file", f.name())))]
    LodOnFile {
        /// The level of detail asked for.
        lod: volux_render::bricked::Lod,
        /// The file.
        path: std::path::PathBuf,
        /// Its format, when it has one Volux reads.
        format: Option<volux_io::Format>,
    },
    /// A transfer-function file that cannot be read.
    #[error("{}: {reason}", path.display())]
    TfFile {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
    /// A layer weight of a layered transfer function that is not finite and >= 0.
    #[error("the weight {weight} of the layer {layer} must be >= 0")]
    LayerWeight {
        /// The layer (preset or file).
        layer: String,
        /// The weight.
        weight: f64,
    },
    /// A grid integrator asked for where only the mesh rules apply, or the reverse.
    #[error("the integrator {integrator} applies to tetrahedral meshes (ray casting)")]
    MeshOnlyIntegrator {
        /// The integrator's name.
        integrator: String,
    },
    /// Colouring RGB voxels by the transfer function asked for a volume of one value per
    /// voxel.
    #[error("colouring by the transfer function applies to RGB volumes, and this volume has one value per voxel")]
    NotRgb,
    /// The engine's error.
    #[error(transparent)]
    Render(#[from] RenderError),
}
