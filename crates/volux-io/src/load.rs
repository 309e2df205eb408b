//! [`load`]: any supported file, DICOM or TIFF folder, the reader chosen by [`detect`].
use std::path::Path;

use crate::dataset::{Dataset, LoadOptions};
use crate::detect::{detect, Format};
use crate::error::Result;
use crate::{dicom, metaimage, nifti, nrrd, off, plot3d, raw, slc, vtet, vtk_legacy, vtk_xml};

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
        Format::OmeZarr => Dataset::Grid(load_zarr(path, opts)?),
        Format::Tiff => Dataset::Grid(crate::tiff::read(path, opts.channel, opts.timepoint)?),
    };
    Ok((dataset, format))
}

/// One level of an OME-Zarr store as an in-core grid.
#[cfg(feature = "zarr")]
fn load_zarr(path: &Path, opts: &LoadOptions) -> Result<volux_core::grid::Grid> {
    crate::omezarr::load_level(
        path,
        &crate::omezarr::ZarrOptions {
            array: opts.array.clone(),
            level: opts.level.unwrap_or(0),
            channel: opts.channel,
            timepoint: opts.timepoint,
        },
    )
}

/// Without the `zarr` feature, stores are refused.
#[cfg(not(feature = "zarr"))]
fn load_zarr(path: &Path, _opts: &LoadOptions) -> Result<volux_core::grid::Grid> {
    Err(crate::error::ReadError::new(
        path,
        crate::error::ErrorKind::Unsupported(
            "OME-Zarr stores (this build lacks the `zarr` feature of volux-io)".into(),
        ),
    ))
}
