//! `volux-view [FILE|SESSION.json]`: the interactive viewer (see the crate documentation
//! and the README's viewer guide); `--screenshot OUT.png` renders the fully refined view and
//! exits; `--bench` runs the viewer benchmark without a window.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use eframe::egui;
use volux_app::{words, Backend};
use volux_render::bricked::Lod;
use volux_viewer::app::{Options, ViewerApp};

/// The interactive viewer of Volux.
#[derive(Parser, Debug)]
#[command(name = "volux-view", version, about)]
struct Args {
    /// A dataset (any format `volux` reads, or a DICOM folder) or a session JSON.
    path: Option<PathBuf>,
    /// Write the fully refined 3D view to this PNG and exit.
    #[arg(long, value_name = "OUT.png")]
    screenshot: Option<PathBuf>,
    /// Render size of the 3D view for --screenshot and --bench, WxH.
    #[arg(long, value_name = "WxH", value_parser = words::image_size)]
    size: Option<(usize, usize)>,
    /// With --screenshot: also save the session here.
    #[arg(long, value_name = "S.json")]
    save_session: Option<PathBuf>,
    /// Run the viewer benchmark on the given dataset(s) without a window; JSON lines out.
    #[arg(long)]
    bench: bool,
    /// For an OME-Zarr store: the level it refines to, auto (voxels about a pixel) or a
    /// level number (0 = full resolution).
    #[arg(long, value_name = "auto|N", default_value = "auto", value_parser = words::level)]
    lod: Lod,
    /// The memory budget of an OME-Zarr store's brick cache (4G, 512M, 50%); default: a
    /// quarter of the available memory, as the CLI's. The images and slices are not counted
    /// in it: a small cache shows the coarse level first and refines, reading chunks again.
    #[arg(long, value_name = "SIZE", value_parser = words::memory_budget)]
    memory_budget: Option<u64>,
    /// Where frames are rendered: auto (the GPU when there is an adapter and it draws the
    /// scene, else the CPU), cpu, or gpu (an error shown in the view when it cannot).
    #[arg(long, value_name = "auto|cpu|gpu", default_value = "auto", value_parser = Backend::parse)]
    backend: Backend,
    /// OME-Zarr, ImageJ hyperstacks and OME-TIFF: the channel to show [default: 0].
    #[arg(long)]
    channel: Option<usize>,
    /// Files holding several volumes (4-D NIfTI, NRRD, DICOM series with several stacks,
    /// OME-Zarr, ImageJ hyperstacks, OME-TIFF): the timepoint to show [default: 0].
    #[arg(long)]
    timepoint: Option<usize>,
    /// Vector and colour volumes: the component shown as the scalar [default: the first
    /// component of a vector; a colour image keeps its colour].
    #[arg(long)]
    component: Option<usize>,
    /// Seconds of scripted orbit in --bench.
    #[arg(long, default_value_t = 3.0)]
    bench_seconds: f64,
}

fn main() -> ExitCode {
    #[cfg(feature = "gpu")]
    volux_gpu::quiet_headless_vulkan();
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("volux-view: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<(), String> {
    let (size, lod) = (args.size, args.lod);
    if let Some(b) = args.memory_budget {
        volux_viewer::store::set_cache_budget(b);
    }
    if let Some(p) = &args.screenshot {
        volux_viewer::png_path(p)?;
    }
    if args.bench {
        let path = args.path.ok_or("--bench needs a dataset")?;
        let size = size.unwrap_or((800, 600));
        let report = volux_viewer::bench::run(&path, size, args.bench_seconds, lod)?;
        println!(
            "{}",
            serde_json::to_string(&report).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    let options = Options {
        open: args.path,
        screenshot: args.screenshot,
        size,
        save_session: args.save_session,
        lod,
        backend: args.backend,
        channel: args.channel,
        timepoint: args.timepoint,
        component: args.component,
    };
    if options.screenshot.is_some() && !volux_viewer::headless::have_display() {
        // No window to open: the same frames run without one.
        let screenshot = options.screenshot.clone();
        volux_viewer::headless::screenshot(options)?;
        return written(screenshot);
    }
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("volux-view")
            .with_inner_size(volux_viewer::headless::WINDOW)
            .with_drag_and_drop(true),
        ..Default::default()
    };
    let screenshot = options.screenshot.clone();
    eframe::run_native(
        "volux-view",
        native,
        Box::new(move |cc| Ok(Box::new(ViewerApp::new(&cc.egui_ctx, options)))),
    )
    .map_err(|e| format!("cannot open a window: {e} (is a display available? set DISPLAY)"))?;
    written(screenshot)
}

/// `Ok` unless a screenshot was asked for and not written (the viewer said why).
fn written(screenshot: Option<PathBuf>) -> Result<(), String> {
    match screenshot {
        Some(p) if !p.exists() => Err(format!("{}: no screenshot was written", p.display())),
        _ => Ok(()),
    }
}
