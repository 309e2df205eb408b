//! One level of a store read whole into an in-core [`Grid`], within the memory budget.
use std::path::Path;

use rayon::prelude::*;
use volux_core::bricked::ChunkSource;
use volux_core::grid::{Grid, Samples};

use super::pyramid::Elem;
use super::read::open_store;
use super::store::ZarrOptions;
use crate::error::{ErrorKind, ReadError, Result};

/// Copies the chunks of one layer of chunks (fixed z chunk index) into `out`.
fn fill<T: Elem>(
    source: &dyn ChunkSource,
    out: &mut [T],
    chunks: Vec<([usize; 3], Samples)>,
) -> volux_core::Result<()> {
    let layout = source.layout();
    let d = layout.dims;
    for (c, s) in chunks {
        let (lo, size) = layout.chunk_extent(c);
        let v = T::slice(&s).ok_or_else(|| {
            volux_core::Error::Chunked(format!("chunk {c:?} has samples of another type"))
        })?;
        for k in 0..size[2] {
            for j in 0..size[1] {
                let src = size[0] * (j + size[1] * k);
                let dst = lo[0] + d[0] * (lo[1] + j + d[1] * (lo[2] + k));
                out[dst..dst + size[0]].copy_from_slice(&v[src..src + size[0]]);
            }
        }
    }
    Ok(())
}

fn read_all<T: Elem>(source: &dyn ChunkSource) -> volux_core::Result<Samples> {
    let layout = source.layout();
    let mut out = vec![T::default(); layout.dims.iter().product()];
    let n = layout.chunks_per_axis();
    // One layer of chunks at a time: memory beyond the grid stays one layer.
    for kz in 0..n[2] {
        let chunks = (0..n[0] * n[1])
            .into_par_iter()
            .map(|i| {
                let c = [i % n[0], i / n[0], kz];
                source.read_chunk(c).map(|s| (c, s))
            })
            .collect::<volux_core::Result<Vec<_>>>()?;
        fill::<T>(source, &mut out, chunks)?;
    }
    Ok(T::samples(out))
}

/// Reads level `opts.level` of the store at `path` into an in-core grid. A level larger than
/// the memory budget ([`volux_core::limits`]) is refused before anything is read, with an
/// error naming `--level` and the bricked renderer; a corrupt or truncated chunk is an error
/// naming the chunk.
pub fn load_level(path: &Path, opts: &ZarrOptions) -> Result<Grid> {
    let store = open_store(path, opts)?;
    let levels = store.multiscale.levels();
    let Some(level) = levels.get(opts.level) else {
        return Err(ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "level {} does not exist: the store has {} levels (0 to {})",
                opts.level,
                levels.len(),
                levels.len() - 1
            )),
        ));
    };
    let layout = level.layout().clone();
    let count = volux_core::limits::count_of(&layout.dims);
    if let Err(e) = volux_core::limits::check_alloc("level", count, layout.scalar.size() as u64) {
        let coarser = levels
            .iter()
            .position(|l| {
                volux_core::limits::count_of(&l.layout().dims)
                    .saturating_mul(l.layout().scalar.size() as u64)
                    <= volux_core::limits::memory_budget()
            })
            .map(|i| format!("level {i} fits"))
            .unwrap_or_else(|| "no level fits".into());
        return Err(ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "level {} ({} x {} x {} samples) is larger than the memory budget ({e}); \
                 choose a coarser level ({coarser}) or render the store with \
                 the bricked (out-of-core) renderer",
                opts.level, layout.dims[0], layout.dims[1], layout.dims[2]
            )),
        ));
    }
    let src: &dyn ChunkSource = level.as_ref();
    let samples = match layout.scalar {
        volux_core::grid::ScalarType::U8 => read_all::<u8>(src),
        volux_core::grid::ScalarType::U16 => read_all::<u16>(src),
        volux_core::grid::ScalarType::I16 => read_all::<i16>(src),
        volux_core::grid::ScalarType::F32 => read_all::<f32>(src),
        other => Err(volux_core::Error::Chunked(format!(
            "samples of type {} cannot be loaded",
            other.name()
        ))),
    }
    .map_err(|e| ReadError::new(path, e))?;
    let mut grid = Grid::new(layout.dims, layout.spacing, layout.origin, samples)
        .map_err(|e| ReadError::new(path, e))?;
    if levels.len() > 1 {
        grid = grid.with_note(format!(
            "OME-Zarr level {} of {} ({})",
            opts.level,
            levels.len(),
            store.paths[opts.level]
        ));
    }
    if store.units.iter().any(Option::is_some) {
        grid = grid.with_note(format!(
            "spacing and origin in the store's units ({})",
            store.unit_words()
        ));
    }
    // One known length unit on every spatial axis: measurements and writers carry it.
    let symbols: Vec<_> = store
        .units
        .iter()
        .flatten()
        .map(|u| volux_core::units::length_symbol(u))
        .collect();
    if let [Some(first), rest @ ..] = symbols.as_slice() {
        if rest.iter().all(|s| s == &Some(*first)) {
            grid = grid.with_unit(first);
        }
    }
    for n in &store.notes {
        grid = grid.with_note(n.clone());
    }
    Ok(grid)
}
