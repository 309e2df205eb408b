//! Texture slicing on the GPU (seed `004` ch. 3) against the CPU engine's Riemann ray casting
//! of the same scene at the same step, both without early termination (slicing composites
//! back to front and stops nowhere): mean difference under 1/255 per channel, and a maximum
//! each test states. The two sample the same field at different points: a ray samples at
//! `t0 + i h` from its own entry, a slice where its plane (perpendicular to the view, planes
//! `h` apart from the volume of interest's nearest vertex) crosses the ray, so the samples
//! of a ray and of the slices sit up to a step apart along it (and, off the axis of a
//! perspective camera, `h / cos` apart, the opacity corrected for that length). Where the
//! field and the TF change fast within a step (a clip plane's cut face, the sculpted hole's
//! rim) a pixel differs by what one step of the classified field changes. Each ray's first
//! slice stands for the segment from the ray's entry and its last stops at the exit, so the
//! slabs tile the ray as the ray caster's do (without that, the means measured ten times
//! larger, 5e-4 to 1e-3, and the maxima up to 5.9e-2). Skipped, with a
//! message, without an adapter unless `VOLUX_GPU_REQUIRED=1`.
mod common;

use std::sync::Arc;

use common::{compare, context, cpu, grid, scene};
use glam::{DMat3, DVec3};
use volux_core::sculpt::SculptMask;
use volux_core::voi::ClipPlane;
use volux_core::{Grid, Image};
use volux_gpu::GpuSlicingRenderer;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::renderer::Renderer;
use volux_render::scene::{Method, Scene, SlicingSettings};
use volux_render::tiles::Control;

const PERSPECTIVE: &str = r#"{"azimuth": 33, "elevation": 21}"#;
const ORTHOGRAPHIC: &str = r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#;

/// The CPU's Riemann scene at `step` without early termination, and its slicing twin.
fn scenes(g: &Grid, camera: &str, step: f64) -> (Scene, Scene) {
    let mut cpu = scene(g, camera, step);
    cpu.early_termination = None;
    let mut gpu = cpu.clone();
    gpu.method = Method::Slicing(SlicingSettings { step });
    (cpu, gpu)
}

/// Renders both and checks the mean (under 1/255) and the maximum (under `max_bound`).
fn check(
    gpu: &mut GpuSlicingRenderer,
    g: &Arc<Grid>,
    name: &str,
    (cpu_scene, gpu_scene): &(Scene, Scene),
    max_bound: f32,
) -> Image {
    let want = cpu(g, cpu_scene);
    assert!(
        want.coverage(0.01) > 0.1,
        "{name}: the picture shows something"
    );
    let got = gpu.render(gpu_scene, &Control::default()).unwrap().image;
    let (mean, max) = compare(&got, &want);
    eprintln!("{name}: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean < 1.0 / 255.0 && max < max_bound,
        "{name}: mean {mean:e}, max {max:e}"
    );
    got
}

fn renderer(g: &Arc<Grid>) -> Option<GpuSlicingRenderer> {
    let ctx = context()?;
    let r = GpuSlicingRenderer::new(ctx, g.clone()).unwrap();
    eprintln!("slicing target: {:?}", r.target_format());
    Some(r)
}

/// Orthographic and perspective cameras, emission only and shaded with the gradient volume:
/// max bound 0.03 (measured on lavapipe: h = 0.5 3.1e-3 perspective, 6.8e-3 orthographic,
/// shaded 5.0e-3 and 6.8e-3; h = 1 8.9e-3 and 1.6e-2, the samples twice as far apart; means
/// 5e-5 to 1.9e-4).
#[test]
fn slicing_equals_riemann_ray_casting() {
    let g = Arc::new(grid());
    let Some(mut gpu) = renderer(&g) else { return };
    for camera in [PERSPECTIVE, ORTHOGRAPHIC] {
        for step in [0.5, 1.0] {
            let pair = scenes(&g, camera, step);
            check(&mut gpu, &g, &format!("{camera} h={step}"), &pair, 0.03);
        }
        let (mut cpu, mut sliced) = scenes(&g, camera, 0.5);
        cpu.appearance.shade_volume = true;
        sliced.appearance.shade_volume = true;
        check(
            &mut gpu,
            &g,
            &format!("shaded {camera}"),
            &(cpu, sliced),
            0.03,
        );
    }
}

