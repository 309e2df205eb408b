//! `volux bench`: ms/frame and samples/s of the grid ray caster per integrator, on synthetic
//! volumes and the shared CT and MRI heads (when `../shared/data` is present).
use std::path::Path;

use serde_json::json;
use volux_core::histogram::Histogram;
use volux_core::{synth, CameraSpec, Grid, TransferFunction};
use volux_io::{Dataset, LoadOptions};
use volux_render::integrate::{AdaptiveParams, Integrator, StepControl};
use volux_render::raycast::GridRenderer;
use volux_render::shading::BlinnPhong;
use volux_render::RenderOptions;

use super::CmdError;

/// A semi-transparent TF for the synthetic volumes (normalized).
const SYNTHETIC_TF: &str = r#"{"space": "normalized",
  "color": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.5, 0.1], [1, 1, 1, 1]],
  "extinction": [[0, 0], [0.2, 0], [0.3, 0.05], [0.45, 0.0], [0.5, 0.2], [0.55, 0.0], [1, 0.1]]}"#;

const SHARED: [(&str, &str); 2] = [
    (
        "ct-head",
        "invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz",
    ),
    (
        "mri-head",
        "niivue_chris_t1/chris_t1_188x256x190_uint8.raw.gz",
    ),
];

/// The grid datasets with their TFs: the `n`^3 synthetic volumes, and the shared heads when
/// `../shared/data` holds them.
pub(super) fn datasets(n: usize) -> Result<Vec<(String, Grid, TransferFunction)>, CmdError> {
    let synthetic = TransferFunction::from_json(SYNTHETIC_TF)?;
    let mut out = vec![
        (
            format!("marschner-lobb-{n}"),
            synth::marschner_lobb(n)?,
            synthetic.clone(),
        ),
        (
            format!("shepp-logan-{n}"),
            synth::shepp_logan(n)?,
            synthetic,
        ),
    ];
    let root = Path::new("../shared/data");
    for (name, rel) in SHARED {
        let p = root.join(rel);
        if !p.exists() {
            eprintln!("bench: {} absent, skipped", p.display());
            continue;
        }
        if let (Dataset::Grid(g), _) = volux_io::load(&p, &LoadOptions::default())? {
            let tf = TransferFunction::preset("auto", &Histogram::of_grid(&g, 256))?
                .with_unit_length(g.spacing().min_element());
            out.push((name.to_string(), g, tf));
        }
    }
    Ok(out)
}

/// How a grid case renders besides its integrator.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Emission,
    /// Blinn-Phong with the default settings.
    Shaded,
    /// Maximum intensity projection (the integrator gives the step).
    Mip,
}

/// The grid cases: an integrator and a mode.
fn integrators() -> Vec<(Integrator, Mode)> {
    let adaptive = |control, hmin, hmax| {
        Integrator::AdaptiveSimpson(AdaptiveParams {
            tol: 0.01,
            h0: 0.5,
            hmin,
            hmax,
            control,
            early_termination: None,
        })
    };
    let unlit = [
        Integrator::Riemann { step: 0.5 },
        Integrator::Riemann { step: 0.2 },
        Integrator::Trapezoid { step: 0.5 },
        Integrator::Simpson { step: 0.5 },
        Integrator::Preintegrated { step: 0.5 },
        // The seed's settings (`001_...txt` fig. 5.1 and table 5.5: h0 0.5, hmin 0.1, hmax 2
        // voxels), and those of its Bonsai tables 5.4 and 5.6 (hmin 0.4, hmax 4).
        adaptive(StepControl::Coupled, 0.1, 2.0),
        adaptive(StepControl::Decoupled, 0.1, 2.0),
        adaptive(StepControl::Coupled, 0.4, 4.0),
    ];
    let shaded = [
        Integrator::Riemann { step: 0.5 },
        Integrator::Preintegrated { step: 0.5 },
        adaptive(StepControl::Coupled, 0.4, 4.0),
    ];
    let unlit = unlit.into_iter().map(|i| (i, Mode::Emission));
    unlit
        .chain(shaded.into_iter().map(|i| (i, Mode::Shaded)))
        .chain([(Integrator::Riemann { step: 0.5 }, Mode::Mip)])
        .collect()
}

