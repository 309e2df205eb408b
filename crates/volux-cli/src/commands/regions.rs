//! `volux regions`: region labelling (seed `004` sec. 6.2). Each `--seed X,Y,LABEL` is picked
//! on the visible surface; the visible voxels of the volume of interest (inside the clip
//! planes and the mask, with a non-zero extinction under the transfer function) take the
//! seeds' labels by `--rule`: `connected` (the default, issue 41) grows each seed's region
//! through the 6-connected visible voxels, breadth-first from all seeds at once, leaving
//! what no seed reaches at 0; `nearest` gives every visible voxel its nearest seed in world
//! distance (the data's anisotropic spacing, not texture space), as the seed does. The
//! labels are written as NRRD `u8` with the grid's geometry, and the voxels of each label
//! and the unlabelled ones are printed.
use volux_render::sculpt::SculptStep;

use super::common::CmdError;
use super::workbench;
use crate::cli::RegionsArgs;

/// Runs `volux regions`.
pub fn run(args: &RegionsArgs, given: &[String], show: bool) -> Result<(), CmdError> {
    workbench::nrrd_path(&args.output, "--output")?;
    if args.seeds.is_empty() {
        return Err("give at least one --seed X,Y,LABEL".into());
    }
    let seeds = args
        .seeds
        .iter()
        .map(|s| seed(s))
        .collect::<Result<Vec<_>, _>>()?;
    let mut bench = workbench::open(&args.view, given, show)?;
    for ((pixel, label), typed) in seeds.iter().zip(&args.seeds) {
        let what = format!("--seed {typed}");
        workbench::in_image(&what, *pixel, bench.size())?;
        let point = workbench::pick(&bench, *pixel, &what)?.world;
        // The colour `render --labels` gives the label too.
        let colour = volux_render::sculpt::labels::LABEL_PALETTE
            [usize::from(label - 1) % volux_render::sculpt::labels::LABEL_PALETTE.len()];
        bench.sculpt.apply(SculptStep::Label {
            point,
            label: *label,
            colour,
            rule: args.rule.into(),
        })?;
    }
    let labels = bench.sculpt.labels(&bench.grid, &bench.scene)?;
    let counts = count(&labels);
    workbench::write_u8_like(&bench.grid, labels, &args.output)?;
    for (label, n) in counts.iter().enumerate().skip(1).filter(|(_, n)| **n > 0) {
        outln!("label {label}: {n} voxels")?;
    }
    outln!("unlabelled: {} voxels", counts[0])?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

/// Parses `--seed X,Y,LABEL`.
fn seed(s: &str) -> Result<([f64; 2], u8), CmdError> {
    let form = "X,Y,LABEL (pixels, and a label from 1 to 255)";
    match workbench::numbers("seed", s, form)?.as_slice() {
        [x, y, l] if l.fract() == 0.0 && (1.0..=255.0).contains(l) => Ok(([*x, *y], *l as u8)),
        _ => Err(format!("--seed '{s}': expected {form}").into()),
    }
}

/// Voxels per label value.
fn count(labels: &[u8]) -> [u64; 256] {
    let mut n = [0u64; 256];
    for &l in labels {
        n[usize::from(l)] += 1;
    }
    n
}
