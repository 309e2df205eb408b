use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use volux_core::grid::{Buffer, Samples};
use volux_core::image::ImageDiff;
use volux_core::tetrahedralize::grid_to_tets;
use volux_core::{synth, Camera, CameraSpec, Grid, Projection, TetMesh, TransferFunction};

use super::*;
use crate::error::{RenderError, Setting, SettingError};
use crate::integrate::adaptive::{AdaptiveParams, StepControl};
use crate::integrate::SegmentRule;
use crate::isosurface::{Isosurfaces, Isovalue};
use crate::pt::reference::{ray_segments, render_mesh_reference, ReferenceOptions};
use crate::shading::BlinnPhong;
use crate::tiles::Control;

fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 0.1, 0.2, 0.9], [0.4, 1, 0.6, 0.1], [1, 0.3, 1, 0.5]],
            "extinction": [[0, 0.5], [0.3, 4], [0.5, 1], [0.8, 6], [1, 2]]}"#,
    )
    .unwrap()
}

fn options(camera: Camera, w: usize, h: usize) -> TetRayOptions {
    TetRayOptions {
        width: w,
        height: h,
        early_termination: None,
        ..TetRayOptions::new(camera, tf())
    }
}

/// Renders with the caster and the reference and checks they agree.
fn check_against_reference(
    mesh: &TetMesh,
    caster: &TetRayCaster<&TetMesh>,
    camera: Camera,
    n: usize,
    label: &str,
) -> TetRayStats {
    let opts = options(camera, n, n);
    let got = caster.render_with(&opts).unwrap();
    let want = render_mesh_reference(
        mesh,
        &ReferenceOptions {
            width: n,
            height: n,
            camera,
            tf: opts.tf.clone(),
            clip_planes: Vec::new(),
        },
    )
    .unwrap();
    let ImageDiff {
        mean_error: mean,
        max_error: max,
        ..
    } = got.image.compare(&want, 0.0).unwrap();
    let cov = want.coverage(1e-3);
    eprintln!(
        "{label}: mean {mean:.2e}, max {max:.2e}, coverage {cov:.2}, {:?}",
        got.stats
    );
    assert!(cov > 0.1, "{label}: the view must show the mesh ({cov})");
    assert!(mean < 1e-4 && max < 1e-2, "{label}: mean {mean}, max {max}");
    assert_eq!(got.stats.abandoned, 0, "{label}");
    assert_eq!(got.stats.rays, (n * n) as u64);
    got.stats
}

fn orbit(proj: &str, az: f64, el: f64, zoom: f64) -> CameraSpec {
    CameraSpec {
        projection: Some(proj.into()),
        azimuth: Some(az),
        elevation: Some(el),
        zoom: Some(zoom),
        ..Default::default()
    }
}

#[test]
fn convex_mesh_matches_the_reference_from_several_cameras() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let b = mesh.bounds();
    let cameras = [
        orbit("perspective", 35.0, 20.0, 1.0).resolve(&b).unwrap(),
        orbit("orthographic", -60.0, 45.0, 1.3).resolve(&b).unwrap(),
        orbit("perspective", 180.0, -70.0, 1.6).resolve(&b).unwrap(),
        // Axis-aligned orthographic: rays in lattice planes.
        orbit("orthographic", 0.0, 0.0, 1.0).resolve(&b).unwrap(),
        // Inside the mesh: rays start in cells around the eye.
        Camera {
            eye: DVec3::new(0.43, 0.31, 0.57),
            target: DVec3::new(0.9, 0.7, 0.2),
            up: DVec3::Z,
            projection: Projection::Perspective { fov_y_deg: 70.0 },
        },
    ];
    for (i, cam) in cameras.into_iter().enumerate() {
        let stats = check_against_reference(&mesh, &caster, cam, 48, &format!("camera {i}"));
        assert_eq!(stats.reentries, 0, "a convex mesh has no re-entries");
        if i == 4 {
            assert!(stats.start_cells > 0);
        }
    }
}

#[test]
fn orthographic_camera_inside_the_mesh_matches_the_reference() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = Camera {
        eye: DVec3::new(0.5, 0.4, 0.5),
        target: DVec3::new(0.6, 1.0, 0.7),
        up: DVec3::Z,
        projection: Projection::Orthographic { height: 0.8 },
    };
    let stats = check_against_reference(&mesh, &caster, cam, 40, "ortho inside");
    assert!(stats.start_cells > 0);
}

