//! `volux accuracy`: how far Riemann sums and adaptive Simpson are from the f64 reference, as
//! the percentage of rays whose error exceeds a threshold per channel (`001_...txt` sec. 5,
//! tables B.1, B.2, 5.5).
use std::path::PathBuf;

use serde_json::json;
use volux_core::histogram::Histogram;
use volux_core::{synth, CameraSpec, Grid, Image};
use volux_io::Dataset;
use volux_render::integrate::{AdaptiveParams, Integrator, StepControl};
use volux_render::raycast::GridRenderer;
use volux_render::RenderOptions;

use super::render::{parse_size, transfer_function};
use super::CmdError;
use crate::cli::LoadArgs;

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

fn load_grid(args: &Args, show: bool) -> Result<Grid, CmdError> {
    let name = args.file.to_string_lossy();
    if synth::GENERATORS[..3].contains(&name.as_ref()) {
        return Ok(synth::generate_grid(&name, 64)?);
    }
    match super::load(&args.file, &args.load, show)?.0 {
        Dataset::Grid(g) => Ok(g),
        _ => Err("accuracy works on regular grids".into()),
    }
}

/// Percentage of pixels whose error exceeds `eps`, per channel.
fn pct_over(a: &Image, reference: &Image, eps: f64) -> [f64; 4] {
    let n = a.pixels().len().max(1) as f64;
    std::array::from_fn(|c| {
        let over = a
            .pixels()
            .iter()
            .zip(reference.pixels())
            .filter(|(p, q)| ((p[c] - q[c]).abs() as f64) > eps);
        100.0 * over.count() as f64 / n
    })
}

pub fn run(args: &Args, show: bool) -> Result<(), CmdError> {
    let (w, h) = parse_size(&args.size)?;
    let grid = load_grid(args, show)?;
    let hist = Histogram::of_grid(&grid, 256);
    let tf = transfer_function(&args.tf, &hist, grid.spacing().min_element())?;
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let mut opts = RenderOptions::new(spec.resolve(&grid.bounds())?, tf);
    (opts.width, opts.height, opts.early_termination) = (w, h, None);
    let renderer = GridRenderer::new(&grid);
    let mut render = |integrator| {
        opts.integrator = integrator;
        renderer.render(&opts)
    };
    let reference = render(Integrator::Reference)?;
    let mut rows = Vec::new();
    for step in [0.5, 0.4, 0.3, 0.2, 0.1] {
        let r = render(Integrator::Riemann { step })?;
        rows.push(Row {
            method: "riemann",
            param: ("step", step),
            threshold: args.eps,
            pct_over: pct_over(&r.image, &reference.image, args.eps),
            samples: r.stats.samples,
            seconds: r.stats.seconds,
        });
    }
    for (method, control) in [
        ("adaptive-coupled", StepControl::Coupled),
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
                pct_over: pct_over(&r.image, &reference.image, tol),
                samples: r.stats.samples,
                seconds: r.stats.seconds,
            });
        }
    }
    print_rows(&rows, args.json, reference.stats.seconds);
    Ok(())
}

fn print_rows(rows: &[Row], as_json: bool, reference_seconds: f64) {
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
        println!("{}", serde_json::Value::Array(list));
        return;
    }
    println!("reference (f64, adaptive 1e-7, split at voxel boundaries): {reference_seconds:.2} s");
    println!(
        "{:<20} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>12} {:>9}",
        "method", "param", "eps", "%R>eps", "%G>eps", "%B>eps", "%A>eps", "samples", "seconds"
    );
    for r in rows {
        println!(
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
        );
    }
}
