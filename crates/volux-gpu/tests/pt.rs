//! The GPU Projected Tetrahedra renderer against the CPU `PtRenderer` on the same scenes.
//! Skipped, with a message, when this machine has no adapter; CI sets
//! `VOLUX_GPU_REQUIRED=1` (it installs lavapipe), which turns the skip into a failure.
//!
//! Bounds: a mean difference under 1/255 per channel, and a largest one of [`MAX_DIFF`].
//! Measured on lavapipe (Mesa 22.3.6, `rgba32float` target), 64x48, 4800 tets: average
//! mean 1.7e-6 to 3.0e-6, max 1.2e-4 to 7.9e-4; ψ mean 7.5e-6 to 1.6e-5, max 2.7e-4 to
//! 1.3e-3 (the orthographic view the smallest). The sort order is the CPU's (the same keys, a
//! stable sort, ties by id, drawn in that order); the differences come from the GPU's `f32`
//! projection (a vertex may snap to the neighbouring 1/256 pixel step where the CPU's `f64`
//! lands near a half step: the edge pixels of that cell change), from the hardware's
//! interpolation of the fan attributes against the CPU's own barycentrics, from the CPU
//! drawing most cells by their face planes rather than by the fan. Both composite front to
//! back with "under" (the GPU by blending; drawing back to front with "over" gave the same
//! differences to 1e-8). Early termination is off in these scenes: the GPU has none.
//!
//! Lit isosurfaces (three isovalues, one where the extinction is zero; a headlight in
//! perspective, a directional light in orthographic): mean 8.8e-7 to 2.9e-6, max 9.3e-5 to
//! 2.3e-4; the isovalue in the zero-extinction stretch alone: mean 2.1e-6, max 7.9e-4. Two
//! clipping planes: average mean 1.1e-6 to 1.3e-6, max 1.0e-4 to 3.4e-4, ψ mean 7.6e-6 to
//! 8.1e-6, max 4.3e-4 to 1.5e-3; planes and isosurfaces together mean 2.0e-6, max 3.2e-4.
//! The GPU computes each pixel's window in `f32` from the planes' distances to the eye (the
//! CPU in `f64` from the world-space ray). A sequence of frames (the same scene, a camera
//! change, a recolouring, a new zero set, isovalues, the ψ rule) draws the CPU's pictures
//! from the caches, keeps the CPU's number of cells, and reports what it rebuilt.
use std::sync::Arc;

use glam::Vec3;
use volux_core::grid::{Buffer, Samples};
use volux_core::tetrahedralize::grid_to_tets;
use volux_core::voi::ClipPlane;
use volux_core::{CameraSpec, Grid, Image, TetMesh, TransferFunction};
use volux_gpu::{GpuContext, GpuPtRenderer};
use volux_render::engine::create_renderer;
use volux_render::frame::{MethodStats, Rebuilt};
use volux_render::integrate::SegmentRule;
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::renderer::Renderer;
use volux_render::scene::{Method, PtSettings, Scene, SortMode, Volume};
use volux_render::shading::Light;
use volux_render::tiles::Control;
use volux_render::RenderError;

/// The largest difference allowed in one channel: three times the largest measured (1.3e-3,
/// see the module docs).
const MAX_DIFF: f32 = 4e-3;

/// The device, or `None` (with a message) when there is none and none is required.
fn context() -> Option<Arc<GpuContext>> {
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

/// A smooth field on a 13x11x9 grid, anisotropic and offset, as 5 tets a cell (4800 tets).
fn mesh() -> TetMesh {
    let [nx, ny, nz] = [13usize, 11, 9];
    let mut v = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let [x, y, z] = [i as f32 / 12.0, j as f32 / 10.0, k as f32 / 8.0];
                let r = ((x - 0.5).powi(2) + (y - 0.45).powi(2) + (z - 0.55).powi(2)).sqrt();
                v.push(100.0 * (1.0 - r) + 20.0 * (7.0 * x).sin() * (5.0 * y).cos());
            }
        }
    }
    let samples = Samples::F32(Buffer::owned(v));
    let g = Grid::new([nx, ny, nz], [0.8, 1.1, 1.7], [-3.0, 2.0, 5.0], samples).unwrap();
    grid_to_tets(&g).unwrap()
}

