//! `volux render` and `volux demo`.
use std::path::Path;

use volux_core::histogram::Histogram;
use volux_core::image::PngOptions;
use volux_core::{synth, CameraSpec, Image, TransferFunction};
use volux_io::Dataset;
use volux_render::integrate::{AdaptiveParams, Integrator, StepControl};
use volux_render::isosurface::{parse_iso, Isosurfaces};
use volux_render::raycast::render_field;
use volux_render::raycast::Rendered;
use volux_render::resample::resample_mesh;
use volux_render::sampling::Reconstruction;
use volux_render::sampling::Trilinear;
use volux_render::shading::{BlinnPhong, Light};
use volux_render::{render_grid, RenderOptions, RenderStats};

use super::CmdError;
use crate::cli::RenderArgs;
use crate::progress;

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(usize, usize), CmdError> {
    let bad = || format!("--size '{s}': expected WxH, e.g. 512x512, each 1..=16384");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (usize, usize) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(bad().into());
    }
    Ok((w, h))
}

fn parse_background(s: &str) -> Result<Option<[f32; 3]>, CmdError> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--background '{s}': expected R,G,B in 0..1 or 'none'"))?;
    match v.as_slice() {
        [r, g, b] if v.iter().all(|c| (0.0..=1.0).contains(c)) => Ok(Some([*r, *g, *b])),
        _ => Err(format!("--background '{s}': expected three values in 0..1 or 'none'").into()),
    }
}

/// A preset name or a JSON file, with presets scaled to `unit_length` world units.
pub fn transfer_function(
    spec: &str,
    hist: &Histogram,
    unit_length: f64,
) -> Result<TransferFunction, CmdError> {
    let path = Path::new(spec);
    let tf = if spec.ends_with(".json") || path.is_file() {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{spec}: {e}"))?;
        TransferFunction::from_json(&text).map_err(|e| format!("{spec}: {e}"))?
    } else {
        TransferFunction::preset(spec, hist)?.with_unit_length(unit_length)
    };
    Ok(tf)
}

/// Blinn-Phong parameters from the command line.
fn shading(args: &RenderArgs) -> Result<Option<BlinnPhong>, CmdError> {
    if !args.shade {
        return Ok(None);
    }
    blinn_phong(args).map(Some)
}

/// The lighting parameters of the command line (used by `--shade` and by PT isosurfaces).
pub fn blinn_phong(args: &RenderArgs) -> Result<BlinnPhong, CmdError> {
    let light = if args.light == "headlight" {
        Light::Headlight
    } else {
        let v: Vec<f32> = args
            .light
            .split(',')
            .map(|c| c.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("--light '{}': expected X,Y,Z or 'headlight'", args.light))?;
        match v.as_slice() {
            [x, y, z] => Light::Direction(glam::Vec3::new(*x, *y, *z)),
            _ => {
                return Err(
                    format!("--light '{}': expected X,Y,Z or 'headlight'", args.light).into(),
                )
            }
        }
    };
    let s = BlinnPhong {
        ambient: args.ambient,
        diffuse: args.diffuse,
        specular: args.specular,
        shininess: args.shininess,
        light,
        ..BlinnPhong::default()
    };
    s.validate()?;
    Ok(s)
}

