//! `volux convert` and `volux generate`.
use std::path::Path;

use volux_core::tetrahedralize::grid_to_tets;
use volux_core::{synth, Grid, TetMesh};
use volux_io::Dataset;

use super::common::CmdError;
use crate::cli::{value_name, Generator, LoadArgs};

pub fn run(input: &Path, output: &Path, args: &LoadArgs, show: bool) -> Result<(), CmdError> {
    let (data, _) = super::common::load(input, args, show)?;
    write(data, output)?;
    eprintln!("wrote {}", output.display());
    Ok(())
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
    write(data, output)?;
    eprintln!("wrote {}", output.display());
    Ok(())
}

fn extension(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

fn write(data: Dataset, output: &Path) -> Result<(), CmdError> {
    let ext = extension(output);
    match data {
        Dataset::Grid(g) if ext.ends_with(".vtet") => write_mesh(&grid_to_tets(&g)?, output),
        Dataset::Grid(g) => write_grid(&g, output, &ext),
        Dataset::Mesh(m) if ext.ends_with(".vtet") => write_mesh(&m, output),
        Dataset::Mesh(_) => Err(format!(
            "{}: a tet mesh can only be written as .vtet",
            output.display()
        )
        .into()),
        _ => Err("unsupported dataset kind".into()),
    }
}

fn write_grid(g: &Grid, output: &Path, ext: &str) -> Result<(), CmdError> {
    if ext.ends_with(".raw") {
        volux_io::raw::write(g, output)?;
    } else if ext.ends_with(".nrrd") {
        volux_io::nrrd::write(g, output)?;
    } else {
        return Err(format!(
            "{}: unknown output format (use .raw, .nrrd or .vtet)",
            output.display()
        )
        .into());
    }
    Ok(())
}

fn write_mesh(m: &TetMesh, output: &Path) -> Result<(), CmdError> {
    volux_io::vtet::write(m, output)?;
    Ok(())
}
