//! `volux render` and `volux demo`: a scene built from the arguments ([`crate::settings`]),
//! rendered through the engine API, written as PNG, its figures reported.
use std::path::Path;

use volux_core::heatmap::{heat_map, heat_map_legend_text};
use volux_core::image::PngOptions;
use volux_core::{synth, CameraSpec, Image, TransferFunction};
use volux_io::{Dataset, Format};
use volux_render::engine::Frame;
use volux_render::framing::{visible_bounds_of, Invisible};
use volux_render::scene::{Scene, Volume};
use volux_render::tiles::Control;

use super::common::CmdError;
use super::report;
use crate::cli::{Backend, RenderArgs};
use crate::progress;
use crate::settings::RenderPlan;

/// Renders the file of `args` and writes the PNG (and the error map); a session file is
/// rendered by `session::run` instead (the caller picks).
pub fn run(args: &RenderArgs, show: bool) -> Result<(), CmdError> {
    if args.distributed {
        return super::distributed::run(args);
    }
    let plan = RenderPlan::new(args)?;
    let file = args
        .file
        .as_deref()
        .ok_or("give the file to render, or --session S.json")?;
    let (volume, format, loaded_grid) = match super::bricked::volume(file, args)? {
        Some(v) => (v, volux_io::Format::OmeZarr, false),
        None => {
            crate::settings::check_before_load(file, args)?;
            let (data, format) = super::common::load(file, &args.load, show)?;
            let loaded_grid = matches!(data, Dataset::Grid(_));
            (crate::settings::volume(data, args)?, format, loaded_grid)
        }
    };
    let scene = plan.scene(args, &volume, loaded_grid)?;
    let measured = super::measure::Drawn::pick(args, &volume, &scene, loaded_grid)?;
    let invisible = warn_invisible(&volume, &scene, format);
    if let Some(spec) = &args.orbit {
        return super::orbit::run(args, spec, &volume, &scene, &plan.png);
    }
    let mut frame = render_on(&volume, &scene, show, args.backend)?;
    if let Some(m) = &measured {
        m.draw(&mut frame.image);
    }
    if !invisible && frame.image.coverage(0.0) == 0.0 {
        warn("the image is empty: no ray met a visible sample (check the camera)");
    }
    let output = args.output();
    let replaced = args.output.is_none() && output.exists();
    frame
        .image
        .write_png(&output, &plan.png)
        .map_err(|e| format!("{}: {e}", output.display()))?;
    if let Some(path) = &args.error_map {
        write_error_map(&frame, args.tol, plan.size, path)?;
    }
    if let Some(path) = &args.raw_out {
        super::raw::write_raw(&frame.image, path)?;
    }
    if let Some(m) = &measured {
        m.print()?;
    }
    report::frame(args, &frame, &scene, &volume)?;
    let note = if replaced {
        " (replaced the file there; name the output with -o)"
    } else {
        ""
    };
    eprintln!("wrote {}{note}", output.display());
    Ok(())
}

/// A warning on stderr, the render goes on.
pub fn warn(message: &str) {
    eprintln!("volux: warning: {}", crate::messages::sanitize(message));
}

/// Warns when the scene can show nothing (constant data, a TF transparent over the data's
/// range) or an isosurface lies outside the data; returns whether nothing can show.
fn warn_invisible(volume: &Volume, scene: &Scene, format: Format) -> bool {
    let range = volume.range();
    for iso in scene.appearance.isosurfaces.as_slice() {
        let v = iso.value as f64;
        if v < range[0] || v > range[1] {
            warn(&format!(
                "the isosurface at {v} lies outside the data range [{}, {}]",
                range[0] as f32, range[1] as f32
            ));
        }
    }
    match visible_bounds_of(volume, scene) {
        Ok(_) => false,
        Err(why) => {
            let hint = match (&why, format) {
                (Invisible::Constant(_), Format::Plot3d) => {
                    "; pick another --q-variable (density, momentum-x|y|z, energy, \
                     velocity-magnitude)"
                }
                (Invisible::Transparent { .. }, _) => {
                    "; try --tf auto, or see `volux info` for the data's range"
                }
                _ => "",
            };
            warn(&format!("the image will be empty: {why}{hint}"));
            true
        }
    }
}

