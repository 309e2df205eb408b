//! # volux-io
//!
//! Readers and writers for the formats Volux users have. [`load()`](fn@load) picks the reader from the
//! file's magic bytes first and its extension second (a folder by what it holds), and returns a [`Dataset`]: a regular
//! [`Grid`](volux_core::grid::Grid) or a [`TetMesh`](volux_core::mesh::TetMesh). Every reader checks sizes before allocating, reports truncated or
//! inconsistent files as a [`ReadError`] naming the file, and never panics on bad input.
//!
//! | format | module | crate used |
//! |---|---|---|
//! | raw + JSON sidecar (`.raw`, `.raw.gz`) | [`raw`] | `flate2`, `serde_json` |
//! | NRRD (raw, gzip, bzip2, ascii; 4-D time, vector and colour axes) | [`nrrd`] | `flate2`, `bzip2` (pure-Rust backend) |
//! | MetaImage `.mhd` / `.mha` (channels, 4-D) | [`metaimage`] | `flate2` |
//! | NIfTI-1 and NIfTI-2 `.nii` / `.nii.gz`, `.hdr` + `.img` (4-D, 5-D, colour) | [`nifti`] | (hand-written header parser) |
//! | Analyze 7.5 / SPM `.hdr` + `.img` | [`nifti`] ([`nifti::read_analyze`]) | (the NIfTI-1 parser) |
//! | FreeSurfer MGH / MGZ | [`mgh`] | `flate2` |
//! | DICOM series and multi-frame (uncompressed, RLE, JPEG, JPEG 2000) | [`dicom`] | `dicom-object`, `dicom-pixeldata` |
//! | VTK legacy `.vtk` | [`vtk_legacy`] | |
//! | VTK XML `.vti` / `.vtu` | [`vtk_xml`] | `quick-xml`, `base64`, `flate2` |
//! | PLOT3D xyz + q | [`plot3d`] | |
//! | VolVis SLC `.slc` | [`slc`] | |
//! | OFF tet meshes | [`off`] | `flate2` |
//! | Volux binary tet mesh `.vtet` | [`vtet`] | |
//! | OME-Zarr stores (`*.ome.zarr`, NGFF 0.4/0.5, read and written; feature `zarr`) | `omezarr` | `zarrs` |
//! | TIFF stacks, ImageJ hyperstacks, OME-TIFF, folders of TIFF slices | [`tiff`](mod@tiff) | `tiff`, `quick-xml` |
//!
//! The other modules: [`load`](mod@load) (the entry point), [`detect`](mod@detect) (format
//! detection), [`dataset`] (what readers return), [`error`] (typed errors), [`cells`] (the VTK
//! cell types shared by the legacy and XML readers), [`util`] (bounded reads and header
//! errors), [`progress`] (a load's progress and cancellation, for front ends with a bar).
//! Files holding several volumes (a time series, vector components, colour channels) are read
//! one 3-D volume at a time, the one a [`VolumeChoice`] names; the grid records the axis it was
//! chosen along ([`volux_core::volume_axes::ExtraAxis`]). `.mnc` files are refused by name
//! (MINC-2 is HDF5: the `hdf5` crates need the HDF5 C library, built with cmake, and the
//! pure-Rust readers are young; MINC-1 is netCDF).
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod cells;
pub mod dataset;
pub mod detect;
pub mod dicom;
pub mod error;
pub mod load;
pub mod metaimage;
pub mod mgh;
pub mod nifti;
pub mod nrrd;
pub mod off;
#[cfg(feature = "zarr")]
pub mod omezarr;
pub mod plot3d;
pub mod progress;
pub mod raw;
pub mod slc;
pub mod tiff;
pub mod util;
mod volumes;
pub mod vtet;
pub mod vtk_legacy;
pub mod vtk_xml;

pub use dataset::{Dataset, LoadOptions, VolumeChoice};
pub use detect::{detect, Format};
pub use error::{ErrorKind, ReadError, Result, WriteError};
pub use load::{load, peek_dims};
