//! `volux render --session S.json`: a view saved by `volux-view` rendered in batch. The
//! session holds the whole scene (dataset and reader options, camera, image size, TF,
//! method and every setting, background, clip planes and sculpt steps, seed `004`), so
//! nothing is taken from defaults that could differ, and the PNG equals the viewer's
//! screenshot of the same session. The sculpt steps are replayed on the grid to rebuild
//! its mask ([`Session::scene_on`]). It renders on the session's backend (`auto`, `cpu`,
//! `gpu`; the CPU when it names none) unless `--backend` is given.
use std::path::Path;

use volux_render::scene::Volume;
use volux_render::session::{Session, SessionBackend};

use super::common::CmdError;
use crate::cli::{Backend, LoadArgs, RenderArgs};

/// Options that may go with `--session` (the rest is in the session).
const WITH_SESSION: [&str; 3] = ["session", "output", "backend"];

/// Where the session renders: `--backend` when given, else the session's backend, else the
/// CPU engine (the reference, as sessions saved before backends existed were rendered).
fn backend(args: &RenderArgs, session: &Session) -> Backend {
    if args.given("backend") {
        return args.backend;
    }
    match session.backend {
        Some(SessionBackend::Auto) => Backend::Auto,
        Some(SessionBackend::Gpu) => Backend::Gpu,
        Some(SessionBackend::Cpu) | None => Backend::Cpu,
    }
}

/// Renders the session at `path` to `args.output()`.
pub fn run(args: &RenderArgs, path: &Path, show: bool) -> Result<(), CmdError> {
    if let Some(o) = args
        .given
        .iter()
        .find(|g| !WITH_SESSION.contains(&g.as_str()))
    {
        return Err(format!(
            "--{o} does not go with --session: the session holds the whole scene \
             (open it in volux-view to change it)"
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
    let (scene, _) = session.scene_on(&volume)?;
    scene
        .method
        .resolve(&volume)?
        .check_appearance(&scene.appearance)?;
    let frame = super::render::render_on(&volume, &scene, show, backend(args, &session))?;
    frame
        .image
        .write_png(&output, &session.png_options())
        .map_err(|e| format!("{}: {e}", output.display()))?;
    eprintln!(
        "wrote {} ({}x{}, {:.0} ms)",
        output.display(),
        scene.view.width,
        scene.view.height,
        frame.stats.ms
    );
    Ok(())
}
