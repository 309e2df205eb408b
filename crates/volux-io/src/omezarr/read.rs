//! Opening a store: its metadata parsed and checked, each level a [`ZarrLevel`], the whole
//! an [`OmeZarr`] (levels, axes, units, codec).
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde_json::Value;
use volux_core::bricked::{ChunkLayout, ChunkSource, Multiscale};
use volux_core::histogram::STORED_BINS;
use zarrs::array::Array;
use zarrs::filesystem::FilesystemStore;

use super::level::{Stored, ZarrLevel};
use super::meta::{self, Axis, MultiscaleMeta};
use super::store::{OmeZarr, ZarrOptions, VOLUX_KEY};
use crate::error::{ErrorKind, ReadError, Result};

/// Chunks whose decoded bytes exceed this are refused (a 512^3 u16 chunk is 256 MiB).
pub const MAX_CHUNK_BYTES: u64 = 1 << 30;
/// Levels of more samples than this (2^50) are refused as absurd metadata.
pub const MAX_SAMPLES: u64 = 1 << 50;

fn header(path: &Path, msg: impl Into<String>) -> ReadError {
    ReadError::new(path, ErrorKind::Header(msg.into()))
}

/// The `volux` attributes of a level written by [`super::write_ome_zarr`]: per-chunk ranges
/// (flat `[min, max, ...]`, x fastest) and the level's range; `None` when absent or not
/// matching `count` chunks.
fn volux_ranges(
    attrs: &serde_json::Map<String, Value>,
    count: usize,
) -> (Option<Vec<[f64; 2]>>, Option<[f64; 2]>) {
    let Some(v) = attrs.get(VOLUX_KEY) else {
        return (None, None);
    };
    let range = v
        .get("range")
        .and_then(Value::as_array)
        .and_then(|a| Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?]));
    let chunks = v
        .get("chunk_ranges")
        .and_then(Value::as_array)
        .filter(|a| a.len() == 2 * count)
        .and_then(|a| {
            a.chunks(2)
                .map(|p| Some([p[0].as_f64()?, p[1].as_f64()?]))
                .collect::<Option<Vec<_>>>()
        });
    (chunks, range)
}

/// The full level's histogram counts recorded by [`super::write_ome_zarr`] (the `volux`
/// attribute `histogram`: [`STORED_BINS`] counts over the level's range), when present and
/// counting `samples` samples.
fn volux_histogram(attrs: &serde_json::Map<String, Value>, samples: u64) -> Option<Vec<u64>> {
    let counts: Vec<u64> = attrs
        .get(VOLUX_KEY)?
        .get("histogram")?
        .as_array()?
        .iter()
        .map(Value::as_u64)
        .collect::<Option<_>>()?;
    let total = counts.iter().try_fold(0u64, |a, &c| a.checked_add(c));
    (counts.len() == STORED_BINS && total == Some(samples)).then_some(counts)
}

/// The codec chain of an array's metadata file, in words (`blosc(zstd)`, `zstd`, `gzip`).
fn codec_words(array_dir: &Path) -> String {
    let name_of = |c: &Value| -> String {
        let name = c
            .get("name")
            .or_else(|| c.get("id"))
            .and_then(Value::as_str)
            .unwrap_or("?")
            .to_string();
        let conf = c.get("configuration").unwrap_or(c);
        match conf.get("cname").and_then(Value::as_str) {
            Some(cname) => format!("{name}({cname})"),
            None => name,
        }
    };
    if let Ok(v) = meta::read_json(&array_dir.join("zarr.json")) {
        let list: Vec<String> = v
            .get("codecs")
            .and_then(Value::as_array)
            .map(|l| l.iter().map(name_of).filter(|n| n != "bytes").collect())
            .unwrap_or_default();
        return if list.is_empty() {
            "none".into()
        } else {
            list.join(" + ")
        };
    }
    if let Ok(v) = meta::read_json(&array_dir.join(".zarray")) {
        return match v.get("compressor") {
            Some(c) if !c.is_null() => name_of(c),
            _ => "none".into(),
        };
    }
    "unknown".into()
}