/// An oblique clip plane through the middle (the slices are the cut box's sections, each
/// ray's first slice standing for the segment from the cut face): max bound 0.01 (measured
/// on lavapipe 1.9e-3 perspective, 2.8e-3 orthographic).
#[test]
fn a_clip_plane_cuts_the_slices() {
    let g = Arc::new(grid());
    let Some(mut gpu) = renderer(&g) else { return };
    let normal = DVec3::new(1.0, 0.4, -0.3).normalize();
    let plane = ClipPlane {
        normal,
        offset: -normal.dot(g.bounds().center()),
    };
    for camera in [PERSPECTIVE, ORTHOGRAPHIC] {
        let (mut cpu, mut sliced) = scenes(&g, camera, 0.5);
        cpu.clip_planes = vec![plane];
        sliced.clip_planes = vec![plane];
        let name = format!("clipped {camera}");
        check(&mut gpu, &g, &name, &(cpu, sliced), 0.01);
    }
}

/// The sculpt mask: a ball of voxels removed through the middle, then part of a slab too
/// (the bits uploaded again): max bound 0.08 (measured on lavapipe 3.7e-2 and 4.0e-2, means
/// 6e-4 and 7.7e-4): a hidden sample drops a whole slab on both engines, and the slabs of a
/// ray and of the slices dropped at the hole's rim are a fraction of a step apart, where the
/// field behind is opaque.
#[test]
fn the_sculpt_mask_hides_fragments() {
    let g = Arc::new(grid());
    let Some(mut gpu) = renderer(&g) else { return };
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
    let (mut cpu, mut sliced) = scenes(&g, PERSPECTIVE, 0.5);
    let mask = Some(Arc::new(SculptMask::from_values(g.dims(), &kept).unwrap()));
    (cpu.mask, sliced.mask) = (mask.clone(), mask);
    let open = check(
        &mut gpu,
        &g,
        "ball removed",
        &(cpu.clone(), sliced.clone()),
        0.08,
    );
    for v in kept.iter_mut().take(nx * ny * 8) {
        *v = 0;
    }
    let mask = Some(Arc::new(SculptMask::from_values(g.dims(), &kept).unwrap()));
    (cpu.mask, sliced.mask) = (mask.clone(), mask);
    let cut = check(&mut gpu, &g, "ball and slab removed", &(cpu, sliced), 0.08);
    assert!(compare(&open, &cut).1 > 0.05, "the new mask was drawn");
}

/// A grid turned about z (an orientation): sliced in its local frame as the ray caster
/// traces it: max bound 0.01 (measured on lavapipe 2.1e-3 perspective, 3.9e-3
/// orthographic).
#[test]
fn an_oriented_grid_is_sliced_in_its_frame() {
    let turn = DMat3::from_rotation_z(0.6) * DMat3::from_rotation_x(-0.3);
    let g = Arc::new(grid().with_direction(turn).unwrap());
    let Some(mut gpu) = renderer(&g) else { return };
    for camera in [PERSPECTIVE, ORTHOGRAPHIC] {
        let pair = scenes(&g, camera, 0.5);
        check(&mut gpu, &g, &format!("oriented {camera}"), &pair, 0.01);
    }
}

/// What slicing does not draw is refused by name, with or without a device; the CPU engine
/// refuses slicing itself.
#[test]
fn what_slicing_does_not_draw_is_refused() {
    let g = grid();
    let (raycast, sliced) = scenes(&g, PERSPECTIVE, 0.5);
    let refusal = GpuSlicingRenderer::supports(&raycast).unwrap_err();
    assert_eq!(
        refusal.remedy,
        Some(volux_render::Remedy::Method("slicing"))
    );
    let e = refusal.to_string();
    assert!(e.contains("'raycast'"), "{e}");
    assert!(GpuSlicingRenderer::supports(&sliced).is_ok());
    let mut mip = sliced.clone();
    mip.appearance.mip = true;
    let mut iso = sliced.clone();
    iso.appearance.isosurfaces = Isosurfaces::new(vec![Isovalue {
        value: 80.0,
        rgba: [1.0; 4],
    }])
    .unwrap();
    let cases = [
        (&mip, "maximum intensity projection"),
        (&iso, "isosurfaces"),
    ];
    for (s, what) in cases {
        let e = GpuSlicingRenderer::supports(s).unwrap_err().to_string();
        assert!(e.contains(what) && e.contains("slicing"), "{e}");
    }
    let volume = volux_render::scene::Volume::from(grid());
    let e = volux_render::engine::create_renderer(&volume, &sliced.method)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("GPU method"), "{e}");
    let g = Arc::new(g);
    let Some(mut gpu) = renderer(&g) else { return };
    let e = gpu.render(&mip, &Control::default()).unwrap_err();
    assert!(
        e.to_string().contains("maximum intensity projection"),
        "{e}"
    );
    let mut bad = sliced;
    bad.method = Method::Slicing(SlicingSettings { step: -1.0 });
    assert!(gpu.render(&bad, &Control::default()).is_err());
}