#[test]
fn walked_segments_equal_the_reference_segments() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = orbit("perspective", 20.0, 30.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let mut rays = 0;
    for y in (0..64).step_by(7) {
        for x in (0..64).step_by(5) {
            let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, 64, 64);
            let got = caster.trace(ray.origin, ray.dir);
            let want = ray_segments(&mesh, ray.origin, ray.dir);
            assert_eq!(got.segments.len(), want.len(), "pixel {x} {y}");
            for (g, w) in got.segments.iter().zip(&want) {
                assert_eq!(g.tet as usize, w.tet);
                assert_eq!(
                    (g.t_in, g.t_out),
                    (w.t_in, w.t_out),
                    "bit-identical crossings"
                );
                assert!((g.s_in - w.s_in).abs() < 1e-9 && (g.s_out - w.s_out).abs() < 1e-9);
            }
            rays += usize::from(!want.is_empty());
        }
    }
    assert!(rays > 40, "{rays}");
}

#[test]
fn non_convex_torus_matches_the_reference_with_reentries() {
    let mesh = synth::torus_tets(24).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let b = mesh.bounds();
    let cams = [
        orbit("perspective", 10.0, 25.0, 1.0).resolve(&b).unwrap(),
        orbit("orthographic", 0.0, 0.0, 1.0).resolve(&b).unwrap(),
        // From inside the tube.
        Camera {
            eye: DVec3::new(1.3, 0.0, 0.05),
            target: DVec3::new(0.0, 1.2, 0.0),
            up: DVec3::Z,
            projection: Projection::Perspective { fov_y_deg: 80.0 },
        },
    ];
    for (i, cam) in cams.into_iter().enumerate() {
        let stats = check_against_reference(&mesh, &caster, cam, 48, &format!("torus {i}"));
        assert!(stats.reentries > 0, "torus {i}: {stats:?}");
    }
    // Side-on through the ring: four wall crossings, three re-entries.
    let r = caster.trace(DVec3::new(0.013, -3.0, 0.02), DVec3::Y);
    assert_eq!(r.outcome.reentries, 3, "{:?}", r.outcome);
}

/// A lattice of `n^3` points spacing 0.25 (exact in binary) with the scalar `x + 2 y + 3 z`.
pub(super) fn lattice(n: usize) -> TetMesh {
    let mut vals = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                vals.push(0.25 * (i + 2 * j + 3 * k) as f32);
            }
        }
    }
    let g = Grid::new(
        [n; 3],
        [0.25; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(vals)),
    )
    .unwrap();
    grid_to_tets(&g).unwrap()
}

