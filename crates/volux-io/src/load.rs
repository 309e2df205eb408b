//! [`load`]: any supported file, DICOM or TIFF folder, the reader chosen by [`detect`].
use std::path::Path;

use crate::dataset::{Dataset, LoadOptions};
use crate::detect::{detect, Format};
use crate::error::Result;
use crate::{dicom, metaimage, mgh, nifti, nrrd, off, plot3d, raw, slc, vtet, vtk_legacy, vtk_xml};

/// Loads any supported file or DICOM folder.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<(Dataset, Format)> {
    let format = detect(path)?;
    let dataset = match format {
        Format::RawJson => Dataset::Grid(raw::read(path)?),
        Format::Nrrd => Dataset::Grid(nrrd::read(path, opts.choice())?),
        Format::MetaImage => Dataset::Grid(metaimage::read(path, opts.choice())?),
        Format::Nifti => Dataset::Grid(nifti::read(path, opts.choice())?),
        Format::Analyze => Dataset::Grid(nifti::read_analyze(path, opts.choice())?),
        Format::Mgh => Dataset::Grid(mgh::read(path, opts.choice())?),
        Format::Slc => Dataset::Grid(slc::read(path)?),
        Format::Dicom => Dataset::Grid(dicom::read(
            path,
            opts.series_uid.as_deref(),
            opts.choice(),
        )?),
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
        Format::Tiff => Dataset::Grid(crate::tiff::read(path, opts.channel, opts.choice())?),
    };
    if format != Format::OmeZarr {
        check_chosen(path, &dataset, opts)?;
    }
    Ok((dataset, format))
}

/// The dims of the grid `path` holds, read from its header alone when its format has a
/// cheap one (raw + JSON sidecar); `None` when it would take reading the file. Front ends use
/// it to refuse, before loading gigabytes, what a grid of that size cannot become.
pub fn peek_dims(path: &Path) -> Option<[usize; 3]> {
    match detect(path).ok()? {
        Format::RawJson => raw::dims(path).ok(),
        _ => None,
    }
}

/// A timepoint, component or channel asked for must be the one the reader chose: a reader
/// that found no such axis in the file leaves no record of it, and the request is then an
/// error rather than silently ignored (the file holds one volume, one value per voxel, or one
/// channel).
fn check_chosen(path: &Path, dataset: &Dataset, opts: &LoadOptions) -> Result<()> {
    let axes = match dataset {
        Dataset::Grid(g) => g.extra_axes(),
        _ => &[],
    };
    let asked = [
        ("timepoint", (opts.timepoint > 0).then_some(opts.timepoint)),
        ("component", opts.component.filter(|&c| c > 0)),
        ("channel", (opts.channel > 0).then_some(opts.channel)),
    ];
    for (option, index) in asked {
        let Some(index) = index else { continue };
        let axis = axes.iter().find(|a| a.kind.option() == option);
        if axis.and_then(|a| a.chosen) != Some(index) {
            let len = axis.map_or(1, |a| a.len);
            return Err(crate::error::ReadError::new(
                path,
                volux_core::Error::NoSuchVolume { option, index, len },
            ));
        }
    }
    Ok(())
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
