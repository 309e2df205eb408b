//! A dataset opened as the volume to render, the same way in every front end: a file or a
//! DICOM folder read whole, or an OME-Zarr store rendered out of core (seed `003`) when a
//! level of detail is asked for or its full level is over the memory budget. The reader
//! options that belong to other formats are refused by name ([`ReaderOption`]), and a grid
//! is split into tetrahedra when the dataset asks for it (for the mesh methods).
use volux_io::{Dataset, Format};
use volux_render::bricked::Lod;
use volux_render::scene::Volume;

use crate::error::AppError;
pub use crate::reader_option::ReaderOption;
use crate::session::DatasetRef;

/// Refuses the first reader option of `dataset` that does not apply to its `format`.
pub fn check_reader_options(dataset: &DatasetRef, format: Format) -> Result<(), AppError> {
    let given = [
        (ReaderOption::QVariable, dataset.q_variable.is_some()),
        (ReaderOption::QFile, dataset.q_file.is_some()),
        (ReaderOption::Series, dataset.series_uid.is_some()),
        (ReaderOption::Array, dataset.array.is_some()),
        (ReaderOption::Level, dataset.level.is_some()),
        (ReaderOption::Channel, dataset.channel.is_some()),
        (ReaderOption::Timepoint, dataset.timepoint.is_some()),
        (ReaderOption::Component, dataset.component.is_some()),
    ];
    match given
        .into_iter()
        .find(|(option, is_given)| *is_given && !option.applies_to(format))
    {
        Some((option, _)) => Err(AppError::MisplacedOption { option, format }),
        None => Ok(()),
    }
}

/// How a dataset is opened besides its reader options.
#[derive(Clone, Copy, Debug)]
pub struct OpenRequest {
    /// A level of detail rendered out of core (stores only); `None`: out of core only when
    /// the full level is over `budget`.
    pub lod: Option<Lod>,
    /// The memory budget in bytes ([`volux_core::limits::memory_budget`]): a store whose full
    /// level is larger is rendered out of core, its brick caches sharing the budget.
    pub budget: u64,
}

impl Default for OpenRequest {
    fn default() -> Self {
        Self {
            lod: None,
            budget: volux_core::limits::memory_budget(),
        }
    }
}

/// A dataset opened as a volume.
pub struct OpenedVolume {
    /// The volume (a grid, a mesh, a grid split into tetrahedra, a bricked store).
    pub volume: Volume,
    /// The file's format.
    pub format: Format,
    /// Whether the file held a grid read whole (split into tetrahedra or not).
    pub loaded_grid: bool,
    /// What a user should know: the store's notes (its statistics), the reader's notes on
    /// the data (non-finite values replaced, axes read), in that order.
    pub notes: Vec<String>,
}

/// Whether `dataset` is a store that `request` renders out of core (its level of detail):
/// `None` for a file read whole. Refuses a level of detail for anything but a store.
pub fn out_of_core_lod(
    dataset: &DatasetRef,
    request: &OpenRequest,
) -> Result<Option<Lod>, AppError> {
    let path = &dataset.path;
    let format = volux_io::detect(path).ok();
    if let (Some(lod), false) = (request.lod, format == Some(Format::OmeZarr)) {
        return Err(AppError::LodOnFile {
            lod,
            path: path.clone(),
            format,
        });
    }
    if format != Some(Format::OmeZarr) || dataset.level.is_some() {
        return Ok(None);
    }
    let ms = volux_io::omezarr::open_multiscale(path, &crate::store::zarr_options(dataset))
        .map_err(|e| AppError::Store {
            path: path.clone(),
            reason: e.to_string(),
        })?;
    let over = ms.full().layout().bytes() > u128::from(request.budget);
    Ok(request.lod.or(over.then_some(Lod::Auto)))
}

/// Opens `dataset`: a store out of core ([`out_of_core_lod`]), anything else read whole
/// ([`volux_io::load()`]) with its reader options checked against its format, a grid split
/// into tetrahedra when `dataset.as_tets` (refused before reading when the mesh would be
/// too large).
pub fn open_volume(dataset: &DatasetRef, request: &OpenRequest) -> Result<OpenedVolume, AppError> {
    if let Some(lod) = out_of_core_lod(dataset, request)? {
        let store = crate::store::open_store(dataset, request.budget)?;
        crate::store::check_level(&dataset.path, &store.volume, lod)?;
        return Ok(OpenedVolume {
            volume: Volume::Bricked(store.volume, lod),
            format: Format::OmeZarr,
            loaded_grid: false,
            notes: store.notes,
        });
    }
    if dataset.as_tets {
        if let Some(dims) = volux_io::peek_dims(&dataset.path) {
            volux_core::limits::check_alloc(
                "the tetrahedral mesh of the grid",
                volux_core::tetrahedralize::grid_mesh_bytes(dims),
                1,
            )
            .map_err(volux_render::RenderError::from)?;
        }
    }
    let (data, format) =
        volux_io::load(&dataset.path, &dataset.load_options()).map_err(AppError::Read)?;
    check_reader_options(dataset, format)?;
    let (volume, loaded_grid, notes) = match data {
        Dataset::Grid(g) => {
            let notes = g.notes().to_vec();
            (Volume::from(g), true, notes)
        }
        Dataset::Mesh(m) => (Volume::from(m), false, Vec::new()),
        _ => {
            return Err(AppError::Read(volux_io::ReadError {
                path: dataset.path.clone(),
                kind: volux_io::ErrorKind::Unsupported("a dataset of another kind".into()),
            }))
        }
    };
    let volume = if dataset.as_tets && loaded_grid {
        volume.to_tets()?
    } else {
        volume
    };
    Ok(OpenedVolume {
        volume,
        format,
        loaded_grid,
        notes,
    })
}
