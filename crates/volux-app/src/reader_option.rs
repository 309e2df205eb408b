//! The reader options of a [`crate::session::DatasetRef`] as names, and the formats each
//! applies to ([`crate::open::check_reader_options`] refuses the others).
use volux_io::Format;

/// A reader option of a [`crate::session::DatasetRef`], for the errors that name one (each
/// front end names it its own way: `--q-variable` on the command line, `q_variable=` in
/// Python).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReaderOption {
    /// PLOT3D's q variable.
    QVariable,
    /// PLOT3D's q file.
    QFile,
    /// A DICOM series.
    Series,
    /// A VTK point-data array or an OME-Zarr array.
    Array,
    /// An OME-Zarr pyramid level read whole.
    Level,
    /// A channel of a store or a TIFF stack.
    Channel,
    /// A timepoint of a file holding several volumes.
    Timepoint,
    /// A component of a vector or colour volume.
    Component,
    /// A level of detail rendered out of core.
    Lod,
}

impl ReaderOption {
    /// The option's word (`q-variable`, `series`, ...).
    pub fn word(self) -> &'static str {
        match self {
            ReaderOption::QVariable => "q-variable",
            ReaderOption::QFile => "q-file",
            ReaderOption::Series => "series",
            ReaderOption::Array => "array",
            ReaderOption::Level => "level",
            ReaderOption::Channel => "channel",
            ReaderOption::Timepoint => "timepoint",
            ReaderOption::Component => "component",
            ReaderOption::Lod => "lod",
        }
    }

    /// The formats the option applies to, in words.
    pub fn owners(self) -> &'static str {
        match self {
            ReaderOption::QVariable | ReaderOption::QFile => "PLOT3D",
            ReaderOption::Series => "DICOM",
            ReaderOption::Array => "VTK and OME-Zarr",
            ReaderOption::Level | ReaderOption::Lod => "OME-Zarr",
            ReaderOption::Channel => "OME-Zarr and TIFF",
            ReaderOption::Timepoint => {
                "files holding several volumes (NIfTI, Analyze, MGH, NRRD, MetaImage, DICOM, \
                 OME-Zarr, TIFF)"
            }
            ReaderOption::Component => {
                "vector and colour volumes (NIfTI, Analyze, NRRD, MetaImage, DICOM, TIFF)"
            }
        }
    }

    /// Whether the option applies to files of `format`.
    pub fn applies_to(self, format: Format) -> bool {
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
        match self {
            ReaderOption::QVariable | ReaderOption::QFile => format == Format::Plot3d,
            ReaderOption::Series => format == Format::Dicom,
            ReaderOption::Array => vtk || zarr,
            ReaderOption::Level | ReaderOption::Lod => zarr,
            ReaderOption::Channel => stack,
            ReaderOption::Timepoint => volumes,
            // Of those, the formats with vector components or colour channels (not MGH: its
            // frames are volumes).
            ReaderOption::Component => volumes && !zarr && format != Format::Mgh,
        }
    }
}