#[test]
fn rays_through_lattice_vertices_and_edges_are_walked_exactly() {
    let mesh = lattice(5); // [0, 1]^3, cells 0.25
    let caster = TetRayCaster::new(&mesh).unwrap();
    // 16 x 16 orthographic pixels of 1/16 with the eye shifted by half a pixel: pixel rays
    // run along x, z in {1/16, ..., 1}, every fourth exactly on lattice planes, so rays go
    // through vertices, along edges and in (diagonal) faces.
    let n = 16;
    let views = [
        (
            DVec3::new(0.5 + 1.0 / 32.0, -2.0, 0.5 - 1.0 / 32.0),
            DVec3::Y,
            DVec3::Z,
        ),
        (
            DVec3::new(3.0, 0.5 + 1.0 / 32.0, 0.5 - 1.0 / 32.0),
            -DVec3::X,
            DVec3::Z,
        ),
        (
            DVec3::new(0.5 - 1.0 / 32.0, 0.5 - 1.0 / 32.0, 2.5),
            -DVec3::Z,
            DVec3::Y,
        ),
    ];
    let mut through_vertices = 0;
    let mut local_searches = 0;
    for (vi, (eye, dir, up)) in views.into_iter().enumerate() {
        let camera = Camera {
            eye,
            target: eye + dir,
            up,
            projection: Projection::Orthographic { height: 1.0 },
        };
        for y in 0..n {
            for x in 0..n {
                let ray = camera.ray(x as f64 + 0.5, y as f64 + 0.5, n, n);
                let (r, _, _) = camera.basis();
                let inside = |v: f64| (0.0..=1.0).contains(&v);
                let lateral = [ray.origin.dot(r.abs()), ray.origin.dot(up)];
                assert!(
                    lateral.iter().all(|v| (v * 16.0).fract() == 0.0),
                    "{lateral:?}"
                );
                let traced = caster.trace(ray.origin, ray.dir);
                assert!(!traced.outcome.abandoned);
                local_searches += traced.outcome.local_searches;
                let total: f64 = traced.segments.iter().map(|s| s.t_out - s.t_in).sum();
                // Rays on the box's own faces belong to the box or not by the tie rule; the
                // reference decides, and must agree.
                let want: f64 = ray_segments(&mesh, ray.origin, ray.dir)
                    .iter()
                    .map(|s| s.length())
                    .sum();
                assert!(
                    (total - want).abs() < 1e-12,
                    "view {vi} pixel {x} {y}: {total} vs {want}"
                );
                if lateral.iter().all(|&v| v > 0.0 && v < 1.0) {
                    assert!(
                        (total - 1.0).abs() < 1e-12,
                        "view {vi} pixel {x} {y}: {total}"
                    );
                }
                if lateral
                    .iter()
                    .all(|v| (v * 4.0).fract() == 0.0 && inside(*v))
                {
                    through_vertices += 1;
                }
                // Contiguous, and the scalar continuous across cells.
                for p in traced.segments.windows(2) {
                    assert_eq!(p[0].t_out, p[1].t_in, "view {vi} pixel {x} {y}");
                    assert!((p[0].s_out - p[1].s_in).abs() < 1e-9);
                }
            }
        }
        let opts = TetRayOptions {
            color: SegmentRule::Exact,
            ..options(camera, n, n)
        };
        let img = caster.render_with(&opts).unwrap();
        assert_eq!(img.stats.abandoned, 0);
        let reference = render_mesh_reference(
            &mesh,
            &ReferenceOptions {
                width: n,
                height: n,
                camera,
                tf: opts.tf.clone(),
                clip_planes: Vec::new(),
            },
        )
        .unwrap();
        let ImageDiff {
            mean_error: mean,
            max_error: max,
            ..
        } = img.image.compare(&reference, 0.0).unwrap();
        assert!(mean < 1e-6 && max < 1e-5, "view {vi}: {mean} {max}");
    }
    assert!(through_vertices >= 3 * 16, "{through_vertices}");
    // The degenerate exits really happened (and were resolved by the local search).
    assert!(local_searches > 100, "{local_searches}");
    // Diagonal rays through lattice vertices (the body diagonal passes through 5 vertices).
    for (o, d, want) in [
        (DVec3::splat(-0.5), DVec3::ONE, 1.0),
        (DVec3::new(-0.5, -0.5, 0.25), DVec3::new(1.0, 1.0, 0.0), 1.0),
        (DVec3::new(0.5, -0.5, -0.5), DVec3::new(0.0, 1.0, 1.0), 1.0),
    ] {
        let r = caster.trace(o, d);
        assert!(!r.outcome.abandoned);
        let total: f64 = r.segments.iter().map(|s| s.t_out - s.t_in).sum();
        assert!((total - want).abs() < 1e-12, "{o} {d}: {total}");
        assert!(r.segments.len() >= 4, "{:?}", r.segments);
        // Scalar x + 2y + 3z along the ray, exactly linear.
        for s in &r.segments {
            let f = |t: f64| {
                let p = o + d * t;
                p.x + 2.0 * p.y + 3.0 * p.z
            };
            assert!((s.s_in - f(s.t_in)).abs() < 1e-9 && (s.s_out - f(s.t_out)).abs() < 1e-9);
        }
    }
}

#[test]
fn mesh_with_gaps_matches_the_reference() {
    let full = synth::smooth_tets(3000).unwrap();
    // Remove a slab of cells and a scattering of single cells: interior boundary faces.
    let pos = full.positions().to_vec();
    let keep: Vec<[u32; 4]> = full
        .tets()
        .iter()
        .enumerate()
        .filter(|(i, t)| {
            let c = t.iter().map(|&v| pos[v as usize]).sum::<Vec3>() / 4.0;
            !(c.x > 0.45 && c.x < 0.6) && i % 17 != 3
        })
        .map(|(_, t)| *t)
        .collect();
    assert!(keep.len() < full.tets().len() * 9 / 10);
    let mesh = TetMesh::new(pos, full.scalars().to_vec(), keep).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let b = mesh.bounds();
    for (i, cam) in [
        orbit("perspective", 80.0, 10.0, 1.0).resolve(&b).unwrap(),
        orbit("orthographic", 100.0, -30.0, 1.0)
            .resolve(&b)
            .unwrap(),
    ]
    .into_iter()
    .enumerate()
    {
        let stats = check_against_reference(&mesh, &caster, cam, 48, &format!("gaps {i}"));
        assert!(stats.reentries > 0, "{stats:?}");
    }
}

#[test]
fn psi_colour_is_close_to_exact() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let exact = caster.render_with(&options(cam, 40, 40)).unwrap();
    let psi = caster
        .render_with(&TetRayOptions {
            color: SegmentRule::Psi,
            ..options(cam, 40, 40)
        })
        .unwrap();
    let ImageDiff {
        mean_error: mean,
        max_error: max,
        ..
    } = exact.image.compare(&psi.image, 0.0).unwrap();
    eprintln!("psi vs exact: mean {mean:.2e}, max {max:.2e}");
    assert!(
        mean > 0.0,
        "psi is an approximation, not the exact integral"
    );
    assert!(mean < 5e-3 && max < 5e-2, "{mean} {max}");
    assert_eq!(psi.stats.segments, exact.stats.segments);
}

