use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use volux_core::grid::{Buffer, Samples};
use volux_core::tetrahedralize::grid_to_tets;
use volux_core::{synth, Camera, CameraSpec, Grid, Image, Projection, TetMesh, TransferFunction};

use super::*;
use crate::pt::reference::{ray_segments, render_mesh_reference, ReferenceOptions};
use crate::RenderError;

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

/// Mean (per channel) and max absolute difference.
fn diff(a: &Image, b: &Image) -> (f64, f64) {
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels().iter().zip(b.pixels()) {
        for c in 0..4 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            sum += d;
            max = max.max(d);
        }
    }
    (sum / (a.pixels().len() * 4) as f64, max)
}

/// Renders with the caster and the reference and checks they agree.
fn check_against_reference(
    mesh: &TetMesh,
    caster: &TetRayCaster,
    camera: Camera,
    n: usize,
    label: &str,
) -> TetRayStats {
    let opts = options(camera, n, n);
    let got = caster.render(&opts).unwrap();
    let want = render_mesh_reference(
        mesh,
        &ReferenceOptions {
            width: n,
            height: n,
            camera,
            tf: opts.tf.clone(),
        },
    )
    .unwrap();
    let (mean, max) = diff(&got.image, &want);
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
    let caster = TetRayCaster::new(&mesh);
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
    let caster = TetRayCaster::new(&mesh);
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
    let caster = TetRayCaster::new(&mesh);
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
    let caster = TetRayCaster::new(&mesh);
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
fn lattice(n: usize) -> TetMesh {
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
    let caster = TetRayCaster::new(&mesh);
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
            color: TetRayColor::Exact,
            ..options(camera, n, n)
        };
        let img = caster.render(&opts).unwrap();
        assert_eq!(img.stats.abandoned, 0);
        let reference = render_mesh_reference(
            &mesh,
            &ReferenceOptions {
                width: n,
                height: n,
                camera,
                tf: opts.tf.clone(),
            },
        )
        .unwrap();
        let (mean, max) = diff(&img.image, &reference);
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
    let caster = TetRayCaster::new(&mesh);
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
    let caster = TetRayCaster::new(&mesh);
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let exact = caster.render(&options(cam, 40, 40)).unwrap();
    let psi = caster
        .render(&TetRayOptions {
            color: TetRayColor::Psi,
            ..options(cam, 40, 40)
        })
        .unwrap();
    let (mean, max) = diff(&exact.image, &psi.image);
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
    let caster = TetRayCaster::new(&mesh);
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let mut opts = options(cam, 40, 40);
    // Dense enough to become opaque.
    opts.tf = TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 1, 1, 1]], "extinction": [[0, 30], [1, 30]]}"#,
    )
    .unwrap();
    let full = caster.render(&opts).unwrap();
    opts.early_termination = Some(0.95);
    let early = caster.render(&opts).unwrap();
    assert!(
        early.stats.segments < full.stats.segments / 2,
        "{:?}",
        early.stats
    );
    let (_, max) = diff(&full.image, &early.image);
    assert!(max <= 0.05 + 1e-6, "{max}");
    assert!(early.image.pixels().iter().any(|p| p[3] >= 0.95));
}

#[test]
fn renders_are_deterministic_and_options_are_checked() {
    let mesh = synth::torus_tets(16).unwrap();
    let caster = TetRayCaster::new(&mesh);
    let cam = orbit("perspective", 30.0, 40.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let opts = options(cam, 37, 29);
    let a = caster.render(&opts).unwrap();
    let b = caster.render(&opts).unwrap();
    assert_eq!(a.image, b.image);
    assert_eq!(a.image.width(), 37);
    assert!(a.image.coverage(1e-3) > 0.1);
    for (w, h) in [(0, 8), (8, 0), (40000, 8)] {
        let e = caster
            .render(&TetRayOptions {
                width: w,
                height: h,
                ..opts.clone()
            })
            .unwrap_err();
        assert!(matches!(e, RenderError::InvalidOptions(_)), "{e}");
    }
    let mut bad = opts.clone();
    bad.camera.eye.x = f64::NAN;
    assert!(caster.render(&bad).is_err());
    let mut bad = opts.clone();
    bad.early_termination = Some(f32::NAN);
    assert!(caster.render(&bad).is_err());
    let cancel = Arc::new(AtomicBool::new(true));
    let e = caster
        .render(&TetRayOptions {
            cancel: Some(cancel),
            ..opts.clone()
        })
        .unwrap_err();
    assert!(matches!(e, RenderError::Cancelled), "{e}");
    assert_eq!(TetRayColor::parse("psi"), Ok(TetRayColor::Psi));
    assert!(TetRayColor::parse("nope").is_err());
    let bpt = caster.bytes_per_tet();
    assert!(bpt > 64.0 && bpt < 400.0, "{bpt}");
    // A ray missing the mesh, a zero direction.
    assert!(caster
        .trace(DVec3::splat(5.0), DVec3::X)
        .segments
        .is_empty());
    assert!(caster.trace(DVec3::ZERO, DVec3::ZERO).segments.is_empty());
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
    let caster = TetRayCaster::new(&mesh);
    let build = t.elapsed().as_secs_f64();
    let cam = orbit("perspective", 35.0, 20.0, 1.0)
        .resolve(&mesh.bounds())
        .unwrap();
    let mut opts = TetRayOptions::new(cam, tf());
    opts.early_termination = None;
    for color in [TetRayColor::Exact, TetRayColor::Psi] {
        opts.color = color;
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..3 {
            let r = caster.render(&opts).unwrap();
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
