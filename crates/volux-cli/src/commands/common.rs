//! What every command shares: the error type, and loading a file with a spinner.
use std::path::Path;

use volux_io::{Dataset, Format};

use crate::cli::LoadArgs;
use crate::progress;

/// An error of a command: one readable line.
pub type CmdError = Box<dyn std::error::Error + Send + Sync>;

/// Loads a file with a spinner.
pub fn load(path: &Path, args: &LoadArgs, show: bool) -> Result<(Dataset, Format), CmdError> {
    let pb = progress::spinner(show, format!("loading {}", path.display()));
    let out = volux_io::load(path, &args.dataset(path).load_options());
    pb.finish_and_clear();
    let (data, format) = out?;
    check_reader_options(args, format)?;
    Ok((data, format))
}

/// The reader options apply to one format each: given for another, they are refused.
fn check_reader_options(args: &LoadArgs, format: Format) -> Result<(), CmdError> {
    let vtk = matches!(format, Format::VtkLegacy | Format::Vti | Format::Vtu);
    let zarr = format == Format::OmeZarr;
    let stack = zarr || format == Format::Tiff;
    // Formats that can hold several volumes (a 4th axis) or several values per voxel.
    let volumes = stack
        || matches!(
            format,
            Format::Nifti
                | Format::Analyze
                | Format::Mgh
                | Format::Nrrd
                | Format::MetaImage
                | Format::Dicom
        );
    // Of those, the formats with vector components or colour channels (not MGH: its frames
    // are volumes).
    let components = volumes && !zarr && format != Format::Mgh;
    let misplaced = [
        (
            "q-variable",
            args.q_variable.is_some(),
            format == Format::Plot3d,
            "PLOT3D",
        ),
        (
            "q-file",
            args.q_file.is_some(),
            format == Format::Plot3d,
            "PLOT3D",
        ),
        (
            "series",
            args.series.is_some(),
            format == Format::Dicom,
            "DICOM",
        ),
        (
            "array",
            args.array.is_some(),
            vtk || zarr,
            "VTK and OME-Zarr",
        ),
        ("level", args.level.is_some(), zarr, "OME-Zarr"),
        (
            "channel",
            args.channel.is_some(),
            stack,
            "OME-Zarr and TIFF",
        ),
        (
            "timepoint",
            args.timepoint.is_some(),
            volumes,
            "files holding several volumes (NIfTI, Analyze, MGH, NRRD, MetaImage, DICOM, OME-Zarr, \
             TIFF)",
        ),
        (
            "component",
            args.component.is_some(),
            components,
            "vector and colour volumes (NIfTI, Analyze, NRRD, MetaImage, DICOM, TIFF)",
        ),
    ];
    match misplaced.iter().find(|(_, given, fits, _)| *given && !fits) {
        Some((flag, _, _, owner)) => Err(format!(
            "--{flag} applies to {owner} files; this one is {}",
            format.name()
        )
        .into()),
        None => Ok(()),
    }
}
