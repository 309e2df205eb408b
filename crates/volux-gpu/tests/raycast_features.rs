//! The GPU ray caster's shading, pre-integration, isosurfaces, sculpt mask, jitter and
//! empty-space skipping against the CPU engine on the same scenes: mean difference under
//! 1/255 per channel, and a maximum each test states (the GPU computes positions in `f32`
//! where the CPU uses `f64` and looks the TF up in the lane tables where some CPU paths
//! evaluate it per sample, so values land a hair apart; the lighting and the regula falsi
//! amplify that where the gradient is steep). Skipped, with a message, without an adapter
//! unless `VOLUX_GPU_REQUIRED=1`.
mod common;

use std::sync::Arc;

use common::{compare, context, cpu, grid, scene, tf};
use volux_core::sculpt::SculptMask;
use volux_core::{Grid, Image, TransferFunction};
use volux_gpu::GpuGridRenderer;
use volux_render::frame::MethodStats;
use volux_render::integrate::Integrator;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::renderer::Renderer;
use volux_render::scene::{GridRaycast, Method, Scene};
use volux_render::tiles::Control;

const CAMERAS: [&str; 2] = [
    r#"{"azimuth": 33, "elevation": 21}"#,
    r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
];

/// Renders `s` on both engines and checks the difference (mean under 1/255, max under
/// `max_bound`); returns the GPU frame's sample count.
fn check(
    gpu: &mut GpuGridRenderer,
    g: &Arc<Grid>,
    name: &str,
    s: &Scene,
    max_bound: f32,
) -> (Image, u64) {
    let want = cpu(g, s);
    assert!(
        want.coverage(0.01) > 0.1,
        "{name}: the picture shows something"
    );
    let frame = gpu.render(s, &Control::default()).unwrap();
    let (mean, max) = compare(&frame.image, &want);
    eprintln!("{name}: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean < 1.0 / 255.0 && max < max_bound,
        "{name}: mean {mean:e}, max {max:e}"
    );
    (frame.image, samples(&frame.stats.method))
}

fn samples(stats: &MethodStats) -> u64 {
    match stats {
        MethodStats::GridRaycast(r) => r.samples,
        _ => panic!("not a grid ray casting frame"),
    }
}

fn with_integrator(mut s: Scene, integrator: Integrator) -> Scene {
    s.method = Method::GridRaycast(GridRaycast {
        integrator,
        ..GridRaycast::default()
    });
    s
}

/// Blinn-Phong shading with the CPU's gradient volume (the same quantized gradients, looked
/// up trilinearly), at the sample for Riemann and at the segment's middle for
/// pre-integration: bound 1e-4 (measured 5.8e-6 on lavapipe).
#[test]
fn shaded_riemann_and_preintegration_equal_the_cpu_engine() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    for camera in CAMERAS {
        let mut s = scene(&g, camera, 0.5);
        s.appearance.shade_volume = true;
        check(&mut gpu, &g, &format!("shaded riemann {camera}"), &s, 1e-4);
        let pre = with_integrator(s, Integrator::Preintegrated { step: 0.6 });
        check(
            &mut gpu,
            &g,
            &format!("shaded preintegrated {camera}"),
            &pre,
            1e-4,
        );
    }
}

/// Pre-integration (the CPU's 256 x 256 table, looked up bilinearly), emission only and
/// jittered: max 1e-4.
#[test]
fn preintegration_and_jitter_equal_the_cpu_engine() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    for camera in CAMERAS {
        let s = with_integrator(
            scene(&g, camera, 0.5),
            Integrator::Preintegrated { step: 0.4 },
        );
        check(&mut gpu, &g, &format!("preintegrated {camera}"), &s, 1e-4);
        let mut jittered = s.clone();
        jittered.method = Method::GridRaycast(GridRaycast {
            integrator: Integrator::Preintegrated { step: 0.4 },
            jitter: true,
            ..GridRaycast::default()
        });
        check(
            &mut gpu,
            &g,
            &format!("jittered preint {camera}"),
            &jittered,
            1e-4,
        );
        let mut riemann = scene(&g, camera, 0.7);
        riemann.method = Method::GridRaycast(GridRaycast {
            integrator: Integrator::Riemann { step: 0.7 },
            jitter: true,
            ..GridRaycast::default()
        });
        check(
            &mut gpu,
            &g,
            &format!("jittered riemann {camera}"),
            &riemann,
            1e-4,
        );
    }
}

/// Two isosurfaces through a faint volume, lit with gradients on the fly (unshaded volume)
/// and with the gradient volume (shaded): each crossing refined by regula falsi in `f32` on
/// the GPU and `f64` on the CPU, so a pixel where a ray grazes a surface may see it a
/// little apart: bound 1e-4 (measured 1.1e-5 on lavapipe).
#[test]
fn lit_isosurfaces_equal_the_cpu_engine() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    let isos = Isosurfaces::new(vec![
        Isovalue {
            value: 85.0,
            rgba: [1.0, 0.7, 0.3, 0.4],
        },
        Isovalue {
            value: 100.0,
            rgba: [0.3, 0.6, 1.0, 0.8],
        },
    ])
    .unwrap();
    let faint = TransferFunction::from_json(
        r#"{"color": [[40,0.2,0.4,1],[110,1,1,1]], "extinction": [[40,0],[110,0.02]]}"#,
    )
    .unwrap();
    for camera in CAMERAS {
        for shaded in [false, true] {
            let mut s = scene(&g, camera, 0.5);
            s.appearance.tf = faint.clone();
            s.appearance.isosurfaces = isos.clone();
            s.appearance.shade_volume = shaded;
            let name = format!("isosurfaces (shaded volume {shaded}) {camera}");
            check(&mut gpu, &g, &name, &s, 1e-4);
        }
    }
}

