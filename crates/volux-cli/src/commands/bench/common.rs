//! What the suites share: the datasets, one frame, the median, `--only`.
use std::path::Path;

use volux_core::grid::Grid;
use volux_core::mesh::TetMesh;
use volux_core::{synth, TransferFunction};
use volux_io::{Dataset, LoadOptions};
use volux_render::engine::{Frame, Renderer};
use volux_render::scene::{Scene, Volume};
use volux_render::tiles::Control;

use crate::commands::common::CmdError;

/// The shared data folder, relative to the repository root the bench runs from.
const SHARED_DATA: &str = "../shared/data";

/// The early termination of the PT and tet ray casting cases (the figure of the earlier
/// measurements).
pub const EARLY_TERMINATION: f32 = 0.999;

/// A shared dataset loaded as a volume, or `None` (said on stderr) when absent.
pub fn shared(rel: &str) -> Result<Option<Volume>, CmdError> {
    let p = Path::new(SHARED_DATA).join(rel);
    if !p.exists() {
        eprintln!("bench: {} absent, skipped", p.display());
        return Ok(None);
    }
    Ok(match volux_io::load(&p, &LoadOptions::default())?.0 {
        Dataset::Grid(g) => Some(Volume::from(g)),
        Dataset::Mesh(m) => Some(Volume::from(m)),
        _ => None,
    })
}

/// The synthetic grids and the shared CT and MRI heads, each with its TF.
pub fn grids(n: usize) -> Result<Vec<(String, Volume, TransferFunction)>, CmdError> {
    let synthetic = TransferFunction::from_json(SYNTHETIC_TF)?;
    let mut out = vec![
        (
            format!("marschner-lobb-{n}"),
            synth::marschner_lobb(n)?.into(),
            synthetic.clone(),
        ),
        (
            format!("shepp-logan-{n}"),
            synth::shepp_logan(n)?.into(),
            synthetic,
        ),
    ];
    for (name, rel) in SHARED_GRIDS {
        if let Some(v @ Volume::Grid(_)) = shared(rel)? {
            let tf = v.preset_tf("auto")?;
            out.push((name.to_string(), v, tf));
        }
    }
    Ok(out)
}

/// The generated meshes of about 200K (and 1.25M unless `quick`) tetrahedra, and the shared
/// Blunt Fin and LOx Post.
pub fn meshes(quick: bool) -> Result<Vec<(String, Volume)>, CmdError> {
    let mut out = vec![(
        "smooth-200k".to_string(),
        mesh(synth::smooth_tets(200_000)?),
    )];
    if !quick {
        out.push((
            "smooth-1.25m".to_string(),
            mesh(synth::smooth_tets(1_250_000)?),
        ));
    }
    for (name, rel) in SHARED_MESHES {
        if let Some(v @ Volume::Mesh(_)) = shared(rel)? {
            out.push((name.to_string(), v));
        }
    }
    Ok(out)
}

fn mesh(m: TetMesh) -> Volume {
    Volume::from(m)
}

/// The grid of a grid volume.
pub fn grid_of(v: &Volume) -> Option<&Grid> {
    match v {
        Volume::Grid(g) => Some(g),
        _ => None,
    }
}

/// Renders one frame.
pub fn frame(renderer: &mut dyn Renderer, scene: &Scene) -> Result<Frame, CmdError> {
    Ok(renderer.render(scene, &Control::default())?)
}

/// The median of `times` (sorted in place).
pub fn median(times: &mut [f64]) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Whether a case named `case` is selected by `--only` (every word must appear).
pub fn selected(case: &str, only: Option<&str>) -> bool {
    only.is_none_or(|o| o.split_whitespace().all(|w| case.contains(w)))
}

/// The TF of the synthetic grids (normalized: two thin shells and a faint top).
const SYNTHETIC_TF: &str = r#"{"space": "normalized",
  "color": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.5, 0.1], [1, 1, 1, 1]],
  "extinction": [[0, 0], [0.2, 0], [0.3, 0.05], [0.45, 0.0], [0.5, 0.2], [0.55, 0.0], [1, 0.1]]}"#;

const SHARED_GRIDS: [(&str, &str); 2] = [
    (
        "ct-head",
        "invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz",
    ),
    (
        "mri-head",
        "niivue_chris_t1/chris_t1_188x256x190_uint8.raw.gz",
    ),
];

const SHARED_MESHES: [(&str, &str); 2] = [
    ("blunt-fin", "nasa_blunt_fin/blunt_fin_tets_density.off.gz"),
    ("lox-post", "nasa_lox_post/lox_post_tets_velmag.off.gz"),
];