/// Breakpoints inside the cells' ranges (the ψ rule cuts there, the average looks the
/// table up) and a zero-extinction stretch below 40 (discarded cells).
fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"color": [[40,0.2,0.4,1],[70,1,0.8,0.3],[110,1,1,1]],
            "extinction": [[40,0],[60,0.08],[75,0.3],[90,0.05],[110,0.4]]}"#,
    )
    .unwrap()
}

fn scene(m: &TetMesh, camera: &str, color: SegmentRule) -> Scene {
    let cam = CameraSpec::from_json(camera)
        .unwrap()
        .resolve(&m.bounds())
        .unwrap();
    let mut s = Scene::new(cam, 64, 48, tf());
    s.method = Method::ProjectedTetrahedra(PtSettings {
        color,
        ..PtSettings::default()
    });
    s.early_termination = None;
    s
}

/// Mean and largest difference per channel.
fn compare(a: &Image, b: &Image) -> (f64, f32) {
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

fn cpu(m: &Arc<TetMesh>, s: &Scene) -> Image {
    let volume = Volume::Mesh(m.clone());
    let mut r = create_renderer(&volume, &s.method).unwrap();
    r.render(s, &Control::default()).unwrap().image
}

const CAMERAS: [&str; 3] = [
    r#"{"azimuth": 33, "elevation": 21}"#,
    r#"{"azimuth": 200, "elevation": -40}"#,
    r#"{"azimuth": -70, "elevation": 35, "projection": "orthographic"}"#,
];

#[test]
fn projected_tetrahedra_on_the_gpu_equal_the_cpu_renderer() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    eprintln!("target format: {:?}", gpu.target_format());
    for color in [SegmentRule::Average, SegmentRule::Psi] {
        for camera in CAMERAS {
            let s = scene(&m, camera, color);
            let want = cpu(&m, &s);
            assert!(
                want.coverage(0.01) > 0.2,
                "{camera}: the picture shows something"
            );
            let got = gpu.render(&s, &Control::default()).unwrap().image;
            let (mean, max) = compare(&got, &want);
            eprintln!("{} {camera}: mean {mean:.2e}, max {max:.2e}", color.name());
            assert!(
                mean < 1.0 / 255.0 && max < MAX_DIFF,
                "{} {camera}: mean {mean:e}, max {max:e}",
                color.name()
            );
        }
    }
}

/// The exact visibility order (MPVO on the CPU, uploaded as the draw order) against the
/// CPU's `SortMode::Exact` (the mesh is convex: the CPU draws its MPVO order too), both
/// colour rules and the three cameras, then a centroid frame after the exact ones.
#[test]
fn the_exact_order_on_the_gpu_equals_the_cpu_renderer() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    for color in [SegmentRule::Average, SegmentRule::Psi] {
        for camera in CAMERAS {
            let mut s = scene(&m, camera, color);
            s.method = Method::ProjectedTetrahedra(PtSettings {
                color,
                sort: SortMode::Exact,
                ..PtSettings::default()
            });
            let want = cpu(&m, &s);
            let got = gpu.render(&s, &Control::default()).unwrap().image;
            let (mean, max) = compare(&got, &want);
            eprintln!(
                "exact {} {camera}: mean {mean:.2e}, max {max:.2e}",
                color.name()
            );
            assert!(
                mean < 1.0 / 255.0 && max < MAX_DIFF,
                "exact {} {camera}: mean {mean:e}, max {max:e}",
                color.name()
            );
        }
    }
    let s = scene(&m, CAMERAS[0], SegmentRule::Psi);
    let (mean, max) = compare(
        &gpu.render(&s, &Control::default()).unwrap().image,
        &cpu(&m, &s),
    );
    assert!(
        mean < 1.0 / 255.0 && max < MAX_DIFF,
        "centroid after exact: mean {mean:e}, max {max:e}"
    );
}

