//! Typed errors of the data model.
use thiserror::Error;

/// Errors raised when building or validating data-model objects.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// Grid dimensions that are zero, negative or whose product overflows.
    #[error("invalid dimensions {dims:?}: {reason}")]
    InvalidDims {
        /// The offending dimensions (as given).
        dims: [i64; 3],
        /// Why they are invalid.
        reason: String,
    },
    /// Spacing or origin a grid cannot be placed with: subnormal or absurd spacing, an
    /// origin or far corner beyond the coordinates Volux handles, spacing lost beside the
    /// origin.
    #[error("invalid grid geometry: {0}")]
    InvalidGeometry(String),
    /// Spacing that is not finite and positive.
    #[error("invalid spacing {0:?}: must be finite and > 0")]
    InvalidSpacing([f64; 3]),
    /// The number of values does not match the dimensions.
    #[error("size mismatch: expected {expected} values, found {actual}")]
    SizeMismatch {
        /// Values the dimensions ask for.
        expected: u64,
        /// Values present.
        actual: u64,
    },
    /// Shared memory ([`crate::samples::Buffer::shared`]) not aligned for its scalar type.
    #[error("memory at {address:#x} is not aligned to {alignment} bytes for its values")]
    Unaligned {
        /// The first byte's address.
        address: usize,
        /// The alignment the values need.
        alignment: usize,
    },
    /// A grid (a mask, labels) that does not lie on another grid's lattice.
    #[error("{what} {other}, the volume's {grid}")]
    GeometryMismatch {
        /// The property that differs: "dims", "spacing", "origin", "direction", "unit".
        what: &'static str,
        /// The volume's value.
        grid: String,
        /// The other grid's value.
        other: String,
    },
    /// A request for more memory than this machine can hold.
    #[error("{what} needs {bytes} bytes, more than the {limit} bytes this machine can hold")]
    TooLarge {
        /// What would be allocated.
        what: String,
        /// Bytes requested.
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// A structure that would take more memory than the process's budget
    /// ([`crate::limits::memory_budget`]).
    #[error(
        "{what} needs {}, over the memory budget of {}",
        crate::units::format_bytes_apart(*bytes, *budget).0,
        crate::units::format_bytes_apart(*bytes, *budget).1
    )]
    OverBudget {
        /// What would be allocated ("the gradient volume").
        what: String,
        /// Bytes it needs (`u64::MAX` when the size overflows).
        bytes: u64,
        /// The budget, in bytes.
        budget: u64,
    },
    /// A memory budget that cannot be set (zero, or set twice).
    #[error("memory budget: {0}")]
    MemoryBudget(String),
    /// A tetrahedral mesh that cannot be used.
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A transfer function that cannot be used.
    #[error("invalid transfer function: {0}")]
    InvalidTransferFunction(String),
    /// A transfer function from another program ([`crate::transfer_import`]) that cannot be
    /// read: `format` names the program's format, `field` the field or line at fault.
    #[error("{format} transfer function: {field}: {reason}")]
    TfImport {
        /// The format ("ParaView preset", "Slicer .vp").
        format: &'static str,
        /// The field or line at fault (`RGBPoints[7]`, `line 7 (scalar opacity)`).
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A volume asked for along an axis beyond x, y, z (a timepoint, a component) that the
    /// file does not hold.
    #[error("{option} {index} does not exist: the file holds {len} ({})", if *len == 0 { "none".to_string() } else { format!("0 to {}", len - 1) })]
    NoSuchVolume {
        /// The reader option: `"timepoint"` or `"component"`.
        option: &'static str,
        /// The index asked for.
        index: usize,
        /// How many there are.
        len: usize,
    },
    /// A camera that cannot be used.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// A clipping plane with a zero or non-finite normal or a non-finite offset.
    #[error("invalid clip plane {0}")]
    InvalidClipPlane(String),
    /// A sweep of slices with a step that is not positive or gives too many slices.
    #[error("invalid sweep: {0}")]
    InvalidSweep(String),
    /// A volume of interest that would enclose no volume (a cut removing everything, or
    /// leaving only a face, an edge or a point; a flat starting box).
    #[error("empty volume of interest: {0}")]
    EmptyVolumeOfInterest(String),
    /// A sculpting tool given unusable input (a non-positive radius, no points, label 0).
    #[error("invalid sculpting input: {0}")]
    InvalidSculpt(String),
    /// A chunked (bricked) volume that cannot be used: a bad layout, a chunk outside the
    /// grid, a chunk that cannot be read or decoded (the message names it).
    #[error("chunked volume: {0}")]
    Chunked(String),
    /// Heat-map arguments that cannot be used (e.g. a scale maximum that is not > 0).
    #[error("invalid heat map: {0}")]
    InvalidHeatMap(String),
    /// An unknown preset or generator name.
    #[error("unknown {kind} '{name}' (known: {known})")]
    UnknownName {
        /// What kind of name.
        kind: &'static str,
        /// The name given.
        name: String,
        /// The accepted names.
        known: String,
    },
    /// JSON that does not parse or does not match the schema.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// An operating-system I/O error.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// PNG encoding failed.
    #[error("PNG encoding: {0}")]
    Png(String),
}

/// Result alias of the data model.
pub type Result<T, E = Error> = std::result::Result<T, E>;