/// Opens the OME-Zarr image (or plain Zarr array) at `path` (`opts.array` naming a sub-path):
/// its levels as [`ChunkSource`]s, with spacing and origin from the coordinate
/// transformations. Nothing but metadata is read.
pub fn open_store(path: &Path, opts: &ZarrOptions) -> Result<OmeZarr> {
    let dir: PathBuf = match &opts.array {
        Some(a) => path.join(a.trim_matches('/')),
        None => path.to_path_buf(),
    };
    let node = meta::read_node(&dir)?.ok_or_else(|| {
        header(
            &dir,
            "not a Zarr group or array: no zarr.json, .zgroup, .zattrs or .zarray (missing metadata)",
        )
    })?;
    let store = Arc::new(
        FilesystemStore::new(&dir)
            .map_err(|e| ReadError::new(&dir, ErrorKind::Invalid(e.to_string())))?,
    );
    let open = |p: &str| -> Result<Array<FilesystemStore>> {
        let key = format!("/{}", p.trim_matches('/'));
        let key = if key == "/" { "/".to_string() } else { key };
        Array::open(store.clone(), &key)
            .map_err(|e| header(&dir.join(p), format!("cannot open the Zarr array: {e}")))
    };
    let ms: MultiscaleMeta = if node.is_array {
        let ndim = open("")?.dimensionality();
        meta::parse_multiscale(
            &dir,
            &serde_json::json!({"datasets": [{"path": ""}]}),
            None,
            |_| Ok(ndim),
        )?
    } else {
        let (list, version) = meta::multiscales_value(&node.attributes).ok_or_else(|| {
            header(&dir, "a Zarr group without OME-NGFF \"multiscales\" metadata (name an image inside it with the array reader option)")
        })?;
        let first = list
            .first()
            .ok_or_else(|| header(&dir, "an empty \"multiscales\" list"))?;
        meta::parse_multiscale(&dir, first, version, |p| Ok(open(p)?.dimensionality()))?
    };
    let ndim = ms.axes.len();
    let space: Vec<usize> = (0..ndim).filter(|&i| ms.axes[i].is_space()).collect();
    if !(2..=3).contains(&space.len()) {
        return Err(ReadError::new(
            &dir,
            ErrorKind::Unsupported(format!(
                "an image with {} spatial axes (Volux reads 2 or 3)",
                space.len()
            )),
        ));
    }
    // Our x is the last spatial axis.
    let spatial: [Option<usize>; 3] =
        std::array::from_fn(|a| space.len().checked_sub(a + 1).map(|i| space[i]));
    let mut levels: Vec<Arc<dyn ChunkSource>> = Vec::new();
    let mut notes = Vec::new();
    let mut data_type = String::new();
    let mut codec = String::new();
    for (li, ds) in ms.datasets.iter().enumerate() {
        let array = open(&ds.path)?;
        let level_path = dir.join(&ds.path);
        if array.dimensionality() != ndim {
            return Err(header(
                &level_path,
                format!(
                    "the array has {} dimensions but the image {} axes",
                    array.dimensionality(),
                    ndim
                ),
            ));
        }
        let shape = array.shape().to_vec();
        let chunk: Vec<u64> = array
            .chunk_shape(&vec![0; ndim])
            .map_err(|e| header(&level_path, format!("no regular chunk grid: {e}")))?
            .iter()
            .map(|c| c.get())
            .collect();
        let total = shape.iter().try_fold(1u64, |acc, &d| acc.checked_mul(d));
        if shape.contains(&0) || total.is_none_or(|t| t > MAX_SAMPLES) {
            return Err(header(
                &level_path,
                format!("absurd array shape {shape:?} (more than 2^50 samples, or empty)"),
            ));
        }
        let stored = Stored::of(array.data_type()).ok_or_else(|| {
            ReadError::new(&level_path, ErrorKind::Unsupported(format!(
                "data type {} (Volux reads u8, u16, i16, f32, and converts i8, u32, i32, u64, i64, f64)",
                array.data_type().name())))
        })?;
        let chunk_bytes = chunk.iter().try_fold(
            array.data_type().fixed_size().unwrap_or(8) as u64,
            |acc, &d| acc.checked_mul(d),
        );
        if chunk_bytes.is_none_or(|b| b > MAX_CHUNK_BYTES) {
            return Err(header(
                &level_path,
                format!(
                    "chunks of {chunk:?} samples are larger than the 1 GiB Volux reads at once"
                ),
            ));
        }
        let mut fixed = vec![0u64; ndim];
        for (i, ax) in ms.axes.iter().enumerate() {
            if ax.is_space() {
                continue;
            }
            let (want, what) = match (ax.kind.as_deref(), ax.name.as_str()) {
                (Some("channel"), _) | (None, "c") => (opts.channel, "channel"),
                (Some("time"), _) | (None, "t") => (opts.timepoint, "timepoint"),
                _ => (0, "index"),
            };
            if want as u64 >= shape[i] {
                return Err(ReadError::new(
                    &dir,
                    ErrorKind::Invalid(format!(
                        "{what} {want} is out of range: axis \"{}\" has {} entries",
                        ax.name, shape[i]
                    )),
                ));
            }
            fixed[i] = want as u64;
        }
        let pick = |v: &[u64], a: usize, dflt: u64| spatial[a].map_or(dflt, |i| v[i]) as usize;
        let pickf = |v: &[f64], a: usize, dflt: f64| spatial[a].map_or(dflt, |i| v[i]);
        let layout = ChunkLayout::new(
            std::array::from_fn(|a| pick(&shape, a, 1)),
            std::array::from_fn(|a| pick(&chunk, a, 1)),
            std::array::from_fn(|a| pickf(&ds.scale, a, 1.0)),
            std::array::from_fn(|a| pickf(&ds.translation, a, 0.0)),
            stored.scalar(),
        )
        .map_err(|e| ReadError::new(&level_path, e))?;
        if layout
            .chunks_per_axis()
            .iter()
            .try_fold(1usize, |a, &n| a.checked_mul(n))
            .is_none()
        {
            return Err(header(&level_path, "absurd number of chunks"));
        }
        let (ranges, range) = volux_ranges(array.attributes(), layout.chunk_count());
        let samples = layout.dims.iter().map(|&d| d as u64).product();
        let histogram = volux_histogram(array.attributes(), samples);
        if li == 0 {
            data_type = array.data_type().name();
            codec = codec_words(&level_path);
            if !matches!(stored, Stored::U8 | Stored::U16 | Stored::I16 | Stored::F32) {
                notes.push(format!(
                    "stored as {data_type}, read as {}",
                    stored.scalar().name()
                ));
            }
        }
        levels.push(Arc::new(ZarrLevel {
            array,
            layout,
            stored,
            spatial,
            fixed,
            ranges,
            range,
            histogram,
            name: format!("{} level {li} ({})", path.display(), ds.path),
        }));
    }
    let units: [Option<String>; 3] =
        std::array::from_fn(|a| spatial[a].and_then(|i| ms.axes[i].unit.clone()));
    let name = ms
        .name
        .clone()
        .unwrap_or_else(|| path.display().to_string());
    Ok(OmeZarr {
        multiscale: Multiscale::new(name, levels).map_err(|e| ReadError::new(&dir, e))?,
        zarr_format: node.zarr_format,
        ngff_version: ms.version.clone(),
        axes: ms.axes.iter().map(|a: &Axis| a.name.clone()).collect(),
        units,
        codec,
        data_type,
        paths: ms.datasets.iter().map(|d| d.path.clone()).collect(),
        notes,
    })
}
