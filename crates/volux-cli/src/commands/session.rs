//! `volux render --session S.json`: a view saved by `volux-view` rendered in batch. The
//! session holds the whole scene (dataset and reader options, camera, image size, TF,
//! method and every setting, background, clip planes and sculpt steps, seed `004`), so
//! nothing is taken from defaults that could differ, and the PNG equals the viewer's
//! screenshot of the same session. The sculpt steps are replayed on the grid to rebuild
//! its mask ([`Session::scene_on`]), its region labels are coloured and its measurements
//! drawn and printed, as the viewer shows them. `--size`, `--zoom`, `--background` and
//! `--sixteen-bit` override the session for a figure (larger, nearer), each said on stderr.
//! It renders on the session's backend (`auto`, `cpu`, `gpu`; the CPU when it names none)
//! unless `--backend` is given.
use std::path::Path;
use std::sync::Arc;

use volux_app::session::Session;
use volux_core::image::PngOptions;
use volux_core::Grid;
use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::Sculpt;

use super::common::CmdError;
use super::measure::Drawn;
use crate::cli::{Backend, LoadArgs, RenderArgs};

/// Options that may go with `--session`: where the picture goes and renders, and what
/// changes its size or look without changing the scene (each override is said on stderr).
const WITH_SESSION: [&str; 7] = [
    "session",
    "output",
    "backend",
    "size",
    "zoom",
    "background",
    "sixteen-bit",
];

/// Where the session renders: `--backend` when given, else the session's backend, else the
/// CPU engine (the reference, as sessions saved before backends existed were rendered).
fn backend(args: &RenderArgs, session: &Session) -> Backend {
    if args.given("backend") {
        return args.backend;
    }
    session.backend.unwrap_or(Backend::Cpu)
}

/// Renders the session at `path` to `args.output()`: its scene with the overrides given,
/// its region labels coloured and its measurements drawn, as the viewer shows them.
pub fn run(args: &RenderArgs, path: &Path, show: bool) -> Result<(), CmdError> {
    if let Some(o) = args
        .given
        .iter()
        .find(|g| !WITH_SESSION.contains(&g.as_str()))
    {
        return Err(format!(
            "--{o} does not go with --session: the session holds the scene (open it in \
             volux-view to change it); --size, --zoom, --background, --sixteen-bit, \
             --backend and -o may override it"
        )
        .into());
    }
    let output = args.output();
    crate::settings::png_path(&output, "--output")?;
    let session = Session::load(path)?;
    let d = &session.dataset;
    let load = LoadArgs {
        q_variable: d.q_variable.clone(),
        q_file: d.q_file.clone(),
        series: d.series_uid.clone(),
        array: d.array.clone(),
        channel: d.channel,
        timepoint: d.timepoint,
        component: d.component,
        ..LoadArgs::default()
    };
    let (data, _) = super::common::load(&d.path, &load, show)
        .map_err(|e| format!("session {}: its dataset: {e}", path.display()))?;
    let mut volume = crate::settings::plain_volume(data)?;
    let mesh_method = session.method.draws_tets();
    if mesh_method && matches!(volume, Volume::Grid(_)) {
        volume = volume.to_tets()?;
    }
    let (mut scene, sculpt) = session.scene_on(&volume)?;
    let png = overrides(args, &session, &mut scene)?;
    scene
        .method
        .resolve(&volume)?
        .check_appearance(&scene.appearance)?;
    let measured = match (&sculpt, &volume) {
        (Some(sculpt), Volume::Grid(grid)) => {
            add_labels(sculpt, grid, &mut scene)?;
            Drawn::of_session(&sculpt.measurements(), &scene, grid.unit())
        }
        _ => Vec::new(),
    };
    let mut frame = super::render::render_on(&volume, &scene, show, backend(args, &session))?;
    for m in &measured {
        m.draw(&mut frame.image);
    }
    frame
        .image
        .write_png(&output, &png)
        .map_err(|e| format!("{}: {e}", output.display()))?;
    for m in &measured {
        m.print()?;
    }
    eprintln!(
        "wrote {} ({}x{}, {:.0} ms)",
        output.display(),
        scene.view.width,
        scene.view.height,
        frame.stats.ms
    );
    Ok(())
}

/// Applies the overrides given beside `--session` to `scene` (size, zoom) and returns the
/// PNG options (background, bit depth), saying on stderr what each one replaces.
fn overrides(
    args: &RenderArgs,
    session: &Session,
    scene: &mut Scene,
) -> Result<PngOptions, CmdError> {
    let mut png = session.png_options();
    if args.given("size") {
        let (w, h) = crate::settings::parse_size(&args.view_args.size)?;
        eprintln!(
            "volux: --size {w}x{h} replaces the session's {}x{} (the same view, its height \
             kept)",
            scene.view.width, scene.view.height
        );
        (scene.view.width, scene.view.height) = (w, h);
    }
    if args.given("zoom") {
        let zoom = args.view_args.zoom;
        scene.view.camera = scene
            .view
            .camera
            .zoomed(zoom)
            .map_err(|e| format!("--zoom {zoom}: {e}"))?;
        eprintln!("volux: --zoom {zoom} zooms the session's camera");
    }
    if args.given("background") {
        png.background = crate::settings::parse_background(&args.background)?;
        let was = match session.background {
            Some([r, g, b]) => format!("{r},{g},{b}"),
            None => "none".into(),
        };
        eprintln!(
            "volux: --background {} replaces the session's {was}",
            args.background
        );
    }
    if args.sixteen_bit {
        png.sixteen_bit = true;
    }
    Ok(png)
}

/// Colours the session's region labels in `scene` as the viewer does (its seeds' nearest
/// visible voxels, [`Sculpt::label_volume`]), or says why this scene cannot draw them.
fn add_labels(sculpt: &Sculpt, grid: &Grid, scene: &mut Scene) -> Result<(), CmdError> {
    if sculpt.label_seeds().is_empty() {
        return Ok(());
    }
    if let Some(why) = scene.labels_not_drawn() {
        super::render::warn(&format!("the session's region labels are not drawn: {why}"));
        return Ok(());
    }
    scene.labels = Some(Arc::new(sculpt.label_volume(grid, scene)?));
    Ok(())
}
