//! `volux accuracy`: how far Riemann sums and adaptive Simpson are from the f64 reference, as
//! the percentage of rays whose error exceeds a threshold per channel (`001_...txt` sec. 5,
//! tables B.1, B.2, 5.5).
use std::path::PathBuf;

use serde_json::json;
use volux_core::{synth, CameraSpec, Image};
use volux_io::Dataset;
use volux_render::engine::{create_renderer, Frame, MethodStats};
use volux_render::integrate::{AdaptiveParams, Integrator, StepControl};
use volux_render::scene::{GridRaycast, Method, Scene, Volume};
use volux_render::tiles::Control;

use super::common::CmdError;
use crate::cli::LoadArgs;
use crate::settings::{parse_size, transfer_function};

/// Arguments of `volux accuracy`.
pub struct Args {
    pub file: PathBuf,
    pub tf: String,
    pub size: String,
    pub eps: f64,
    pub hmax: f64,
    pub hmin: f64,
    pub json: bool,
    pub load: LoadArgs,
}

/// One row of the table.
struct Row {
    method: &'static str,
    param: (&'static str, f64),
    threshold: f64,
    pct_over: [f64; 4],
    samples: u64,
    seconds: f64,
}

fn load_grid(args: &Args, show: bool) -> Result<Volume, CmdError> {
    let name = args.file.to_string_lossy();
    if synth::GENERATORS[..3].contains(&name.as_ref()) {
        return Ok(synth::generate_grid(&name, 64)?.into());
    }
    match super::common::load(&args.file, &args.load, show)?.0 {
        Dataset::Grid(g) => Ok(g.into()),
        _ => Err("accuracy works on regular grids".into()),
    }
}

/// Percentage of pixels whose error exceeds `eps`, per channel.
fn pct_over(a: &Image, reference: &Image, eps: f64) -> Result<[f64; 4], CmdError> {
    let d = a.compare(reference, eps)?;
    Ok(d.fraction_over_per_channel.map(|f| 100.0 * f))
}

/// The render time of a grid frame in seconds.
fn seconds(f: &Frame) -> f64 {
    match &f.stats.method {
        MethodStats::GridRaycast(s) => s.seconds,
        _ => f.stats.ms / 1e3,
    }
}

/// The samples of a grid frame.
fn samples(f: &Frame) -> u64 {
    match &f.stats.method {
        MethodStats::GridRaycast(s) => s.samples,
        _ => 0,
    }
}

pub fn run(args: &Args, show: bool) -> Result<(), CmdError> {
    let (w, h) = parse_size(&args.size)?;
    let volume = load_grid(args, show)?;
    let tf = transfer_function(&args.tf, &volume)?;
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let mut scene = Scene::new(spec.resolve(&volume.bounds())?, w, h, tf);
    scene.early_termination = None;
    let mut renderer = create_renderer(&volume, &Method::GridRaycast(GridRaycast::default()))?;
    let mut render = |integrator| {
        scene.method = Method::GridRaycast(GridRaycast {
            integrator,
            ..GridRaycast::default()
        });
        renderer.render(&scene, &Control::default())
    };
    let reference = render(Integrator::Reference)?;
    let mut rows = Vec::new();
    for step in [0.5, 0.4, 0.3, 0.2, 0.1] {
        let r = render(Integrator::Riemann { step })?;
        rows.push(Row {
            method: "riemann",
            param: ("step", step),
            threshold: args.eps,
            pct_over: pct_over(&r.image, &reference.image, args.eps)?,
            samples: samples(&r),
            seconds: seconds(&r),
        });
    }
    for (method, control) in [
        ("adaptive-coupled", StepControl::Coupled),
        ("adaptive-standard", StepControl::CoupledStandard),
        ("adaptive-decoupled", StepControl::Decoupled),
    ] {
        for tol in [0.01, 0.005, 0.001] {
            let p = AdaptiveParams {
                tol,
                h0: 0.5_f64.min(args.hmax),
                hmin: args.hmin.min(args.hmax),
                hmax: args.hmax,
                control,
                early_termination: None,
            };
            let r = render(Integrator::AdaptiveSimpson(p))?;
            rows.push(Row {
                method,
                param: ("tol", tol),
                threshold: tol,
                pct_over: pct_over(&r.image, &reference.image, tol)?,
                samples: samples(&r),
                seconds: seconds(&r),
            });
        }
    }
    print_rows(&rows, args.json, seconds(&reference))?;
    Ok(())
}

fn print_rows(rows: &[Row], as_json: bool, reference_seconds: f64) -> std::io::Result<()> {
    if as_json {
        let list: Vec<_> = rows
            .iter()
            .map(|r| {
                let mut v = json!({
                    "method": r.method,
                    "threshold": r.threshold,
                    "pct_over": {"r": r.pct_over[0], "g": r.pct_over[1], "b": r.pct_over[2], "a": r.pct_over[3]},
                    "samples": r.samples,
                    "seconds": r.seconds,
                });
                v[r.param.0] = json!(r.param.1);
                v
            })
            .collect();
        outln!("{}", serde_json::Value::Array(list))?;
        return Ok(());
    }
    outln!("reference (f64, adaptive 1e-7, split at voxel boundaries): {reference_seconds:.2} s")?;
    outln!(
        "{:<20} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>12} {:>9}",
        "method",
        "param",
        "eps",
        "%R>eps",
        "%G>eps",
        "%B>eps",
        "%A>eps",
        "samples",
        "seconds"
    )?;
    for r in rows {
        outln!(
            "{:<20} {:>7} {:>7} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>12} {:>9.3}",
            r.method,
            format!(
                "{}={}",
                if r.param.0 == "step" { "h" } else { "tol" },
                r.param.1
            ),
            r.threshold,
            r.pct_over[0],
            r.pct_over[1],
            r.pct_over[2],
            r.pct_over[3],
            r.samples,
            r.seconds
        )?;
    }
    Ok(())
}
