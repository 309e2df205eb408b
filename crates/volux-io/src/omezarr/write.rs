//! Writing: a [`ChunkSource`] streamed into a Zarr v3 + OME-NGFF 0.5 store, chunk by chunk,
//! with its 2x-averaged pyramid and per-chunk value ranges.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;
use serde_json::json;
use volux_core::bricked::{ChunkLayout, ChunkSource};
use volux_core::grid::ScalarType;
use volux_core::histogram::{Histogram, STORED_BINS};
use volux_core::Error;
use zarrs::array::codec::{
    BloscCodec, BloscCompressionLevel, BloscCompressor, BloscShuffleMode, GzipCodec, ZstdCodec,
};
use zarrs::array::{Array, ArrayBuilder, DataType};
use zarrs::array_subset::ArraySubset;
use zarrs::filesystem::FilesystemStore;

use super::pyramid::{halve, range_of, Elem};
use super::store::VOLUX_KEY;
use crate::error::WriteError;

/// How many levels to write.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Levels {
    /// Until a level fits in one chunk.
    #[default]
    Auto,
    /// Exactly this many (at least 1, and no more than halving can make distinct).
    Count(usize),
}

/// The chunks' compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Zarr v3 `zstd` at this level (default 3).
    Zstd(i32),
    /// `blosc` with zstd inside, byte-shuffled, at this level (0-9).
    BloscZstd(u8),
    /// `gzip` at this level (0-9), for readers without zstd.
    Gzip(u32),
    /// No compression.
    None,
}

impl Default for Compression {
    fn default() -> Self {
        Self::Zstd(3)
    }
}

/// What [`write_ome_zarr`] writes.
#[derive(Clone, Debug, Default)]
pub struct WriteOptions {
    /// Levels of the pyramid.
    pub levels: Levels,
    /// Compression of every chunk.
    pub compression: Compression,
    /// The image's name in the metadata.
    pub name: String,
    /// The unit of the spatial axes (`millimeter`, `micrometer`), when known.
    pub unit: Option<String>,
}

fn err(path: &Path, msg: impl Into<String>) -> WriteError {
    WriteError {
        path: path.to_path_buf(),
        source: Error::Chunked(msg.into()),
    }
}

/// The dims of each level: the source's, then halved (rounding up) per level.
pub fn level_dims(
    dims: [usize; 3],
    chunk: [usize; 3],
    levels: Levels,
) -> Result<Vec<[usize; 3]>, String> {
    let mut out = vec![dims];
    let next = |d: [usize; 3]| d.map(|x| x.div_ceil(2));
    match levels {
        Levels::Auto => {
            while (0..3).any(|a| out.last().unwrap_or(&dims)[a] > chunk[a]) {
                let d = next(*out.last().unwrap_or(&dims));
                out.push(d);
            }
        }
        Levels::Count(n) => {
            if n == 0 {
                return Err("a pyramid needs at least 1 level".into());
            }
            while out.len() < n {
                let last = *out.last().unwrap_or(&dims);
                if last == [1, 1, 1] {
                    return Err(format!(
                        "{n} levels are more than halving {dims:?} can make ({} down to one sample)",
                        out.len()
                    ));
                }
                out.push(next(last));
            }
        }
    }
    Ok(out)
}

/// Writes `source` (one level; its chunk shape is the store's) to `out` as an OME-Zarr store
/// (Zarr v3, NGFF 0.5) with a pyramid of 2x averages. Chunks are read, compressed and written
/// in parallel, one chunk per task (memory: a few chunks per thread, never a level); each
/// next level is computed from the level just written, read back by regions. The store is
/// written to a hidden sibling directory renamed to `out` at the end, so an error leaves no
/// partial store. Returns the dims of the levels written.
///
/// Level `k` has spacing `2^k` times the source's and its origin moved by `(2^k - 1) / 2`
/// source samples (the centre of the samples it averages).
pub fn write_ome_zarr(
    source: &dyn ChunkSource,
    out: &Path,
    opts: &WriteOptions,
) -> Result<Vec<[usize; 3]>, WriteError> {
    if out.exists() {
        return Err(err(
            out,
            "already exists; Volux does not overwrite a store (remove it first)",
        ));
    }
    let file_name = out
        .file_name()
        .ok_or_else(|| err(out, "not a directory name"))?
        .to_string_lossy()
        .into_owned();
    let tmp: PathBuf = out.with_file_name(format!(".{file_name}.partial-{}", std::process::id()));
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(|e| WriteError {
            path: tmp.clone(),
            source: e.into(),
        })?;
    }
    std::fs::create_dir_all(&tmp).map_err(|e| WriteError {
        path: tmp.clone(),
        source: e.into(),
    })?;
    let result = match source.layout().scalar {
        ScalarType::U8 => write_typed::<u8>(source, &tmp, opts),
        ScalarType::U16 => write_typed::<u16>(source, &tmp, opts),
        ScalarType::I16 => write_typed::<i16>(source, &tmp, opts),
        ScalarType::F32 => write_typed::<f32>(source, &tmp, opts),
        other => Err(Error::Chunked(format!(
            "samples of type {} cannot be written",
            other.name()
        ))),
    };
    match result {
        Ok(dims) => {
            std::fs::rename(&tmp, out).map_err(|e| {
                let _ = std::fs::remove_dir_all(&tmp);
                WriteError {
                    path: out.to_path_buf(),
                    source: e.into(),
                }
            })?;
            Ok(dims)
        }
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            Err(WriteError {
                path: out.to_path_buf(),
                source: e,
            })
        }
    }
}