#[test]
fn early_termination_stops_rays_within_the_threshold() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let mut opts = options(cam, 40, 40);
    // Dense enough to become opaque.
    opts.tf = TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 1, 1, 1]], "extinction": [[0, 30], [1, 30]]}"#,
    )
    .unwrap();
    let full = caster.render_with(&opts).unwrap();
    opts.early_termination = Some(0.95);
    let early = caster.render_with(&opts).unwrap();
    assert!(
        early.stats.segments < full.stats.segments / 2,
        "{:?}",
        early.stats
    );
    let max = full.image.compare(&early.image, 0.0).unwrap().max_error;
    assert!(max <= 0.05 + 1e-6, "{max}");
    assert!(early.image.pixels().iter().any(|p| p[3] >= 0.95));
}

#[test]
fn renders_are_deterministic_and_options_are_checked() {
    let mesh = synth::torus_tets(16).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = orbit("perspective", 30.0, 40.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let opts = options(cam, 37, 29);
    let a = caster.render_with(&opts).unwrap();
    let b = caster.render_with(&opts).unwrap();
    assert_eq!(a.image, b.image);
    assert_eq!(a.image.width(), 37);
    assert!(a.image.coverage(1e-3) > 0.1);
    for (w, h) in [(0, 8), (8, 0), (40000, 8)] {
        let e = caster
            .render_with(&TetRayOptions {
                width: w,
                height: h,
                ..opts.clone()
            })
            .unwrap_err();
        assert!(matches!(e, RenderError::ImageSize { .. }), "{e}");
    }
    let mut bad = opts.clone();
    bad.camera.eye.x = f64::NAN;
    assert!(caster.render_with(&bad).is_err());
    let mut bad = opts.clone();
    bad.early_termination = Some(f32::NAN);
    assert!(caster.render_with(&bad).is_err());
    let cancel = Arc::new(AtomicBool::new(true));
    let e = caster
        .render_with(&TetRayOptions {
            control: Control::with_cancel(cancel),
            ..opts.clone()
        })
        .unwrap_err();
    assert!(matches!(e, RenderError::Cancelled), "{e}");
    let bpt = caster.bytes_per_tet();
    assert!(bpt > 64.0 && bpt < 400.0, "{bpt}");
    // A ray missing the mesh, a zero direction.
    assert!(caster
        .trace(DVec3::splat(5.0), DVec3::X)
        .segments
        .is_empty());
    assert!(caster.trace(DVec3::ZERO, DVec3::ZERO).segments.is_empty());
}

/// Adaptive parameters in units of `diagonal / 256` of the mesh (as the CLI's voxel units).
fn adaptive(mesh: &TetMesh, tol: f64, control: StepControl) -> SegmentRule {
    let unit = mesh.bounds().diagonal() / 256.0;
    SegmentRule::AdaptiveSimpson(AdaptiveParams {
        tol,
        h0: 2.0 * unit,
        hmin: 1e-3 * unit,
        hmax: 4.0 * unit,
        control,
        early_termination: None,
    })
}

#[test]
fn adaptive_simpson_matches_the_exact_colour_within_the_tolerance() {
    let tol = 1e-3;
    for (name, mesh) in [
        ("smooth", synth::smooth_tets(3000).unwrap()),
        ("torus", synth::torus_tets(24).unwrap()),
    ] {
        let caster = TetRayCaster::new(&mesh).unwrap();
        let cam = orbit("perspective", 35.0, 20.0, 1.0)
            .resolve(&mesh.bounds())
            .unwrap();
        let n = 64;
        let exact = caster.render_with(&options(cam, n, n)).unwrap();
        assert!(exact.error_map.iter().all(|&e| e == 0.0));
        assert_eq!(exact.stats.rays_over_tolerance, 0);
        assert!(exact.image.coverage(1e-3) > 0.1, "{name}");
        for control in [StepControl::Coupled, StepControl::Decoupled] {
            let got = caster
                .render_with(&TetRayOptions {
                    color: adaptive(&mesh, tol, control),
                    ..options(cam, n, n)
                })
                .unwrap();
            let ImageDiff {
                fraction_over: over,
                mean_error: mean,
                max_error: max,
                ..
            } = got.image.compare(&exact.image, tol).unwrap();
            let est_max = got.error_map.iter().copied().fold(0.0f32, f32::max);
            let est_mean = got.error_map.iter().sum::<f32>() / (n * n) as f32;
            eprintln!(
                "{name} {control:?}: {:.3} % over tol, mean {mean:.2e}, max {max:.2e}, \
                 estimated error mean {est_mean:.2e} max {est_max:.2e}, {:.0} samples/ray, \
                 {} rays over tolerance, {:?}",
                over * 100.0,
                got.stats.samples as f64 / got.stats.rays as f64,
                got.stats.rays_over_tolerance,
                got.stats
            );
            assert!(over <= 0.001, "{name} {control:?}: {over}");
            assert_eq!(got.error_map.len(), n * n);
            assert!(got.error_map.iter().any(|&e| e > 0.0));
            assert!(got.stats.samples > got.stats.segments);
            assert_eq!(got.stats.segments, exact.stats.segments);
            if name == "torus" {
                assert!(got.stats.reentries > 0);
            }
        }
    }
}

#[test]
fn adaptive_simpson_converges_and_respects_early_termination() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = orbit("orthographic", -60.0, 45.0, 1.3)
        .resolve(&mesh.bounds())
        .unwrap();
    let exact = caster.render_with(&options(cam, 32, 32)).unwrap();
    let mut last = f64::INFINITY;
    for tol in [1e-2, 1e-4] {
        let r = caster
            .render_with(&TetRayOptions {
                color: adaptive(&mesh, tol, StepControl::Coupled),
                ..options(cam, 32, 32)
            })
            .unwrap();
        let ImageDiff {
            mean_error: mean,
            max_error: max,
            ..
        } = r.image.compare(&exact.image, 0.0).unwrap();
        eprintln!("tol {tol}: mean {mean:.2e} max {max:.2e}");
        assert!(max <= tol * 2.0 + 1e-6, "tol {tol}: {max}");
        assert!(mean < last);
        last = mean;
    }
    // Early termination: an opaque TF stops rays (fewer samples), within the threshold.
    let mut opts = TetRayOptions {
        color: adaptive(&mesh, 1e-3, StepControl::Coupled),
        ..options(cam, 32, 32)
    };
    opts.tf = TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 1, 1, 1]], "extinction": [[0, 30], [1, 30]]}"#,
    )
    .unwrap();
    let full = caster.render_with(&opts).unwrap();
    opts.early_termination = Some(0.95);
    let early = caster.render_with(&opts).unwrap();
    assert!(early.stats.samples < full.stats.samples / 2);
    let max = full.image.compare(&early.image, 0.0).unwrap().max_error;
    assert!(max <= 0.05 + 2e-3, "{max}");
    // Bad parameters are rejected.
    let mut bad = options(cam, 8, 8);
    bad.color = SegmentRule::AdaptiveSimpson(AdaptiveParams {
        tol: 0.0,
        h0: 1.0,
        hmin: 1.0,
        hmax: 1.0,
        control: StepControl::Coupled,
        early_termination: None,
    });
    assert!(matches!(
        caster.render_with(&bad),
        Err(RenderError::Setting(SettingError {
            setting: Setting::Tolerance,
            ..
        }))
    ));
}