/// The `--iso` options.
pub fn isosurfaces(args: &RenderArgs) -> Result<Isosurfaces, CmdError> {
    let values = args
        .isos
        .iter()
        .map(|s| parse_iso(s).map_err(|e| format!("--iso '{s}': {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Isosurfaces::new(values)?)
}

/// The integrator named on the command line.
pub fn integrator(args: &RenderArgs) -> Result<Integrator, CmdError> {
    let adaptive = |control| {
        Integrator::AdaptiveSimpson(AdaptiveParams {
            tol: args.tol,
            h0: args.h0,
            hmin: args.hmin,
            hmax: args.hmax,
            control,
            early_termination: None,
        })
    };
    let control = if args.decoupled {
        StepControl::Decoupled
    } else {
        StepControl::Coupled
    };
    Ok(match args.integrator.as_str() {
        "riemann" => Integrator::Riemann { step: args.step },
        "trapezoid" => Integrator::Trapezoid { step: args.step },
        "simpson" => Integrator::Simpson { step: args.step },
        "adaptive-simpson" | "adaptive" => adaptive(control),
        "preintegrated" => Integrator::Preintegrated { step: args.step },
        "reference" => Integrator::Reference,
        other => {
            return Err(format!(
                "unknown integrator '{other}' (riemann, trapezoid, simpson, adaptive-simpson, preintegrated, reference)"
            )
            .into())
        }
    })
}

pub fn camera_spec(args: &RenderArgs) -> Result<CameraSpec, CmdError> {
    if let Some(p) = &args.camera {
        let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
        return Ok(CameraSpec::from_json(&text).map_err(|e| format!("{}: {e}", p.display()))?);
    }
    Ok(CameraSpec {
        projection: Some(
            if args.orthographic {
                "orthographic"
            } else {
                "perspective"
            }
            .into(),
        ),
        azimuth: args.azimuth,
        elevation: args.elevation,
        zoom: Some(args.zoom),
        ..Default::default()
    })
}

pub fn run(args: &RenderArgs, show: bool) -> Result<(), CmdError> {
    let (w, h) = parse_size(&args.size)?;
    let background = parse_background(&args.background)?;
    let spec = camera_spec(args)?;
    let mesh_integrator = matches!(args.integrator.as_str(), "exact" | "psi");
    let integrator = if mesh_integrator {
        Integrator::Riemann { step: args.step }
    } else {
        integrator(args)?
    };
    integrator.validate()?;
    let (data, _) = super::load(&args.file, &args.load, show)?;
    let png = PngOptions {
        background,
        sixteen_bit: args.sixteen_bit,
    };
    if let Some(mesh) = super::render_pt::mesh_for_pt(&data, args)? {
        return super::render_pt::run(&mesh, args, &spec, (w, h), &png);
    }
    if let (Dataset::Mesh(mesh), "raycast") = (&data, args.method.as_str()) {
        return super::render_pt::run_raycast(mesh, args, &spec, (w, h), &png);
    }
    if mesh_integrator {
        return Err(format!(
            "--integrator {} applies to tetrahedral meshes (--method raycast)",
            args.integrator
        )
        .into());
    }
    let out = render_dataset(&data, args, integrator, &spec, (w, h), show)?;
    out.image
        .write_png(&args.output, &png)
        .map_err(|e| format!("{}: {e}", args.output.display()))?;
    if let Some(path) = &args.error_map {
        error_map_image(&out, args.tol, w, h)
            .write_png(path, &PngOptions::default())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    report(args, &out.stats, w, h);
    Ok(())
}

fn render_dataset(
    data: &Dataset,
    args: &RenderArgs,
    integrator: Integrator,
    spec: &CameraSpec,
    (w, h): (usize, usize),
    show: bool,
) -> Result<Rendered, CmdError> {
    let (bounds, hist, unit) = match data {
        Dataset::Grid(g) => (
            g.bounds(),
            Histogram::of_grid(g, 256),
            g.spacing().min_element(),
        ),
        Dataset::Mesh(m) => {
            let b = m.bounds();
            (
                b,
                Histogram::from_values(m.scalars(), m.range(), 256),
                b.diagonal() / 256.0,
            )
        }
        _ => return Err("unsupported dataset kind".into()),
    };
    let tf = transfer_function(&args.tf, &hist, unit)?.with_opacity_scale(args.opacity_scale);
    let camera = spec.resolve(&bounds)?;
    let mut opts = RenderOptions::new(camera, tf);
    (opts.width, opts.height, opts.integrator) = (w, h, integrator);
    opts.jitter = args.jitter;
    opts.mip = args.mip;
    opts.reconstruction = match args.reconstruction.as_str() {
        "trilinear" => Reconstruction::Trilinear,
        "catmull-rom" => Reconstruction::CatmullRom,
        "b-spline" | "bspline" => Reconstruction::BSpline,
        other => {
            return Err(format!(
                "unknown reconstruction '{other}' (trilinear, catmull-rom, b-spline)"
            )
            .into())
        }
    };
    opts.shading = shading(args)?;
    opts.isosurfaces = isosurfaces(args)?;
    if args.no_early_termination || integrator == Integrator::Reference {
        opts.early_termination = None;
    }
    let (pb, progress) = progress::rows(show, h);
    opts.control.progress = progress;
    let out = match data {
        Dataset::Grid(g) => render_grid(g, &opts)?,
        Dataset::Mesh(m) => {
            let r = resample_mesh(m, args.resample)?;
            let field = Trilinear::new(&r.values, r.place.dims);
            render_field(&field, r.place, m.range(), &opts)?
        }
        _ => unreachable!("checked above"),
    };
    pb.finish_and_clear();
    Ok(out)
}

/// The estimated error per pixel as an image: black (0) to white (`tol`), pixels above the
/// tolerance in magenta (as the seed's figures 5.3 to 5.13).
fn error_map_image(out: &Rendered, tol: f64, w: usize, h: usize) -> Image {
    error_image(&out.error_map, tol, w, h).expect("one error per pixel")
}

/// Per-pixel estimated errors as an image: black (0) to white (`tol`), above `tol` magenta.
pub fn error_image(errors: &[f32], tol: f64, w: usize, h: usize) -> Result<Image, CmdError> {
    let pixels = errors
        .iter()
        .map(|&e| {
            if e as f64 > tol {
                [1.0, 0.0, 1.0, 1.0]
            } else {
                let v = (e as f64 / tol) as f32;
                [v, v, v, 1.0]
            }
        })
        .collect();
    Ok(Image::from_pixels(w, h, pixels)?)
}

fn report(args: &RenderArgs, s: &RenderStats, w: usize, h: usize) {
    if args.stats && args.json {
        let v = serde_json::json!({
            "ms": s.seconds * 1e3,
            "width": w,
            "height": h,
            "rays": s.rays,
            "samples": s.samples,
            "samples_per_s": s.samples as f64 / s.seconds.max(1e-9),
            "rays_over_tolerance": s.rays_over_tolerance,
            "integrator": args.integrator,
            "threads": rayon::current_num_threads(),
        });
        println!("{v}");
    } else if args.stats {
        eprintln!(
            "{w}x{h}: {:.1} ms, {} rays, {} samples, {:.1} M samples/s",
            s.seconds * 1e3,
            s.rays,
            s.samples,
            s.samples as f64 / s.seconds.max(1e-9) / 1e6
        );
    }
    if !(args.stats && args.json) {
        eprintln!("wrote {}", args.output.display());
    }
}

/// Renders the built-in Marschner-Lobb dataset to `demo.png`.
pub fn demo(show: bool) -> Result<(), CmdError> {
    let grid = synth::marschner_lobb(128)?;
    let tf = TransferFunction::from_json(DEMO_TF)?;
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(25.0),
        zoom: Some(1.1),
        ..Default::default()
    };
    let mut opts = RenderOptions::new(spec.resolve(&grid.bounds())?, tf);
    let (pb, progress) = progress::rows(show, opts.height);
    opts.control.progress = progress;
    let Rendered { image, stats, .. } = render_grid(&grid, &opts)?;
    pb.finish_and_clear();
    let out = Path::new("demo.png");
    let png = PngOptions {
        background: Some([0.02, 0.02, 0.03]),
        sixteen_bit: false,
    };
    image
        .write_png(out, &png)
        .map_err(|e| format!("{}: {e}", out.display()))?;
    let abs = std::env::current_dir()
        .map(|d| d.join(out))
        .unwrap_or(out.to_path_buf());
    println!(
        "rendered Marschner-Lobb 128^3 at 512x512 in {:.0} ms; wrote {}",
        stats.seconds * 1e3,
        abs.display()
    );
    Ok(())
}

/// The demo's transfer function: two translucent shells of the Marschner-Lobb signal, the
/// classic one at 0.5 and a faint one at 0.25.
const DEMO_TF: &str = r#"{
  "color": [[0.0, 0.02, 0.15, 0.5], [0.3, 0.1, 0.45, 0.9], [0.45, 0.95, 0.45, 0.1], [0.55, 1.0, 0.85, 0.3], [1.0, 1.0, 1.0, 1.0]],
  "extinction": [[0.0, 0.0], [0.2, 0.0], [0.25, 0.06], [0.3, 0.0], [0.46, 0.0], [0.5, 0.5], [0.54, 0.0], [1.0, 0.0]]
}"#;