fn zarr_err(what: &str) -> impl Fn(&dyn std::fmt::Display) -> Error + '_ {
    move |e| Error::Chunked(format!("{what}: {e}"))
}

fn data_type(s: ScalarType) -> volux_core::Result<DataType> {
    Ok(match s {
        ScalarType::U8 => DataType::UInt8,
        ScalarType::U16 => DataType::UInt16,
        ScalarType::I16 => DataType::Int16,
        ScalarType::F32 => DataType::Float32,
        other => {
            return Err(Error::Chunked(format!(
                "samples of type {} cannot be written",
                other.name()
            )))
        }
    })
}

/// zarr order (z, y, x) of an xyz triple.
/// The counts of the histogram of `source`'s samples (chunked as `layout`) over `range` in
/// [`STORED_BINS`] bins, read chunk by chunk in parallel (the bins of
/// [`Histogram::from_values`], so that they equal those of the data held whole).
fn full_histogram(
    source: &dyn ChunkSource,
    layout: &ChunkLayout,
    range: [f64; 2],
) -> volux_core::Result<Vec<u64>> {
    (0..layout.chunk_count())
        .into_par_iter()
        .map(|i| {
            let s = source.read_chunk(layout.chunk_coords(i))?;
            Ok(
                volux_core::with_samples!(&s, |v| Histogram::from_values(v, range, STORED_BINS))
                    .counts,
            )
        })
        .try_reduce(
            || vec![0; STORED_BINS],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                Ok(a)
            },
        )
}

fn zyx<T: Copy>(v: [T; 3]) -> [T; 3] {
    [v[2], v[1], v[0]]
}