/// The sculpt mask: a ball of voxels removed through the middle, then part of a slab; the
/// bits uploaded again when the mask changes: max 1e-4.
#[test]
fn the_sculpt_mask_equals_the_cpu_engines() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    let [nx, ny, nz] = g.dims();
    let mut kept = vec![1u8; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let d = [i as f64 - 20.0, j as f64 - 14.0, k as f64 - 12.0];
                if d.iter().map(|d| d * d).sum::<f64>() < 81.0 {
                    kept[i + nx * (j + ny * k)] = 0;
                }
            }
        }
    }
    let mut s = scene(&g, CAMERAS[0], 0.5);
    s.mask = Some(Arc::new(SculptMask::from_values(g.dims(), &kept).unwrap()));
    let (open, _) = check(&mut gpu, &g, "ball removed", &s, 1e-4);
    for v in kept.iter_mut().take(nx * ny * 8) {
        *v = 0;
    }
    s.mask = Some(Arc::new(SculptMask::from_values(g.dims(), &kept).unwrap()));
    let (cut, _) = check(&mut gpu, &g, "ball and slab removed", &s, 1e-4);
    assert!(compare(&open, &cut).1 > 0.05, "the new mask was drawn");
    let pre = with_integrator(s, Integrator::Preintegrated { step: 0.5 });
    check(&mut gpu, &g, "masked preintegration", &pre, 1e-4);
}

/// The faces a clip plane and the sculpt mask expose, lit with the cut's normal
/// (`CutFaces`, whose lighting the CPU engine's tests check against Blinn-Phong with the
/// cut's normal), shaded Riemann and pre-integration: mean under 1/255, and a bound of 0.25
/// on the few pixels whose sample lies within f32 rounding of the lit layer's depth, which
/// the GPU (world positions in f32) and the CPU (voxel-space planes) may put on either side.
#[test]
fn cut_faces_lit_with_the_cuts_normal_equal_the_cpu_engine() {
    use glam::DVec3;
    use volux_core::voi::ClipPlane;
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    let [nx, ny, nz] = g.dims();
    let mut kept = vec![1u8; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let d = [i as f64 - 24.0, j as f64 - 10.0, k as f64 - 14.0];
                if d.iter().map(|d| d * d).sum::<f64>() < 49.0 {
                    kept[i + nx * (j + ny * k)] = 0;
                }
            }
        }
    }
    let centre = g.bounds().center();
    let normal = DVec3::new(-0.6, 0.8, 0.2).normalize();
    for camera in CAMERAS {
        let mut s = scene(&g, camera, 0.5);
        s.appearance.shade_volume = true;
        s.clip_planes = vec![ClipPlane {
            normal,
            offset: -normal.dot(centre),
        }];
        s.mask = Some(Arc::new(SculptMask::from_values(g.dims(), &kept).unwrap()));
        check(&mut gpu, &g, &format!("cut faces {camera}"), &s, 0.25);
        let pre = with_integrator(s, Integrator::Preintegrated { step: 0.5 });
        check(
            &mut gpu,
            &g,
            &format!("cut faces preintegrated {camera}"),
            &pre,
            0.25,
        );
    }
}

/// Empty-space skipping over the macrocells: with a TF transparent below 72 most of the
/// grid is skipped, the picture is the CPU's (max 1e-4) and the rays take fewer samples than
/// with a TF that leaves no macrocell empty.
#[test]
fn empty_space_is_skipped_without_changing_the_picture() {
    let Some(ctx) = context() else { return };
    let g = Arc::new(grid());
    let mut gpu = GpuGridRenderer::new(ctx, g.clone()).unwrap();
    let mut sparse = scene(&g, CAMERAS[0], 0.3);
    sparse.appearance.tf = TransferFunction::from_json(
        r#"{"color": [[72,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[40,0],[72,0],[75,0.3],[110,0.4]]}"#,
    )
    .unwrap();
    let (_, skipped) = check(&mut gpu, &g, "sparse TF", &sparse, 1e-4);
    let mut dense = sparse.clone();
    dense.appearance.tf = TransferFunction::from_json(
        r#"{"color": [[72,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[0,1e-9],[72,1e-9],[75,0.3],[110,0.4]]}"#,
    )
    .unwrap();
    let all = samples(
        &gpu.render(&dense, &Control::default())
            .unwrap()
            .stats
            .method,
    );
    eprintln!("samples: {skipped} skipping, {all} without empty macrocells");
    assert!(
        (skipped as f64) < 0.8 * all as f64,
        "{skipped} against {all}"
    );
    let _ = tf();
}
