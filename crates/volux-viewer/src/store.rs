//! OME-Zarr stores in the viewer (issue 19): a store is opened as a bricked volume
//! ([`Volume::Bricked`]) read chunk by chunk within the brick-cache budget ([`cache_budget`]:
//! `--memory-budget`, else a quarter of RAM as the CLI's,
//! [`volux_core::limits::memory_budget`]), never its full level at once; the
//! render thread refines it level by level ([`crate::progressive`]). The slice views cut a
//! coarse level read whole (at most [`SLICE_SAMPLES`] samples), which the panel notes.
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use volux_app::session::DatasetRef;
use volux_core::bricked::ChunkSource;
use volux_core::grid::{Buffer, Grid, Samples, Scalar};
use volux_core::units::format_bytes;
use volux_render::bricked::{BrickedVolume, Lod};
use volux_render::scene::Volume;

use crate::slices::SliceVolume;

/// The brick caches' budget set by `--memory-budget` (0: not set).
static CACHE_BUDGET: AtomicU64 = AtomicU64::new(0);

/// Sets the memory budget of the stores' brick caches (`volux-view --memory-budget`): the
/// caches only. The frames' images, the slices and every other allocation keep the process's
/// budget ([`volux_core::limits::memory_budget`]), so that a small cache still shows the
/// coarse level first and refines (reading chunks again as it must), instead of refusing
/// the view's image. 0 goes back to the process's budget.
pub fn set_cache_budget(bytes: u64) {
    CACHE_BUDGET.store(bytes, Ordering::Relaxed);
}

/// The stores' brick-cache budget: the one set ([`set_cache_budget`]), else the process's
/// memory budget.
pub fn cache_budget() -> u64 {
    match CACHE_BUDGET.load(Ordering::Relaxed) {
        0 => volux_core::limits::memory_budget(),
        set => set,
    }
}

/// The most samples of the level the slice views cut (128^3: 8 MiB of f32).
pub const SLICE_SAMPLES: usize = 1 << 21;

/// A store opened for the viewer.
pub struct OpenedStore {
    /// The bricked volume (automatic level).
    pub volume: Volume,
    /// What the slice views cut.
    pub slices: SliceVolume,
    /// The store's notes, the budget and the slices' level, for the panel.
    pub notes: Vec<String>,
}

/// Opens the store of `source` as a bricked volume within `budget` bytes. Errors (missing
/// metadata, a chunk that cannot be read) are one line naming the store.
pub fn open(source: &DatasetRef, budget: u64) -> Result<OpenedStore, String> {
    let shown = source.path.display().to_string();
    let store = volux_app::store::open_store(source, budget).map_err(|e| e.to_string())?;
    let bricked = store.volume;
    let (slices, slice_level) = coarse_slices(&bricked).map_err(|e| format!("{shown}: {e}"))?;
    let full = bricked.multiscale().full().layout().clone();
    let [x, y, z] = full.dims;
    let mut notes = store.notes;
    notes.push(format!(
        "out of core: {} levels, full level {x}x{y}x{z} ({}), memory budget {}",
        bricked.levels(),
        format_bytes(u64::try_from(full.bytes()).unwrap_or(u64::MAX)),
        format_bytes(budget)
    ));
    let [sx, sy, sz] = slices.dims();
    notes.push(format!(
        "slices: level {slice_level} ({sx}x{sy}x{sz}) read whole; the 3D view refines to full resolution"
    ));
    Ok(OpenedStore {
        volume: Volume::Bricked(bricked, Lod::Auto),
        slices,
        notes,
    })
}

/// The slice volume of the finest level with at most [`SLICE_SAMPLES`] samples (the
/// coarsest when none is that small), read chunk by chunk, and its level.
pub fn coarse_slices(volume: &BrickedVolume) -> Result<(SliceVolume, usize), String> {
    let levels = volume.multiscale().levels();
    let small = |l: &Arc<dyn ChunkSource>| l.layout().dims.iter().product::<usize>();
    let index = levels
        .iter()
        .position(|l| small(l) <= SLICE_SAMPLES)
        .unwrap_or(levels.len().saturating_sub(1));
    let level = levels.get(index).ok_or("the store has no level")?;
    let grid = read_level(level.as_ref())?;
    Ok((SliceVolume::of_grid(Arc::new(grid)), index))
}

/// A whole level as an f32 grid (small levels only: the caller bounds the size).
fn read_level(level: &dyn ChunkSource) -> Result<Grid, String> {
    let layout = level.layout();
    let [nx, ny, _] = layout.dims;
    let count = layout.dims.iter().product::<usize>();
    volux_core::limits::check_alloc("the slices' level", count as u64, 4)
        .map_err(|e| e.to_string())?;
    let mut values = vec![0f32; count];
    for i in 0..layout.chunk_count() {
        let c = layout.chunk_coords(i);
        let (lo, size) = layout.checked_extent(c).map_err(|e| e.to_string())?;
        let samples = level.read_chunk(c).map_err(|e| e.to_string())?;
        let chunk: Vec<f32> =
            volux_core::with_samples!(&samples, |v| v.iter().map(|x| x.to_f32()).collect());
        if chunk.len() != size.iter().product::<usize>() {
            return Err(format!(
                "chunk {c:?} holds {} samples, not the {} of its extent",
                chunk.len(),
                size.iter().product::<usize>()
            ));
        }
        for k in 0..size[2] {
            for j in 0..size[1] {
                let src = (k * size[1] + j) * size[0];
                let dst = ((lo[2] + k) * ny + lo[1] + j) * nx + lo[0];
                values[dst..dst + size[0]].copy_from_slice(&chunk[src..src + size[0]]);
            }
        }
    }
    Grid::new(
        layout.dims,
        layout.spacing,
        layout.origin,
        Samples::F32(Buffer::owned(values)),
    )
    .map_err(|e| e.to_string())
}

/// Why `--lod` cannot apply to `volume` (a level past the store's last, or a level asked of
/// data read whole), or `None`.
pub fn lod_refusal(volume: &Volume, lod: Lod) -> Option<String> {
    let Lod::Level(n) = lod else { return None };
    match volume {
        Volume::Bricked(b, _) if n >= b.levels() => Some(format!(
            "--lod {n}: the store has {} levels, 0 (full resolution) to {}; the automatic \
             level is shown",
            b.levels(),
            b.levels() - 1
        )),
        Volume::Bricked(..) => None,
        _ => Some(format!(
            "--lod {n} applies to OME-Zarr stores rendered out of core; this data is read \
             whole"
        )),
    }
}

/// The volume with `lod` (a bricked volume; other volumes are returned as they are).
pub fn with_lod(volume: &Volume, lod: Lod) -> Volume {
    match volume {
        Volume::Bricked(b, _) => Volume::Bricked(b.clone(), lod),
        v => v.clone(),
    }
}
