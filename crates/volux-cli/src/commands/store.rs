//! OME-Zarr stores in the CLI: `volux convert IN OUT.ome.zarr`, `volux generate KIND -o
//! OUT.ome.zarr` (chunk by chunk, never the whole volume) and `volux info STORE`.
use std::path::Path;
use std::sync::Arc;

use serde_json::json;
use volux_core::bricked::{ChunkSource, GridChunks};
use volux_core::grid::ScalarType;
use volux_io::omezarr::{self, Levels, SyntheticChunks, WriteOptions, ZarrOptions};
use volux_io::{Dataset, Format};

use super::common::CmdError;
use crate::cli::LoadArgs;

/// Whether `path` names an OME-Zarr output (`*.zarr`).
pub fn is_zarr_output(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n.to_string_lossy().to_lowercase().ends_with(".zarr"))
}

/// The store options: `--chunk` (default 128) and `--levels N|auto`.
pub struct StoreArgs {
    /// Samples per chunk side.
    pub chunk: usize,
    /// Pyramid levels.
    pub levels: Levels,
}

impl StoreArgs {
    /// Parses `--chunk` and `--levels`.
    pub fn parse(chunk: Option<usize>, levels: Option<&str>) -> Result<Self, CmdError> {
        let chunk = chunk.unwrap_or(128);
        if !(1..=1024).contains(&chunk) {
            return Err(
                format!("--chunk {chunk} is out of range (1 to 1024 samples per side)").into(),
            );
        }
        let levels = match levels.unwrap_or("auto") {
            "auto" => Levels::Auto,
            n => match n.parse::<usize>() {
                Ok(n) if (1..=32).contains(&n) => Levels::Count(n),
                _ => {
                    return Err(
                        format!("--levels {n}: expected a count from 1 to 32, or auto").into(),
                    )
                }
            },
        };
        Ok(Self { chunk, levels })
    }
}

/// Refuses an output that exists (a store is a folder: it is not replaced).
fn check_output(output: &Path) -> Result<(), CmdError> {
    if output.exists() {
        return Err(format!(
            "{}: already exists; remove it first (Volux does not replace a store)",
            output.display()
        )
        .into());
    }
    Ok(())
}

fn write(
    source: &dyn ChunkSource,
    output: &Path,
    args: &StoreArgs,
    unit: Option<String>,
) -> Result<(), CmdError> {
    let opts = WriteOptions {
        levels: args.levels,
        name: output
            .file_name()
            .map(|n| {
                n.to_string_lossy()
                    .trim_end_matches(".zarr")
                    .trim_end_matches(".ome")
                    .to_string()
            })
            .unwrap_or_default(),
        unit,
        ..Default::default()
    };
    let dims = omezarr::write_ome_zarr(source, output, &opts)?;
    let shown: Vec<String> = dims
        .iter()
        .map(|d| format!("{}x{}x{}", d[0], d[1], d[2]))
        .collect();
    eprintln!(
        "wrote {} ({} levels: {}; chunks of {} samples, zstd)",
        output.display(),
        dims.len(),
        shown.join(", "),
        args.chunk
    );
    Ok(())
}

/// `volux convert IN OUT.ome.zarr`: the input (in memory, or memory-mapped for raw and NRRD)
/// streamed chunk by chunk into a store with its pyramid.
pub fn convert(
    input: &Path,
    output: &Path,
    load: &LoadArgs,
    args: &StoreArgs,
    show: bool,
) -> Result<(), CmdError> {
    check_output(output)?;
    let (data, format) = super::common::load(input, load, show)?;
    let Dataset::Grid(grid) = data else {
        return Err(format!("{}: only grids can be written as OME-Zarr", input.display()).into());
    };
    for n in grid.notes() {
        eprintln!("note: {}", crate::messages::sanitize(n));
    }
    if !grid.is_axis_aligned() {
        eprintln!(
            "note: the grid's direction ({}) is not kept: OME-Zarr levels are axis-aligned",
            grid.orientation_code()
        );
    }
    if grid.color().is_some() {
        eprintln!(
            "note: the colour is not kept: the store holds one scalar per voxel, the \
             luminance (--component N writes one channel)"
        );
    }
    let unit = match format {
        _ if grid.unit() != "mm" => volux_core::units::length_name(grid.unit()).map(String::from),
        Format::Dicom
        | Format::Nifti
        | Format::Analyze
        | Format::Mgh
        | Format::Nrrd
        | Format::MetaImage => Some("millimeter".to_string()),
        Format::OmeZarr => store_options(load)
            .ok()
            .and_then(|o| omezarr::open_store(input, &o).ok())
            .and_then(|s| s.units[0].clone()),
        _ => None,
    };
    let source = GridChunks::new(Arc::new(grid), [args.chunk; 3])?;
    write(&source, output, args, unit)
}