/// A lattice mesh of `n^3` points, spacing 1, scalar `z / (n - 1)`.
fn z_ramp(n: usize) -> TetMesh {
    let vals = (0..n * n * n)
        .map(|i| (i / (n * n)) as f32 / (n - 1) as f32)
        .collect();
    let g = Grid::new(
        [n; 3],
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(vals)),
    )
    .unwrap();
    grid_to_tets(&g).unwrap()
}

#[test]
fn opaque_isosurface_shows_its_lit_colour() {
    // Field s = z / 3 seen from above (orthographic, headlight): the isosurface z = 1.5 faces
    // the viewer, so its lit colour is rgb (ambient + diffuse) + specular exactly.
    let mesh = z_ramp(4);
    let caster = TetRayCaster::new(&mesh).unwrap();
    let cam = Camera {
        eye: DVec3::new(1.5, 1.5, 10.0),
        target: DVec3::new(1.5, 1.5, 1.5),
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 2.0 },
    };
    let zero = TransferFunction::from_json(
        r#"{"color": [[0, 0, 0, 0], [1, 0, 0, 0]], "extinction": [[0, 0], [1, 0]]}"#,
    )
    .unwrap();
    let iso = Isosurfaces::new(vec![Isovalue {
        value: 0.5,
        rgba: [0.8, 0.4, 0.2, 1.0],
    }])
    .unwrap();
    let sh = BlinnPhong::default();
    let expect = [0.8, 0.4, 0.2].map(|c| c * (sh.ambient + sh.diffuse) + sh.specular);
    for color in [
        SegmentRule::Exact,
        SegmentRule::Psi,
        adaptive(&mesh, 1e-3, StepControl::Coupled),
    ] {
        let mut o = options(cam, 16, 16);
        o.tf = zero.clone();
        o.color = color;
        o.isosurfaces = iso.clone();
        let out = caster.render_with(&o).unwrap();
        for p in out.image.pixels() {
            assert!((p[3] - 1.0).abs() < 1e-6, "{color:?}: alpha {}", p[3]);
            for c in 0..3 {
                assert!(
                    (p[c] - expect[c]).abs() < 1e-4,
                    "{color:?}: {p:?} vs {expect:?}"
                );
            }
        }
    }
}

