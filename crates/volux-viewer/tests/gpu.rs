//! The viewer on the GPU backend (`--backend gpu` and `auto`): the render thread draws on
//! the adapter, each frame says so, its picture is the CPU's, and what the GPU does not
//! draw is shown as an error (`gpu`) or drawn on the CPU (`auto`). On lavapipe in CI
//! (`VOLUX_GPU_REQUIRED=1`); skipped with a message on a machine without an adapter.
#![cfg(feature = "gpu")]
use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use volux_core::{synth, CameraSpec};
use volux_render::integrate::Integrator;
use volux_render::scene::{GridRaycast, Method, Scene, SlicingSettings, Volume};
use volux_viewer::app::{Options, ViewerApp};
use volux_viewer::backend::{Backend, Device};
use volux_viewer::render_service::{Event, FinishedFrame, RenderService, VolumeRef};

/// Whether this machine has an adapter (a skip message when not, a failure in CI).
fn have_adapter() -> bool {
    match volux_gpu::GpuContext::new() {
        Ok(_) => true,
        Err(e) if std::env::var_os("VOLUX_GPU_REQUIRED").is_none() => {
            eprintln!("SKIPPED: no GPU adapter ({e}); set VOLUX_GPU_REQUIRED=1 to fail instead");
            false
        }
        Err(e) => panic!("VOLUX_GPU_REQUIRED is set and there is no adapter: {e}"),
    }
}

fn volume() -> VolumeRef {
    VolumeRef {
        id: 1,
        volume: Volume::from(synth::marschner_lobb(24).unwrap()),
    }
}

fn scene(v: &VolumeRef) -> Scene {
    let camera = CameraSpec::default().resolve(&v.volume.bounds()).unwrap();
    Scene::new(camera, 64, 64, v.volume.preset_tf("auto").unwrap())
}

/// The full frame of `scene` on `backend` (previews skipped), or the failure's message.
fn full_frame(backend: Backend, v: &VolumeRef, scene: &Scene) -> Result<FinishedFrame, String> {
    let mut service = RenderService::start_on(|| {}, backend);
    service.submit(v, scene, false);
    loop {
        match service.wait(Duration::from_secs(60)).expect("an event") {
            Event::Frame(f) if f.full => return Ok(*f),
            Event::Frame(_) => {}
            Event::Failed { message, .. } => return Err(message),
        }
    }
}

/// The render thread draws on the adapter, says so, and draws the CPU's picture (mean under
/// 1/255, max 1e-4: the GPU's `f32` positions).
#[test]
fn the_render_thread_draws_on_the_gpu_the_cpus_picture() {
    if !have_adapter() {
        return;
    }
    let v = volume();
    let s = scene(&v);
    let gpu = full_frame(Backend::Gpu, &v, &s).unwrap();
    let cpu = full_frame(Backend::Cpu, &v, &s).unwrap();
    assert!(
        matches!(&gpu.device, Device::Gpu(name) if !name.is_empty()),
        "{:?}",
        gpu.device
    );
    assert_eq!(cpu.device, Device::Cpu);
    assert!(gpu.device.to_string().starts_with("GPU: "));
    let (mut sum, mut max) = (0.0f64, 0.0f32);
    for (a, b) in gpu.image.pixels().iter().zip(cpu.image.pixels()) {
        for c in 0..4 {
            let d = (a[c] - b[c]).abs();
            sum += f64::from(d);
            max = max.max(d);
        }
    }
    let mean = sum / (4 * gpu.image.pixels().len()) as f64;
    eprintln!("viewer GPU frame against CPU: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean < 1.0 / 255.0 && max < 1e-4,
        "mean {mean:e}, max {max:e}"
    );
}

/// What the GPU does not draw (here the Simpson rule): `gpu` shows why,
/// `auto` draws it on the CPU.
#[test]
fn what_the_gpu_does_not_draw_is_an_error_on_gpu_and_the_cpus_on_auto() {
    if !have_adapter() {
        return;
    }
    let v = volume();
    let mut s = scene(&v);
    s.method = Method::GridRaycast(GridRaycast {
        integrator: Integrator::Simpson { step: 0.5 },
        ..GridRaycast::default()
    });
    let err = full_frame(Backend::Gpu, &v, &s).unwrap_err();
    assert!(err.contains("simpson"), "{err}");
    let auto = full_frame(Backend::Auto, &v, &s).unwrap();
    assert_eq!(auto.device, Device::Cpu);
    // A scene the GPU draws: on a hardware adapter `auto` takes it; a software one
    // (llvmpipe, as in CI) is never preferred to the CPU engine.
    let plain = scene(&v);
    let auto = full_frame(Backend::Auto, &v, &plain).unwrap();
    let software = volux_gpu::GpuContext::new()
        .unwrap()
        .adapter()
        .is_software();
    if software {
        assert_eq!(auto.device, Device::Cpu);
    } else {
        assert!(matches!(auto.device, Device::Gpu(_)), "{:?}", auto.device);
    }
    let gpu = full_frame(Backend::Gpu, &v, &plain).unwrap();
    assert!(matches!(gpu.device, Device::Gpu(_)), "{:?}", gpu.device);
}

