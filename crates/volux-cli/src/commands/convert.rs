//! `volux convert` and `volux generate`.
use std::path::Path;

use volux_core::tetrahedralize::grid_to_tets;
use volux_core::{synth, Grid, TetMesh};
use volux_io::Dataset;

use super::common::CmdError;
use crate::cli::{value_name, Generator, LoadArgs};
use crate::progress;

pub fn run(input: &Path, output: &Path, args: &LoadArgs, show: bool) -> Result<(), CmdError> {
    let (data, _) = super::common::load(input, args, show)?;
    // What the reader did to the values (a scaling, a conversion) travels with the data.
    let notes = match &data {
        Dataset::Grid(g) => g.notes(),
        Dataset::Mesh(m) => m.notes(),
        _ => &[],
    };
    for n in notes {
        eprintln!("note: {}", crate::messages::sanitize(n));
    }
    write(data, output, show)?;
    said(output);
    Ok(())
}

/// Says what was written and how large it is.
fn said(output: &Path) {
    let size = std::fs::metadata(output).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "wrote {} ({})",
        output.display(),
        volux_core::units::format_bytes(size)
    );
}

pub fn generate(kind: Generator, size: usize, output: &Path) -> Result<(), CmdError> {
    let kind = value_name(&kind);
    let kind = kind.as_str();
    if size == 0 || size > 4096 * 4096 * 16 {
        return Err(format!("--size {size} is out of range").into());
    }
    let data = if synth::GENERATORS[..3].contains(&kind) {
        if size > 2048 {
            return Err(
                format!("--size {size} is too large for a grid (at most 2048 per axis)").into(),
            );
        }
        Dataset::Grid(synth::generate_grid(kind, size)?)
    } else {
        Dataset::Mesh(synth::generate_mesh(kind, size)?)
    };
    write(data, output, false)?;
    said(output);
    Ok(())
}

fn extension(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

fn write(data: Dataset, output: &Path, show: bool) -> Result<(), CmdError> {
    let ext = extension(output);
    match data {
        Dataset::Grid(g) if ext.ends_with(".vtet") => {
            if g.color().is_some() {
                eprintln!(
                    "note: the colour is not kept: a tet mesh holds one scalar per vertex, the \
                     luminance"
                );
            }
            write_mesh(&grid_to_tets(&g)?, output, show)
        }
        Dataset::Grid(g) => write_grid(&g, output, &ext, show),
        Dataset::Mesh(m) if ext.ends_with(".vtet") => write_mesh(&m, output, show),
        Dataset::Mesh(_) => Err(format!(
            "{}: a tet mesh can only be written as .vtet",
            output.display()
        )
        .into()),
        _ => Err("unsupported dataset kind".into()),
    }
}

/// Files above this size are announced before they are written.
const LARGE: u64 = 256 << 20;

/// A progress bar for writing `total` bytes to `output`, announced when large.
fn bar(output: &Path, total: u64, show: bool) -> indicatif::ProgressBar {
    if total >= LARGE {
        eprintln!(
            "writing {} ({} uncompressed)",
            output.display(),
            volux_core::units::format_bytes(total)
        );
    }
    let pb = progress::bytes(show, output.display().to_string());
    pb.set_length(total);
    pb
}

fn write_grid(g: &Grid, output: &Path, ext: &str, show: bool) -> Result<(), CmdError> {
    if ext.ends_with(".raw") || ext.ends_with(".raw.gz") {
        for n in volux_io::raw::unstored(g) {
            eprintln!("note: {n}");
        }
        let pb = bar(output, volux_io::raw::encoded_size(g), show);
        volux_io::raw::write_with_progress(g, output, &|done, _| pb.set_position(done))?;
        pb.finish_and_clear();
    } else if ext.ends_with(".nrrd") {
        volux_io::nrrd::write(g, output)?;
    } else {
        return Err(format!(
            "{}: unknown output format (use .raw, .raw.gz, .nrrd, .vtet or .ome.zarr)",
            output.display()
        )
        .into());
    }
    Ok(())
}

fn write_mesh(m: &TetMesh, output: &Path, show: bool) -> Result<(), CmdError> {
    let pb = bar(output, volux_io::vtet::encoded_size(m), show);
    volux_io::vtet::write_with_progress(m, output, &|done, _| pb.set_position(done))?;
    pb.finish_and_clear();
    Ok(())
}