#[test]
fn what_the_shaders_do_not_draw_is_refused_with_a_reason() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    let s = scene(&m, "{}", SegmentRule::Exact);
    let err = gpu.render(&s, &Control::default()).unwrap_err();
    assert_eq!(
        err.remedy(),
        Some(volux_render::Remedy::CpuBackend),
        "{err}"
    );
    assert!(matches!(err, RenderError::Refused(_)), "{err}");
    assert!(err.to_string().contains("exact fragment colour"), "{err}");
    let mut s = scene(&m, "{}", SegmentRule::Psi);
    let iso = Isovalue {
        value: 70.0,
        rgba: [1.0, 0.5, 0.2, 0.8],
    };
    s.appearance.isosurfaces = Isosurfaces::new(vec![iso; 17]).unwrap();
    let err = GpuPtRenderer::supports(&s).unwrap_err().to_string();
    assert!(err.contains("17 isosurfaces"), "{err}");
    let mut s = scene(&m, "{}", SegmentRule::Psi);
    s.clip_planes = vec![ClipPlane::new(1.0, 0.0, 0.0, 0.0).unwrap(); 9];
    let err = GpuPtRenderer::supports(&s).unwrap_err().to_string();
    assert!(err.contains("9 clip planes"), "{err}");
}

/// Renders `s` on both and checks the bounds, and that the picture differs from that of
/// `plain` (the scene without what is tested) by a mean of at least `changed`.
fn check(
    gpu: &mut GpuPtRenderer,
    m: &Arc<TetMesh>,
    (s, plain): (&Scene, &Scene),
    what: &str,
    (bound, changed): (f32, f64),
) {
    let want = cpu(m, s);
    assert!(
        want.coverage(0.01) > 0.1,
        "{what}: the picture shows something"
    );
    let (other, _) = compare(&want, &cpu(m, plain));
    assert!(other > changed, "{what}: the picture changes ({other:e})");
    let got = gpu.render(s, &Control::default()).unwrap().image;
    let (mean, max) = compare(&got, &want);
    eprintln!("{what}: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean < 1.0 / 255.0 && max < bound,
        "{what}: mean {mean:e}, max {max:e}"
    );
}

/// Three isovalues: two in the visible range, one (35) where the extinction is zero, so that
/// only the kept set's isovalue rule keeps its cells.
fn isosurfaces() -> Isosurfaces {
    Isosurfaces::new(vec![
        Isovalue {
            value: 95.0,
            rgba: [0.2, 0.6, 1.0, 0.5],
        },
        Isovalue {
            value: 35.0,
            rgba: [0.3, 1.0, 0.3, 0.7],
        },
        Isovalue {
            value: 65.0,
            rgba: [0.9, 0.3, 0.2, 0.6],
        },
    ])
    .unwrap()
}

#[test]
fn lit_isosurfaces_on_the_gpu_equal_the_cpu_renderer() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    for color in [SegmentRule::Average, SegmentRule::Psi] {
        for (camera, light) in [
            (CAMERAS[0], Light::Headlight),
            (CAMERAS[2], Light::Direction(Vec3::new(0.3, -1.0, 0.5))),
        ] {
            let plain = scene(&m, camera, color);
            let mut s = plain.clone();
            s.appearance.isosurfaces = isosurfaces();
            s.appearance.lighting.light = light;
            let what = format!("isosurfaces, {} {camera}", color.name());
            check(&mut gpu, &m, (&s, &plain), &what, (MAX_DIFF, 0.02));
        }
    }
}

#[test]
fn clip_planes_on_the_gpu_equal_the_cpu_renderer() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    let planes = vec![
        ClipPlane::new(1.0, 0.0, 0.0, -1.5).unwrap(),
        ClipPlane::new(0.2, -1.0, 0.3, 7.0).unwrap(),
    ];
    for color in [SegmentRule::Average, SegmentRule::Psi] {
        for camera in [CAMERAS[1], CAMERAS[2]] {
            let plain = scene(&m, camera, color);
            let mut s = plain.clone();
            s.clip_planes = planes.clone();
            let what = format!("clip, {} {camera}", color.name());
            check(&mut gpu, &m, (&s, &plain), &what, (MAX_DIFF, 0.02));
        }
    }
    // Planes and isosurfaces together: the surfaces' gradients trimmed with the segment.
    let mut plain = scene(&m, CAMERAS[0], SegmentRule::Psi);
    plain.appearance.isosurfaces = isosurfaces();
    let mut s = plain.clone();
    s.clip_planes = planes;
    check(
        &mut gpu,
        &m,
        (&s, &plain),
        "clip and isosurfaces",
        (MAX_DIFF, 0.02),
    );
    // The lowest isovalue alone (35, where the extinction is zero): its cells are kept.
    let plain = scene(&m, CAMERAS[0], SegmentRule::Average);
    let mut s = plain.clone();
    s.appearance.isosurfaces = Isosurfaces::new(vec![isosurfaces().as_slice()[0]]).unwrap();
    check(
        &mut gpu,
        &m,
        (&s, &plain),
        "the isovalue 35",
        (MAX_DIFF, 0.005),
    );
}