/// Texture slicing (`--method slicing`) is drawn on the GPU on `auto` (a software adapter
/// too: only the GPU draws it), and refused with why on `cpu`.
#[test]
fn texture_slicing_is_drawn_on_the_gpu() {
    if !have_adapter() {
        return;
    }
    let v = volume();
    let mut s = scene(&v);
    s.method = Method::Slicing(SlicingSettings::default());
    let frame = full_frame(Backend::Auto, &v, &s).unwrap();
    assert!(matches!(frame.device, Device::Gpu(_)), "{:?}", frame.device);
    assert!(
        frame.image.coverage(0.01) > 0.1,
        "the slices show the volume"
    );
    let err = full_frame(Backend::Cpu, &v, &s).unwrap_err();
    assert!(err.contains("GPU method"), "{err}");
}

/// A store's frames go through the application layer's factory like a grid's: on `gpu`
/// every level of the refinement is drawn by the GPU's brick pool, and the final level is
/// the CPU's picture of that level.
#[test]
fn a_stores_levels_are_drawn_by_the_gpus_brick_pool() {
    use std::sync::Arc;
    use volux_core::bricked::GridChunks;
    use volux_io::omezarr::{write_ome_zarr, Levels, WriteOptions};
    use volux_render::bricked::Lod;
    if !have_adapter() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ml.ome.zarr");
    let grid = Arc::new(synth::marschner_lobb(32).unwrap());
    let chunks = GridChunks::new(grid, [16, 16, 16]).unwrap();
    let opts = WriteOptions {
        levels: Levels::Auto,
        name: "ml".into(),
        ..WriteOptions::default()
    };
    write_ome_zarr(&chunks, &path, &opts).unwrap();
    let store =
        volux_app::store::open_store(&volux_app::session::DatasetRef::at(&path), 64 << 20).unwrap();
    let v = VolumeRef {
        id: 7,
        volume: Volume::Bricked(store.volume, Lod::Level(0)),
    };
    let s = scene(&v);
    let mut service = RenderService::start_on(|| {}, Backend::Gpu);
    service.submit(&v, &s, false);
    let mut levels = Vec::new();
    let gpu = loop {
        match service.wait(Duration::from_secs(60)).expect("an event") {
            Event::Frame(f) => {
                assert!(matches!(f.device, Device::Gpu(_)), "{:?}", f.device);
                levels.push(f.level.expect("a store's frame names its level").level);
                if f.full {
                    break f;
                }
            }
            Event::Failed { message, .. } => panic!("{message}"),
        }
    };
    assert_eq!(
        levels.first(),
        Some(&1),
        "the coarsest level first: {levels:?}"
    );
    assert_eq!(levels.last(), Some(&0), "{levels:?}");
    let cpu = full_frame(Backend::Cpu, &v, &s).unwrap();
    assert_eq!(cpu.device, Device::Cpu);
    let mean = gpu
        .image
        .pixels()
        .iter()
        .zip(cpu.image.pixels())
        .map(|(a, b)| (0..4).map(|c| f64::from((a[c] - b[c]).abs())).sum::<f64>())
        .sum::<f64>()
        / (4 * gpu.image.pixels().len()) as f64;
    assert!(mean < 1.0 / 255.0, "mean {mean}");
    assert!(gpu.image.coverage(0.01) > 0.1, "the store is drawn");
}

/// The window with `--backend gpu` opens a grid and shows a full frame drawn on the GPU.
#[test]
fn the_window_shows_frames_drawn_on_the_gpu() {
    if !have_adapter() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("ml.raw");
    volux_io::raw::write(&synth::marschner_lobb(24).unwrap(), &path).unwrap();
    let options = Options {
        open: Some(path),
        backend: Backend::Gpu,
        ..Default::default()
    };
    let mut h = Harness::builder()
        .with_size([900.0, 700.0])
        .with_max_steps(8)
        .build_state(
            move |ctx, app: &mut Option<ViewerApp>| {
                app.get_or_insert_with(|| ViewerApp::new(ctx, options.clone()));
                volux_viewer::window::frame(app.as_mut().unwrap(), ctx)
            },
            None,
        );
    let start = Instant::now();
    loop {
        h.step();
        if let Some(app) = h.state().as_ref().filter(|a| a.shown_full()) {
            let device = app.shown_device();
            assert!(matches!(device, Some(Device::Gpu(_))), "{device:?}");
            return;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no full frame");
        std::thread::sleep(Duration::from_millis(10));
    }
}