fn param(i: &Integrator, mode: Mode) -> String {
    let p = match i {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Simpson { step }
        | Integrator::Preintegrated { step } => format!("h={step}"),
        Integrator::AdaptiveSimpson(p) => format!("tol={} hmax={}", p.tol, p.hmax),
        _ => String::new(),
    };
    match mode {
        Mode::Emission => p,
        Mode::Shaded => p + " shaded",
        Mode::Mip => p + " mip",
    }
}

pub fn run(
    quick: bool,
    frames: usize,
    n: usize,
    as_json: bool,
    suite: &str,
    only: Option<&str>,
) -> Result<(), CmdError> {
    if suite == "targets" {
        let rows = super::bench_targets::run(n, frames, as_json)?;
        if as_json {
            println!("{}", serde_json::Value::Array(rows));
        }
        return Ok(());
    }
    let (grid, pt, tetray) = match suite {
        "all" => (true, true, true),
        "grid" => (true, false, false),
        "pt" => (false, true, false),
        "tetray" => (false, false, true),
        other => {
            return Err(format!("unknown suite '{other}' (all, grid, pt, tetray, targets)").into())
        }
    };
    let mut rows = if grid {
        run_grid(quick, frames, n, as_json, only)?
    } else {
        Vec::new()
    };
    if pt {
        rows.extend(super::bench_pt::run(quick, frames, as_json)?);
    }
    if tetray {
        rows.extend(super::bench_pt::run_tetray(quick, frames, as_json)?);
    }
    if as_json {
        println!("{}", serde_json::Value::Array(rows));
    }
    Ok(())
}

fn run_grid(
    quick: bool,
    frames: usize,
    n: usize,
    as_json: bool,
    only: Option<&str>,
) -> Result<Vec<serde_json::Value>, CmdError> {
    let frames = if quick { 1 } else { frames.max(1) };
    let sizes: &[(usize, usize)] = if quick {
        &[(512, 512)]
    } else {
        &[(512, 512), (800, 600)]
    };
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    if !as_json {
        println!("threads: {threads}; frames per case: {frames} (median)");
        println!(
            "{:<22} {:>8} {:<20} {:>10} {:>12} {:>14} {:>16}",
            "dataset", "size", "integrator", "ms/frame", "samples", "Msamples/s", "Msamples/s/core"
        );
    }
    for (name, grid, tf) in datasets(n)? {
        let renderer = GridRenderer::new(&grid);
        renderer.macrocells();
        let spec = CameraSpec {
            azimuth: Some(30.0),
            elevation: Some(20.0),
            ..Default::default()
        };
        for &(w, h) in sizes {
            for (integrator, mode) in integrators() {
                let param = param(&integrator, mode);
                let case = format!("{name} {} {param}", integrator.name());
                if !selected(&case, only) {
                    continue;
                }
                let mut opts = RenderOptions::new(spec.resolve(&grid.bounds())?, tf.clone());
                (opts.width, opts.height, opts.integrator) = (w, h, integrator);
                opts.shading = (mode == Mode::Shaded).then(BlinnPhong::default);
                opts.mip = mode == Mode::Mip;
                if opts.shading.is_some() {
                    // Built once per volume (a viewer keeps it), not per frame.
                    renderer.gradients();
                }
                let mut times = Vec::new();
                let mut samples = 0;
                for _ in 0..frames {
                    let r = renderer.render(&opts)?;
                    times.push(r.stats.seconds);
                    samples = r.stats.samples;
                }
                times.sort_by(f64::total_cmp);
                let s = times[times.len() / 2];
                let rate = samples as f64 / s / 1e6;
                let row = json!({
                    "dataset": name, "width": w, "height": h, "integrator": integrator.name(),
                    "param": param, "ms": s * 1e3, "samples": samples,
                    "samples_per_s": rate * 1e6, "samples_per_s_per_core": rate * 1e6 / threads as f64,
                });
                if !as_json {
                    println!(
                        "{:<22} {:>8} {:<20} {:>10.1} {:>12} {:>14.1} {:>16.1}",
                        name,
                        format!("{w}x{h}"),
                        format!("{} {param}", integrator.name()),
                        s * 1e3,
                        samples,
                        rate,
                        rate / threads as f64
                    );
                }
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// Whether a case named `case` is selected by `only` (every word of it appears in the name).
fn selected(case: &str, only: Option<&str>) -> bool {
    only.is_none_or(|o| o.split_whitespace().all(|w| case.contains(w)))
}