/// The samples per axis of a generated store: `N` (a cube) or `XxYxZ`, each 2 to 2^20.
pub fn parse_dims(text: &str) -> Result<[usize; 3], CmdError> {
    let bad = || format!("--size '{text}': expected N or XxYxZ, each 2 to 1048576");
    let parts: Vec<&str> = text.split('x').collect();
    let numbers = parts
        .iter()
        .map(|p| {
            p.trim()
                .parse::<usize>()
                .ok()
                .filter(|n| (2..=1 << 20).contains(n))
        })
        .collect::<Option<Vec<usize>>>()
        .ok_or_else(bad)?;
    match numbers[..] {
        [n] => Ok([n; 3]),
        [x, y, z] => Ok([x, y, z]),
        _ => Err(bad().into()),
    }
}

/// `volux generate KIND --size N|XxYxZ -o OUT.ome.zarr`: computed chunk by chunk.
pub fn generate(
    kind: &str,
    dims: [usize; 3],
    dtype: Option<&str>,
    output: &Path,
    args: &StoreArgs,
) -> Result<(), CmdError> {
    let scalar = match dtype.unwrap_or("f32") {
        "f32" => ScalarType::F32,
        "u16" => ScalarType::U16,
        other => return Err(format!("--dtype {other}: expected f32 or u16").into()),
    };
    let source = SyntheticChunks::new(kind, dims, [args.chunk; 3], scalar)?;
    check_output(output)?;
    write(&source, output, args, None)
}

fn store_options(load: &LoadArgs) -> Result<ZarrOptions, CmdError> {
    Ok(ZarrOptions {
        array: load.array.clone(),
        level: load.level.unwrap_or(0),
        channel: load.channel.unwrap_or(0),
        timepoint: load.timepoint.unwrap_or(0),
    })
}

/// `volux info STORE` (without `--level`): the pyramid, read from the metadata only.
pub fn info(path: &Path, as_json: bool, load: &LoadArgs) -> Result<(), CmdError> {
    let store = omezarr::open_store(path, &store_options(load)?)?;
    let levels = store.multiscale.levels();
    let l0 = levels[0].layout();
    let level_lines: Vec<String> = levels
        .iter()
        .zip(&store.paths)
        .enumerate()
        .map(|(i, (l, p))| {
            let l = l.layout();
            format!(
                "{i} ({p}): {}x{}x{}, chunks {}x{}x{}, spacing [{}]",
                l.dims[0],
                l.dims[1],
                l.dims[2],
                l.chunk[0],
                l.chunk[1],
                l.chunk[2],
                l.spacing.map(crate::numbers::human).join(", ")
            )
        })
        .collect();
    let range = match levels[0].value_range() {
        Some(r) => json!(r),
        None => json!("unknown (not recorded by the writer; load a level to compute it)"),
    };
    let value = json!({
        "kind": "multiscale store",
        "format": format!("OME-Zarr (Zarr v{}, NGFF {})", store.zarr_format, store.ngff_version.as_deref().unwrap_or("?")),
        "dims": l0.dims,
        "dtype": store.data_type,
        "spacing": l0.spacing,
        "origin": l0.origin,
        "units": store.unit_words(),
        "chunk": l0.chunk,
        "codec": store.codec,
        "range": range,
        "levels": level_lines,
        "axes": store.axes,
        "notes": store.notes,
    });
    if as_json {
        outln!("{}", serde_json::to_string(&value)?)?;
    } else {
        super::info::print_text(path, &value)?;
    }
    Ok(())
}
