//! OME-Zarr stores opened out of core as bricked volumes (seed `003`), the same way in every
//! front end: the store's array, channel and timepoint from the [`DatasetRef`], one memory
//! budget for the brick caches, the pyramid level checked, and the notes a user should read
//! (the reader's, and where the statistics that frame the view and fit the presets come
//! from: [`volux_render::bricked::StoreStatistics`]).
use std::path::PathBuf;
use std::sync::Arc;

use volux_io::omezarr::{self, ZarrOptions};
use volux_render::bricked::{BrickedVolume, Lod};

use crate::error::AppError;
use crate::session::DatasetRef;

/// A store opened as a bricked volume.
pub struct OpenedStore {
    /// The bricked volume (all levels, caches within the budget).
    pub volume: Arc<BrickedVolume>,
    /// What a user should know: the reader's notes on the store's metadata, then the note on
    /// the volume's statistics when they are not simply recorded.
    pub notes: Vec<String>,
}

/// The reader options of `dataset`'s store (its full level).
pub fn zarr_options(dataset: &DatasetRef) -> ZarrOptions {
    ZarrOptions {
        array: dataset.array.clone(),
        level: 0,
        channel: dataset.channel.unwrap_or(0),
        timepoint: dataset.timepoint.unwrap_or(0),
    }
}

/// Opens the store of `dataset` as a bricked volume whose brick caches share `budget`
/// bytes. Errors name the store.
pub fn open_store(dataset: &DatasetRef, budget: u64) -> Result<OpenedStore, AppError> {
    let path = &dataset.path;
    let store = omezarr::open_store(path, &zarr_options(dataset)).map_err(|e| AppError::Store {
        path: path.clone(),
        reason: e.to_string(),
    })?;
    let volume = BrickedVolume::open(store.multiscale, budget).map_err(|e| AppError::Store {
        path: path.clone(),
        reason: e.to_string(),
    })?;
    let mut notes = store.notes;
    notes.extend(volume.statistics().note());
    Ok(OpenedStore {
        volume: Arc::new(volume),
        notes,
    })
}

/// Refuses a level past the volume's last (a level number a user gave); `auto` and the
/// levels that exist pass.
pub fn check_level(
    store: &std::path::Path,
    volume: &BrickedVolume,
    lod: Lod,
) -> Result<(), AppError> {
    match lod {
        Lod::Level(level) if level >= volume.levels() => Err(AppError::NoSuchLevel {
            store: PathBuf::from(store),
            level,
            levels: volume.levels(),
        }),
        _ => Ok(()),
    }
}
