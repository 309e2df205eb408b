//! What the readers return: a [`Dataset`], and the options some readers need.
use std::path::PathBuf;

use volux_core::grid::Grid;
use volux_core::mesh::TetMesh;

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
    /// OME-Zarr: the path inside the store of the image to read (default: the root).
    pub array: Option<String>,
    /// OME-Zarr: the pyramid level to load (default 0, full resolution).
    pub level: Option<usize>,
    /// OME-Zarr, ImageJ hyperstacks, OME-TIFF: the channel index (default 0).
    pub channel: usize,
    /// Files holding several volumes: which one along their time or volume axis (fMRI and
    /// perfusion time series, DWI b-values, the stacks of a DICOM series at the same
    /// positions, OME-Zarr and TIFF timepoints); default 0. An index past the axis is
    /// [`volux_core::Error::NoSuchVolume`].
    pub timepoint: usize,
    /// Files with several values per voxel (NIfTI and NRRD vectors, colour images): the one
    /// to read as the scalar. `None`: the first component of a vector, and for colour images
    /// the colour itself (its luminance as the scalar, [`volux_core::color`]).
    pub component: Option<usize>,
}

/// Which volume of a file holding several to read: the part of [`LoadOptions`] that the
/// readers of 4-D, vector and colour data share.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VolumeChoice {
    /// The index along the file's time or volume axis ([`LoadOptions::timepoint`]).
    pub timepoint: usize,
    /// The component read as the scalar ([`LoadOptions::component`]); `None`: the first of a
    /// vector, and the colour of a colour image.
    pub component: Option<usize>,
}

impl LoadOptions {
    /// The timepoint and component asked for.
    pub fn choice(&self) -> VolumeChoice {
        VolumeChoice {
            timepoint: self.timepoint,
            component: self.component,
        }
    }
}
