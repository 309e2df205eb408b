//! `volux bench --suite grid`: ms/frame and samples/s of the grid ray caster per integrator,
//! on synthetic volumes and the shared CT and MRI heads (when `../shared/data` is present).
use serde_json::json;
use volux_core::CameraSpec;
use volux_render::engine::{create_renderer, MethodStats};
use volux_render::integrate::{AdaptiveParams, Integrator, StepControl};
use volux_render::scene::{GridRaycast, Method, Scene};

use super::common::{frame, grids, median, selected};
use crate::commands::common::CmdError;

/// How a case lights and projects.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    Emission,
    Shaded,
    Mip,
}

/// The integrators timed, unlit, shaded and as MIP.
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

/// The parameter column of a case.
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

/// One case: dataset index, image size, integrator, mode, label.
type Case = (usize, (usize, usize), Integrator, Mode, String);

/// Runs the grid suite; returns the JSON rows.
pub fn run(
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
    let datasets = grids(n)?;
    let cases: Vec<Case> = datasets
        .iter()
        .enumerate()
        .flat_map(|(d, (name, _, _))| {
            sizes.iter().flat_map(move |&size| {
                integrators()
                    .into_iter()
                    .filter_map(move |(integrator, mode)| {
                        let label = format!("{} {}", integrator.name(), param(&integrator, mode));
                        selected(&format!("{name} {label}"), only)
                            .then_some((d, size, integrator, mode, label))
                    })
            })
        })
        .collect();
    if cases.is_empty() {
        return Err(format!(
            "--only '{}' matches no grid case; cases are named \"DATASET INTEGRATOR PARAMETER\", \
             e.g. \"marschner riemann h=0.5\" (datasets: {})",
            only.unwrap_or_default(),
            datasets
                .iter()
                .map(|d| d.0.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
        .into());
    }
    let name_w = datasets.iter().map(|d| d.0.len()).max().unwrap_or(0).max(7);
    let label_w = cases.iter().map(|c| c.4.len()).max().unwrap_or(0).max(10);
    if !as_json {
        outln!("threads: {threads}; frames per case: {frames} (median)")?;
        outln!(
            "{:<name_w$} {:>9} {:<label_w$} {:>10} {:>12} {:>12} {:>16}",
            "dataset",
            "size",
            "integrator",
            "ms/frame",
            "samples",
            "Msamples/s",
            "Msamples/s/core"
        )?;
    }
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let mut renderers = Vec::new();
    for (_, volume, _) in &datasets {
        renderers.push(create_renderer(
            volume,
            &Method::GridRaycast(GridRaycast::default()),
        )?);
    }
    for (d, (w, h), integrator, mode, label) in cases {
        let (name, volume, tf) = &datasets[d];
        let renderer = &mut renderers[d];
        let mut scene = Scene::new(spec.resolve(&volume.bounds())?, w, h, tf.clone());
        scene.method = Method::GridRaycast(GridRaycast {
            integrator,
            ..GridRaycast::default()
        });
        scene.appearance.shade_volume = mode == Mode::Shaded;
        scene.appearance.mip = mode == Mode::Mip;
        // The first frame builds the caches (macrocells, gradients, tables).
        frame(renderer.as_mut(), &scene)?;
        let mut times = Vec::new();
        let mut samples = 0;
        for _ in 0..frames {
            let f = frame(renderer.as_mut(), &scene)?;
            times.push(f.stats.ms / 1e3);
            if let MethodStats::GridRaycast(s) = f.stats.method {
                samples = s.samples;
            }
        }
        let s = median(&mut times);
        let rate = samples as f64 / s / 1e6;
        if !as_json {
            outln!(
                "{:<name_w$} {:>9} {:<label_w$} {:>10.1} {:>12} {:>12.1} {:>16.1}",
                name,
                format!("{w}x{h}"),
                label,
                s * 1e3,
                samples,
                rate,
                rate / threads as f64
            )?;
        }
        rows.push(json!({
            "dataset": name, "width": w, "height": h, "integrator": integrator.name(),
            "param": param(&integrator, mode), "ms": s * 1e3, "samples": samples,
            "samples_per_s": rate * 1e6, "samples_per_s_per_core": rate * 1e6 / threads as f64,
        }));
    }
    Ok(rows)
}