#[test]
fn isosurfaces_agree_with_projected_tetrahedra() {
    use crate::pt::{PtOptions, PtRenderer, SortMode};
    let mesh = synth::smooth_tets(3000).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let [lo, hi] = mesh.range();
    let at = |f: f64| (lo + f * (hi - lo)) as f32;
    let iso = Isosurfaces::new(vec![
        Isovalue {
            value: at(0.35),
            rgba: [0.9, 0.3, 0.2, 0.6],
        },
        Isovalue {
            value: at(0.7),
            rgba: [0.2, 0.5, 1.0, 0.9],
        },
    ])
    .unwrap();
    let b = mesh.bounds();
    for (i, cam) in [
        orbit("perspective", 35.0, 20.0, 1.0).resolve(&b).unwrap(),
        orbit("orthographic", -60.0, 45.0, 1.3).resolve(&b).unwrap(),
    ]
    .into_iter()
    .enumerate()
    {
        let n = 64;
        // A light TF, so the surfaces show through the volume.
        let light = tf().with_opacity_scale(0.25);
        let mut o = options(cam, n, n);
        o.tf = light.clone();
        o.isosurfaces = iso.clone();
        let ray = caster.render_with(&o).unwrap();
        let mut po = PtOptions::new(cam, light.clone());
        (po.width, po.height) = (n, n);
        po.sort = SortMode::Exact;
        po.color = SegmentRule::Exact;
        po.early_termination = None;
        po.isosurfaces = iso.clone();
        let pt = PtRenderer::new(&mesh).render_with(&po).unwrap();
        let ImageDiff {
            mean_error: mean,
            max_error: max,
            ..
        } = ray.image.compare(&pt.image, 0.0).unwrap();
        let plain = caster
            .render_with(&TetRayOptions {
                isosurfaces: Isosurfaces::default(),
                ..o.clone()
            })
            .unwrap();
        let shown = ray.image.compare(&plain.image, 0.0).unwrap().mean_error;
        eprintln!("camera {i}: PT vs tetray with isosurfaces: mean {mean:.2e}, max {max:.2e}; surfaces change the image by {shown:.2e}");
        assert!(shown > 0.01, "the surfaces show");
        assert!(mean < 1.0 / 255.0, "camera {i}: mean {mean}, max {max}");
        // The adaptive rule draws the same surfaces.
        o.color = adaptive(&mesh, 1e-3, StepControl::Coupled);
        let ad = caster.render_with(&o).unwrap();
        let ImageDiff {
            fraction_over: over,
            mean_error: mean,
            max_error: max,
            ..
        } = ad.image.compare(&ray.image, 1e-3).unwrap();
        eprintln!("camera {i}: adaptive vs exact with isosurfaces: {:.3} % over, mean {mean:.2e}, max {max:.2e}", over * 100.0);
        assert!(over <= 0.01, "camera {i}: {over}");
    }
}

#[test]
fn mip_shows_the_colour_of_the_largest_scalar() {
    for (name, mesh) in [
        ("smooth", synth::smooth_tets(3000).unwrap()),
        ("torus", synth::torus_tets(24).unwrap()),
    ] {
        let caster = TetRayCaster::new(&mesh).unwrap();
        let b = mesh.bounds();
        for cam in [
            orbit("perspective", 35.0, 20.0, 1.0).resolve(&b).unwrap(),
            orbit("orthographic", 100.0, -30.0, 1.2)
                .resolve(&b)
                .unwrap(),
        ] {
            let n = 40;
            let mut o = options(cam, n, n);
            o.mip = true;
            // Ignored by MIP.
            o.color = SegmentRule::Psi;
            o.early_termination = Some(0.5);
            let got = caster.render_with(&o).unwrap();
            let tf = o.tf.resolved(mesh.range());
            let mut hits = 0;
            for y in 0..n {
                for x in 0..n {
                    let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, n, n);
                    let segs = ray_segments(&mesh, ray.origin, ray.dir);
                    let want = segs
                        .iter()
                        .flat_map(|s| [s.s_in, s.s_out])
                        .reduce(f64::max)
                        .map_or([0.0; 4], |v| {
                            let c = tf.color_at(v);
                            [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
                        });
                    hits += usize::from(!segs.is_empty());
                    let p = got.image.pixels()[y * n + x];
                    for c in 0..4 {
                        assert!(
                            (p[c] - want[c]).abs() < 1e-6,
                            "{name} pixel {x} {y}: {p:?} vs {want:?}"
                        );
                    }
                }
            }
            assert!(hits > n * n / 10, "{name}: {hits}");
            assert_eq!(got.stats.samples, 2 * got.stats.segments);
        }
    }
}

