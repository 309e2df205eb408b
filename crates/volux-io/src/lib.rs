//! # volux-io
//!
//! Readers and writers for the formats Volux users have. [`load`] picks the reader from the
//! file's magic bytes first and its extension second, and returns a [`Dataset`]: a regular
//! [`Grid`] or a [`TetMesh`]. Every reader checks sizes before allocating, reports truncated or
//! inconsistent files as a [`ReadError`] naming the file, and never panics on bad input.
//!
//! | format | module | crate used |
//! |---|---|---|
//! | raw + JSON sidecar (`.raw`, `.raw.gz`) | [`raw`] | `flate2`, `serde_json` |
//! | NRRD | [`nrrd`] | `flate2` |
//! | MetaImage `.mhd` / `.mha` | [`metaimage`] | `flate2` |
//! | NIfTI-1 `.nii` / `.nii.gz` | [`nifti`] | `nifti` |
//! | DICOM series and multi-frame | [`dicom`] | `dicom-object` |
//! | VTK legacy `.vtk` | [`vtk_legacy`] | |
//! | VTK XML `.vti` / `.vtu` | [`vtk_xml`] | `quick-xml`, `base64`, `flate2` |
//! | PLOT3D xyz + q | [`plot3d`] | |
//! | VolVis SLC `.slc` | [`slc`] | |
//! | OFF tet meshes | [`off`] | `flate2` |
//! | Volux binary tet mesh `.vtet` | [`vtet`] | |
#![deny(missing_docs)]
#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

use volux_core::{Grid, TetMesh};

pub mod cells;
pub mod detect;
pub mod dicom;
pub mod metaimage;
pub mod nifti;
pub mod nrrd;
pub mod off;
pub mod plot3d;
pub mod raw;
pub mod slc;
pub mod util;
pub mod vtet;
pub mod vtk_legacy;
pub mod vtk_xml;

pub use detect::{detect, Format};

/// A loaded dataset.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum Dataset {
    /// A regular grid.
    Grid(Grid),
    /// A tetrahedral mesh.
    Mesh(TetMesh),
}

/// Options that some readers need.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// PLOT3D: which q variable (`density`, `momentum-x|y|z`, `energy`, `velocity-magnitude`,
    /// or an index 0..4). Default: density.
    pub q_variable: Option<String>,
    /// PLOT3D: the q file; default: the xyz file name with `xyz` replaced by `q`.
    pub q_file: Option<PathBuf>,
    /// DICOM: the SeriesInstanceUID to load when a folder holds several (default: the series
    /// with the most slices).
    pub series_uid: Option<String>,
    /// VTK / VTU: the name of the point-data array to use (default: the first scalar array).
    pub array: Option<String>,
}

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct ReadError {
    /// The file (or folder) being read.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: ErrorKind,
}

/// What went wrong while reading.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ErrorKind {
    /// An operating-system error.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The data section is shorter than the header says.
    #[error("truncated: expected {expected} bytes of data, found {found}")]
    Truncated {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// A header or sidecar that cannot be parsed or is inconsistent.
    #[error("malformed header: {0}")]
    Header(String),
    /// A valid file using a feature Volux does not read.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// Neither the magic bytes nor the extension name a known format.
    #[error("unknown format (neither the magic bytes nor the extension are recognised)")]
    UnknownFormat,
    /// The data model rejected what was read (dims, sizes, mesh validity, memory).
    #[error("{0}")]
    Data(#[from] volux_core::Error),
    /// Data that is syntactically readable but wrong (e.g. inconsistent DICOM slices).
    #[error("{0}")]
    Invalid(String),
}

impl ReadError {
    /// A read error for `path`.
    pub fn new(path: impl AsRef<Path>, kind: impl Into<ErrorKind>) -> Self {
        Self {
            path: path.as_ref().to_path_buf(),
            kind: kind.into(),
        }
    }
}

/// Result of the readers.
pub type Result<T, E = ReadError> = std::result::Result<T, E>;

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file being written.
    pub path: PathBuf,
    /// What went wrong.
    #[source]
    pub source: volux_core::Error,
}

/// Loads any supported file or DICOM folder.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<(Dataset, Format)> {
    let format = detect(path)?;
    let dataset = match format {
        Format::RawJson => Dataset::Grid(raw::read(path)?),
        Format::Nrrd => Dataset::Grid(nrrd::read(path)?),
        Format::MetaImage => Dataset::Grid(metaimage::read(path)?),
        Format::Nifti => Dataset::Grid(nifti::read(path)?),
        Format::Slc => Dataset::Grid(slc::read(path)?),
        Format::Dicom => Dataset::Grid(dicom::read(path, opts.series_uid.as_deref())?),
        Format::VtkLegacy => vtk_legacy::read(path, opts.array.as_deref())?,
        Format::Vti | Format::Vtu => vtk_xml::read(path, opts.array.as_deref())?,
        Format::Plot3d => Dataset::Mesh(plot3d::read(
            path,
            opts.q_file.as_deref(),
            opts.q_variable.as_deref(),
        )?),
        Format::Off => Dataset::Mesh(off::read(path)?),
        Format::Vtet => Dataset::Mesh(vtet::read(path)?),
    };
    Ok((dataset, format))
}
