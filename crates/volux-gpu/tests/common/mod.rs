//! What the GPU tests share: the device (or a skip), a test grid and TF, scenes, the CPU
//! engine's picture and the comparison.
#![allow(dead_code)]
use std::sync::Arc;

use volux_core::grid::{Buffer, Samples};
use volux_core::{CameraSpec, Grid, Image, TransferFunction};
use volux_gpu::GpuContext;
use volux_render::engine::create_renderer;
use volux_render::integrate::Integrator;
use volux_render::scene::{GridRaycast, Method, Scene, Volume};
use volux_render::tiles::Control;

/// The device, or `None` (with a message) when there is none and none is required.
pub fn context() -> Option<Arc<GpuContext>> {
    match GpuContext::new() {
        Ok(c) => {
            eprintln!("GPU adapter: {}", c.adapter());
            Some(Arc::new(c))
        }
        Err(e) if std::env::var_os("VOLUX_GPU_REQUIRED").is_none() => {
            eprintln!("SKIPPED: no GPU adapter ({e}); set VOLUX_GPU_REQUIRED=1 to fail instead");
            None
        }
        Err(e) => panic!("VOLUX_GPU_REQUIRED is set and there is no adapter: {e}"),
    }
}

/// A smooth field with structure everywhere, odd sizes, anisotropic spacing, offset origin.
pub fn grid() -> Grid {
    let [nx, ny, nz] = [37usize, 30, 23];
    let mut v = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let [x, y, z] = [i as f32 / 36.0, j as f32 / 29.0, k as f32 / 22.0];
                let r = ((x - 0.5).powi(2) + (y - 0.45).powi(2) + (z - 0.55).powi(2)).sqrt();
                v.push(100.0 * (1.0 - r) + 20.0 * (7.0 * x).sin() * (5.0 * y).cos());
            }
        }
    }
    let samples = Samples::F32(Buffer::owned(v));
    Grid::new([nx, ny, nz], [0.8, 1.1, 1.7], [-3.0, 2.0, 5.0], samples).unwrap()
}

pub fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"color": [[40,0.2,0.4,1],[70,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[40,0],[60,0.08],[75,0.3],[90,0.05],[110,0.4]]}"#,
    )
    .unwrap()
}

pub fn scene(g: &Grid, camera: &str, step: f64) -> Scene {
    let cam = CameraSpec::from_json(camera)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap();
    let mut s = Scene::new(cam, 64, 48, tf());
    s.method = Method::GridRaycast(GridRaycast {
        integrator: Integrator::Riemann { step },
        ..GridRaycast::default()
    });
    s
}

/// Mean and largest difference per channel.
pub fn compare(a: &Image, b: &Image) -> (f64, f32) {
    let (mut sum, mut max, mut n) = (0.0f64, 0.0f32, 0usize);
    for (p, q) in a.pixels().iter().zip(b.pixels()) {
        for c in 0..4 {
            let d = (p[c] - q[c]).abs();
            sum += f64::from(d);
            max = max.max(d);
            n += 1;
        }
    }
    (sum / n as f64, max)
}

pub fn cpu(g: &Arc<Grid>, s: &Scene) -> Image {
    let volume = Volume::Grid(g.clone());
    let mut r = create_renderer(&volume, &s.method).unwrap();
    r.render(s, &Control::default()).unwrap().image
}