/// Release-mode timing: `cargo test --release -p volux-render tetray::tests::timing -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn timing_512_smooth_200k() {
    let t = std::time::Instant::now();
    let n = std::env::var("VOLUX_TETRAY_TETS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200_000);
    let mesh = synth::smooth_tets(n).unwrap();
    let gen = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let build = t.elapsed().as_secs_f64();
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let mut opts = TetRayOptions::new(cam, tf());
    opts.early_termination = None;
    for color in [SegmentRule::Exact, SegmentRule::Psi] {
        opts.color = color;
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..3 {
            let r = caster.render_with(&opts).unwrap();
            best = best.min(r.stats.seconds);
            last = Some(r.stats);
        }
        let s = last.unwrap();
        eprintln!(
            "tetray {color:?} 512x512, {} tets: {:.1} ms/frame, {:.2} M tets/s, {:.1} segments/ray, abandoned {}",
            mesh.tets().len(),
            best * 1e3,
            mesh.tets().len() as f64 / best / 1e6,
            s.segments as f64 / s.rays as f64,
            s.abandoned
        );
        assert_eq!(s.abandoned, 0);
    }
    // The walk alone (no integration), single-threaded over every 4th row.
    let walker = super::walk::Walker {
        geo: &caster.geo,
        boundary: &caster.boundary,
        start: &super::bvh::Bvh::default(),
        max_steps: usize::MAX,
    };
    let mut scratch = super::walk::Scratch::default();
    let t = std::time::Instant::now();
    let mut segs = 0;
    for y in (0..512).step_by(4) {
        for x in 0..512 {
            let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, 512, 512);
            segs += walker
                .trace(ray.origin, ray.dir, &mut scratch, |_| true)
                .segments;
        }
    }
    let walk = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let mut hits = 0;
    for y in (0..512).step_by(4) {
        for x in 0..512 {
            let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, 512, 512);
            hits += usize::from(
                caster
                    .boundary
                    .nearest(&caster.geo, ray.origin, ray.dir, 0.0)
                    .is_some(),
            );
        }
    }
    eprintln!(
        "one thread, 1/4 of the rays: walk {:.0} ms ({:.0} ns/segment), entry queries {:.0} ms ({hits} hits)",
        walk * 1e3,
        walk * 1e9 / segs as f64,
        t.elapsed().as_secs_f64() * 1e3
    );
    eprintln!(
        "mesh gen {:.0} ms, caster build {:.0} ms, {:.1} bytes/tet, {} threads",
        gen * 1e3,
        build * 1e3,
        caster.bytes_per_tet(),
        rayon::current_num_threads()
    );
}

/// A TF with zero extinction over `[0, 0.25]` and `[0.62, 0.72]` of the range: runs of
/// invisible cells for empty-space skipping.
pub(super) fn gappy_tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 0.1, 0.2, 0.9], [0.5, 1, 0.6, 0.1], [1, 0.3, 1, 0.5]],
            "extinction": [[0, 0], [0.25, 0], [0.4, 3], [0.55, 3], [0.62, 0], [0.72, 0], [0.85, 5], [1, 2]]}"#,
    )
    .unwrap()
}

/// A TF visible only over `[0.3, 0.45]` of the range (the torus's field is mostly visible
/// under [`gappy_tf`]).
pub(super) fn band_tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 0.1, 0.2, 0.9], [0.5, 1, 0.6, 0.1], [1, 0.3, 1, 0.5]],
            "extinction": [[0, 0], [0.3, 0], [0.35, 4], [0.4, 4], [0.45, 0], [1, 0]]}"#,
    )
    .unwrap()
}

/// The TF with runs of invisible cells for each test mesh.
fn skip_tf(name: &str) -> TransferFunction {
    if name == "torus" {
        band_tf()
    } else {
        gappy_tf()
    }
}