/// Writes the per-pixel estimated error as a heat map with its legend.
fn write_error_map(
    frame: &Frame,
    tol: f64,
    (w, h): (usize, usize),
    path: &Path,
) -> Result<(), CmdError> {
    let zeros;
    let errors = match &frame.error_map {
        Some(e) => e.as_slice(),
        None => {
            zeros = vec![0.0; w * h];
            &zeros
        }
    };
    error_image(errors, tol, w, h)?
        .write_png(path, &PngOptions::default())
        .map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!(
        "wrote {} (estimated error per pixel; {})",
        path.display(),
        heat_map_legend_text(tol as f32)
    );
    Ok(())
}

/// Renders one frame of `scene` on the CPU with a progress bar.
pub fn render(volume: &Volume, scene: &Scene, show: bool) -> Result<Frame, CmdError> {
    render_on(volume, scene, show, Backend::Cpu)
}

/// Renders one frame of `scene` on `backend` with a progress bar.
pub fn render_on(
    volume: &Volume,
    scene: &Scene,
    show: bool,
    backend: Backend,
) -> Result<Frame, CmdError> {
    let mut renderer = super::backend::renderer(volume, scene, backend)?;
    let (pb, progress) = progress::rows(show, scene.view.height);
    let control = Control {
        cancel: None,
        progress,
    };
    let frame = renderer.render(scene, &control)?;
    pb.finish_and_clear();
    Ok(frame)
}

/// Per-pixel estimated errors as a heat map from 0 to `tol` (magenta above, as the seed
/// `001`'s figures 5.3 to 5.13 mark rays over the tolerance), with its legend strip.
pub fn error_image(errors: &[f32], tol: f64, w: usize, h: usize) -> Result<Image, CmdError> {
    Ok(heat_map(errors, w, h, tol as f32)?)
}

/// Renders the built-in Marschner-Lobb dataset to `out`.
pub fn demo(out: &Path, show: bool) -> Result<(), CmdError> {
    crate::settings::png_path(out, "--output")?;
    let volume = Volume::from(synth::marschner_lobb(128)?);
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(25.0),
        zoom: Some(1.1),
        ..Default::default()
    };
    let tf = TransferFunction::from_json(DEMO_TF)?;
    let scene = Scene::new(spec.resolve(&volume.bounds())?, 512, 512, tf);
    let frame = render(&volume, &scene, show)?;
    let png = PngOptions {
        background: Some([0.02, 0.02, 0.03]),
        sixteen_bit: false,
    };
    frame
        .image
        .write_png(out, &png)
        .map_err(|e| format!("{}: {e}", out.display()))?;
    let abs = std::env::current_dir()
        .map(|d| d.join(out))
        .unwrap_or(out.to_path_buf());
    outln!(
        "rendered Marschner-Lobb 128^3 at 512x512 in {:.0} ms; wrote {}",
        frame.stats.ms,
        abs.display()
    )?;
    Ok(())
}

/// The demo's transfer function: two translucent shells of the Marschner-Lobb signal, the
/// classic one at 0.5 and a faint one at 0.25.
const DEMO_TF: &str = r#"{
  "color": [[0.0, 0.02, 0.15, 0.5], [0.3, 0.1, 0.45, 0.9], [0.45, 0.95, 0.45, 0.1], [0.55, 1.0, 0.85, 0.3], [1.0, 1.0, 1.0, 1.0]],
  "extinction": [[0.0, 0.0], [0.2, 0.0], [0.25, 0.06], [0.3, 0.0], [0.46, 0.0], [0.5, 0.5], [0.54, 0.0], [1.0, 0.0]]
}"#;