/// The GPU frame and its `Rebuilt` flags, checked against the CPU's picture and kept count.
fn frame_against_cpu(gpu: &mut GpuPtRenderer, m: &Arc<TetMesh>, s: &Scene, what: &str) -> Rebuilt {
    let volume = Volume::Mesh(m.clone());
    let mut cpu = create_renderer(&volume, &s.method).unwrap();
    let want = cpu.render(s, &Control::default()).unwrap();
    let got = gpu.render(s, &Control::default()).unwrap();
    let (mean, max) = compare(&got.image, &want.image);
    eprintln!("{what}: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean < 1.0 / 255.0 && max < MAX_DIFF,
        "{what}: mean {mean:e}, max {max:e}"
    );
    let (MethodStats::ProjectedTetrahedra(g), MethodStats::ProjectedTetrahedra(c)) =
        (&got.stats.method, &want.stats.method)
    else {
        panic!("{what}: PT statistics");
    };
    assert_eq!(g.tets_kept, c.tets_kept, "{what}: kept cells");
    assert_eq!(got.stats.rebuilt, g.rebuilt, "{what}");
    got.stats.rebuilt
}

#[test]
fn frames_rebuild_only_what_changed() {
    let Some(ctx) = context() else { return };
    let m = Arc::new(mesh());
    let mut gpu = GpuPtRenderer::new(ctx, m.clone()).unwrap();
    let rebuilt = |data, classification, view| Rebuilt {
        data,
        classification,
        view,
    };
    let mut s = scene(&m, CAMERAS[0], SegmentRule::Average);
    let first = frame_against_cpu(&mut gpu, &m, &s, "first frame");
    assert_eq!(first, rebuilt(false, true, true));
    let again = frame_against_cpu(&mut gpu, &m, &s, "the same frame");
    assert_eq!(again, rebuilt(false, false, false));
    // A camera change: projection, classification and sort, not the TF's tables.
    s.view.camera = scene(&m, CAMERAS[1], SegmentRule::Average).view.camera;
    let moved = frame_against_cpu(&mut gpu, &m, &s, "camera change");
    assert_eq!(moved, rebuilt(false, false, true));
    // A TF change with the same zero set: its tables, not the cells.
    let recoloured = TransferFunction::from_json(
        r#"{"color": [[40,0.9,0.4,0.1],[70,0.2,0.8,1],[110,1,0.3,1]],
            "extinction": [[40,0],[60,0.2],[75,0.1],[90,0.3],[110,0.1]]}"#,
    )
    .unwrap();
    s.appearance.tf = recoloured;
    let tf_change = frame_against_cpu(&mut gpu, &m, &s, "TF change");
    assert_eq!(tf_change, rebuilt(false, true, false));
    // A new zero set: the kept set and, with it, the cells.
    s.appearance.tf = TransferFunction::from_json(
        r#"{"color": [[40,0.9,0.4,0.1],[110,1,0.3,1]],
            "extinction": [[70,0],[90,0.3],[110,0.1]]}"#,
    )
    .unwrap();
    let zero_set = frame_against_cpu(&mut gpu, &m, &s, "zero set change");
    assert_eq!(zero_set, rebuilt(false, true, true));
    // Isovalues: the gradients (once), the kept set and the cells.
    s.appearance.isosurfaces = isosurfaces();
    let isos = frame_against_cpu(&mut gpu, &m, &s, "isovalues");
    assert_eq!(isos, rebuilt(true, true, true));
    // The ψ rule: the ψ table (once), nothing else.
    s.method = scene(&m, CAMERAS[0], SegmentRule::Psi).method;
    let psi = frame_against_cpu(&mut gpu, &m, &s, "psi rule");
    assert_eq!(psi, rebuilt(true, false, false));
}