/// Renders `opts` with and without empty-space skipping and checks that the images agree
/// and that cells were skipped; returns the skipping frame's statistics.
fn check_skipping(
    caster: &TetRayCaster<&TetMesh>,
    opts: &TetRayOptions,
    label: &str,
) -> TetRayStats {
    let skip = caster.render_with(opts).unwrap();
    let full = caster
        .render_with(&TetRayOptions {
            skip_empty: false,
            ..opts.clone()
        })
        .unwrap();
    let d = skip.image.compare(&full.image, 0.0).unwrap();
    let s = &skip.stats;
    eprintln!(
        "{label}: max {:.2e}, mean {:.2e}; segments {} of {}, {} visible cells of {}, {} skips",
        d.max_error,
        d.mean_error,
        s.segments,
        full.stats.segments,
        s.visible_cells,
        s.tets,
        s.skips
    );
    assert!(d.max_error < 1e-6, "{label}: {d:?}");
    assert!(
        full.image.coverage(1e-3) > 0.1,
        "{label}: the view must show the mesh"
    );
    assert!(
        s.visible_cells > 0 && s.visible_cells < s.tets,
        "{label}: {s:?}"
    );
    assert!(s.segments < full.stats.segments, "{label}: {s:?}");
    assert_eq!(full.stats.visible_cells, 0, "{label}");
    assert_eq!(s.abandoned + full.stats.abandoned, 0, "{label}");
    skip.stats
}

#[test]
fn empty_space_skipping_leaves_the_image_unchanged() {
    let iso = |mesh: &TetMesh, f: f64| {
        let r = mesh.range();
        Isosurfaces::new(vec![Isovalue {
            value: (r[0] + f * (r[1] - r[0])) as f32,
            rgba: [0.9, 0.8, 0.2, 0.6],
        }])
        .unwrap()
    };
    let smooth = synth::smooth_tets(3000).unwrap();
    let torus = synth::torus_tets(24).unwrap();
    for (name, mesh) in [("smooth", &smooth), ("torus", &torus)] {
        let caster = TetRayCaster::new(mesh).unwrap();
        let b = mesh.bounds();
        let mut cams = vec![
            orbit("perspective", 10.0, 25.0, 1.0).resolve(&b).unwrap(),
            orbit("orthographic", 30.0, -20.0, 1.0).resolve(&b).unwrap(),
        ];
        if name == "torus" {
            // From inside the tube.
            cams.push(Camera {
                eye: DVec3::new(1.3, 0.0, 0.05),
                target: DVec3::new(0.0, 1.2, 0.0),
                up: DVec3::Z,
                projection: Projection::Perspective { fov_y_deg: 80.0 },
            });
        }
        let mut passes = 0;
        for (c, &cam) in cams.iter().enumerate() {
            for color in [SegmentRule::Exact, SegmentRule::Psi] {
                for isos in [Isosurfaces::default(), iso(mesh, 0.2), iso(mesh, 0.67)] {
                    let label = format!("{name} camera {c} {} {} iso", color.name(), isos.len());
                    let opts = TetRayOptions {
                        tf: skip_tf(name),
                        color,
                        isosurfaces: isos,
                        ..options(cam, 40, 40)
                    };
                    let s = check_skipping(&caster, &opts, &label);
                    passes += s.skips + s.reentries;
                }
            }
        }
        assert!(passes > 0, "{name}: some rays jump or re-enter");
    }
}

#[test]
fn empty_space_skipping_matches_the_reference() {
    for (name, mesh) in [
        ("smooth", synth::smooth_tets(3000).unwrap()),
        ("torus", synth::torus_tets(24).unwrap()),
    ] {
        let caster = TetRayCaster::new(&mesh).unwrap();
        let camera = orbit("perspective", 10.0, 25.0, 1.0)
            .resolve(&mesh.bounds())
            .unwrap();
        let opts = TetRayOptions {
            tf: skip_tf(name),
            ..options(camera, 48, 48)
        };
        let got = caster.render_with(&opts).unwrap();
        assert!(got.stats.visible_cells > 0, "{name}: skipping is on");
        let want = render_mesh_reference(
            &mesh,
            &ReferenceOptions {
                width: 48,
                height: 48,
                camera,
                tf: skip_tf(name),
                clip_planes: Vec::new(),
            },
        )
        .unwrap();
        let d = got.image.compare(&want, 0.0).unwrap();
        eprintln!("{name}: max {:.2e}, mean {:.2e}", d.max_error, d.mean_error);
        assert!(d.mean_error < 1e-4 && d.max_error < 1e-2, "{name}: {d:?}");
    }
}

#[test]
fn empty_space_skipping_does_not_depend_on_the_thread_count() {
    let mesh = synth::torus_tets(24).unwrap();
    let caster = TetRayCaster::new(&mesh).unwrap();
    let camera = orbit("perspective", 10.0, 25.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let opts = TetRayOptions {
        tf: band_tf(),
        ..options(camera, 64, 64)
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| caster.render_with(&opts).unwrap());
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap()
        .install(|| caster.render_with(&opts).unwrap());
    assert!(one.stats.visible_cells > 0);
    assert_eq!(one.image, many.image);
    assert_eq!(one.stats.segments, many.stats.segments);
}