fn write_typed<T: Elem>(
    source: &dyn ChunkSource,
    dir: &Path,
    opts: &WriteOptions,
) -> volux_core::Result<Vec<[usize; 3]>> {
    let l0 = source.layout().clone();
    let chunk = l0.chunk;
    let dims = level_dims(l0.dims, chunk, opts.levels).map_err(Error::Chunked)?;
    let store = Arc::new(FilesystemStore::new(dir).map_err(|e| zarr_err("the store")(&e))?);
    let mut previous: Option<(Array<FilesystemStore>, [usize; 3])> = None;
    let mut datasets = Vec::new();
    for (k, &d) in dims.iter().enumerate() {
        let f = (1u64 << k) as f64;
        let spacing = l0.spacing.map(|s| s * f);
        let origin: [f64; 3] =
            std::array::from_fn(|a| l0.origin[a] + (f - 1.0) / 2.0 * l0.spacing[a]);
        let level_chunk: [usize; 3] = std::array::from_fn(|a| chunk[a].min(d[a]));
        let layout = ChunkLayout::new(d, level_chunk, spacing, origin, l0.scalar)?;
        let mut builder = ArrayBuilder::new(
            zyx(d).map(|x| x as u64).to_vec(),
            zyx(level_chunk).map(|x| x as u64).to_vec(),
            data_type(l0.scalar)?,
            zarrs::array::FillValue::new(vec![0u8; l0.scalar.size()]),
        );
        builder.dimension_names(Some(["z", "y", "x"]));
        match opts.compression {
            Compression::Zstd(level) => {
                builder.bytes_to_bytes_codecs(vec![Arc::new(ZstdCodec::new(level, false))]);
            }
            Compression::BloscZstd(level) => {
                let codec = BloscCodec::new(
                    BloscCompressor::Zstd,
                    BloscCompressionLevel::try_from(level.min(9))
                        .map_err(|e| zarr_err("blosc level")(&e))?,
                    None,
                    BloscShuffleMode::Shuffle,
                    Some(l0.scalar.size()),
                )
                .map_err(|e| zarr_err("blosc")(&e))?;
                builder.bytes_to_bytes_codecs(vec![Arc::new(codec)]);
            }
            Compression::Gzip(level) => {
                let codec = GzipCodec::new(level.min(9)).map_err(|e| zarr_err("gzip")(&e))?;
                builder.bytes_to_bytes_codecs(vec![Arc::new(codec)]);
            }
            Compression::None => {}
        }
        let mut array = builder
            .build(store.clone(), &format!("/{k}"))
            .map_err(|e| zarr_err("the level array")(&e))?;
        let ranges: Vec<[f64; 2]> = (0..layout.chunk_count())
            .into_par_iter()
            .map(|i| {
                let c = layout.chunk_coords(i);
                let (lo, size) = layout.chunk_extent(c);
                let values: Vec<T> = match &previous {
                    None => {
                        let s = source.read_chunk(c)?;
                        let v = T::slice(&s).ok_or_else(|| {
                            Error::Chunked(format!(
                                "chunk {c:?} of the source has another sample type"
                            ))
                        })?;
                        if v.len() != size.iter().product::<usize>() {
                            return Err(Error::Chunked(format!(
                                "chunk {c:?} of the source has {} samples, expected {size:?}",
                                v.len()
                            )));
                        }
                        v.to_vec()
                    }
                    Some((prev, pd)) => {
                        let plo: [usize; 3] = std::array::from_fn(|a| 2 * lo[a]);
                        let phi: [usize; 3] =
                            std::array::from_fn(|a| (2 * (lo[a] + size[a])).min(pd[a]));
                        let ranges: Vec<std::ops::Range<u64>> =
                            (0..3).rev().map(|a| plo[a] as u64..phi[a] as u64).collect();
                        let src: Vec<T> = prev
                            .retrieve_array_subset_elements(&ArraySubset::new_with_ranges(&ranges))
                            .map_err(|e| zarr_err("reading back the previous level")(&e))?;
                        let (v, vd) = halve(&src, std::array::from_fn(|a| phi[a] - plo[a]));
                        debug_assert_eq!(vd, size);
                        v
                    }
                };
                let r = range_of(&values);
                // Zarr chunks are full-size: pad edge chunks with the fill value.
                let full = if size == level_chunk {
                    values
                } else {
                    let mut p = vec![T::default(); level_chunk.iter().product()];
                    for z in 0..size[2] {
                        for y in 0..size[1] {
                            let s = size[0] * (y + size[1] * z);
                            let t = level_chunk[0] * (y + level_chunk[1] * z);
                            p[t..t + size[0]].copy_from_slice(&values[s..s + size[0]]);
                        }
                    }
                    p
                };
                array
                    .store_chunk_elements(&zyx(c).map(|x| x as u64), &full)
                    .map_err(|e| zarr_err(&format!("writing chunk {c:?} of level {k}"))(&e))?;
                Ok(r)
            })
            .collect::<volux_core::Result<Vec<_>>>()?;
        let range = ranges
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |a, r| {
                [a[0].min(r[0]), a[1].max(r[1])]
            });
        let flat: Vec<f64> = ranges.iter().flat_map(|r| *r).collect();
        let mut attrs = json!({"range": range, "chunk_ranges": flat, "downsampling": if k == 0 { "none" } else { "2x mean" }});
        if k == 0 {
            // The full level's histogram over its range, so that a reader fits the
            // transfer-function presets as on the data in memory (one more pass over the
            // source, chunk by chunk).
            attrs["histogram"] = json!(full_histogram(source, &l0, range)?);
        }
        array.attributes_mut().insert(VOLUX_KEY.into(), attrs);
        array
            .store_metadata()
            .map_err(|e| zarr_err("the level metadata")(&e))?;
        datasets.push(json!({
            "path": k.to_string(),
            "coordinateTransformations": [
                {"type": "scale", "scale": zyx(spacing)},
                {"type": "translation", "translation": zyx(origin)},
            ]
        }));
        previous = Some((array, d));
    }
    let mut axes = Vec::new();
    for n in ["z", "y", "x"] {
        let mut a = json!({"name": n, "type": "space"});
        if let Some(u) = &opts.unit {
            a["unit"] = json!(u);
        }
        axes.push(a);
    }
    let mut group = zarrs::group::GroupBuilder::new()
        .build(store.clone(), "/")
        .map_err(|e| zarr_err("the group")(&e))?;
    group.attributes_mut().insert(
        "ome".into(),
        json!({"version": "0.5", "multiscales": [{
            "name": opts.name,
            "axes": axes,
            "datasets": datasets,
            "type": "mean",
            "metadata": {"method": "volux 2x mean (odd axes: the last sample averages what exists)"}
        }]}),
    );
    group
        .store_metadata()
        .map_err(|e| zarr_err("the group metadata")(&e))?;
    Ok(dims)
}
