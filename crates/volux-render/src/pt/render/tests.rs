//! PT against independent references: the brute-force per-pixel ray/tetrahedron integrator
//! ([`crate::pt::reference`]) and closed forms.
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::Vec3;
use volux_core::image::ImageDiff;
use volux_core::{synth, Camera, CameraSpec, Image, TetMesh, TransferFunction};

use super::*;
use crate::integrate::SegmentRule;
use crate::isosurface::Isovalue;
use crate::pt::reference::{render_mesh_reference, ReferenceOptions};

/// A semi-transparent TF in normalized space with several pieces.
fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"space": "normalized",
        "color": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.5, 0.1], [1, 1, 1, 1]],
        "extinction": [[0, 0.2], [0.3, 1.5], [0.5, 0.3], [0.8, 2.5], [1, 0.5]]}"#,
    )
    .unwrap()
}

fn camera(mesh: &TetMesh, azimuth: f64, elevation: f64, ortho: bool) -> Camera {
    CameraSpec {
        azimuth: Some(azimuth),
        elevation: Some(elevation),
        projection: ortho.then(|| "orthographic".to_string()),
        ..Default::default()
    }
    .resolve(&mesh.bounds())
    .unwrap()
}

fn opts(camera: Camera, tf: TransferFunction, size: usize) -> PtOptions {
    let mut o = PtOptions::new(camera, tf);
    (o.width, o.height) = (size, size);
    o.early_termination = None;
    o.color = SegmentRule::Exact;
    o.sort = SortMode::Exact;
    o
}

fn reference(mesh: &TetMesh, o: &PtOptions) -> Image {
    let r = ReferenceOptions {
        width: o.width,
        height: o.height,
        camera: o.camera,
        tf: o.tf.clone(),
        clip_planes: Vec::new(),
    };
    render_mesh_reference(mesh, &r).unwrap()
}

fn grid_f32(dims: [usize; 3], v: Vec<f32>) -> volux_core::Grid {
    volux_core::Grid::new(
        dims,
        [1.0; 3],
        [0.0; 3],
        volux_core::Samples::F32(volux_core::Buffer::owned(v)),
    )
    .unwrap()
}

fn one_tet(p: [[f32; 3]; 4], s: [f32; 4]) -> TetMesh {
    TetMesh::new(
        p.iter().map(|v| Vec3::from_array(*v)).collect(),
        s.to_vec(),
        vec![[0, 1, 2, 3]],
    )
    .unwrap()
}

/// An orthographic camera looking down -z at the unit square (x right, y up).
fn top_view() -> Camera {
    Camera {
        eye: glam::DVec3::new(0.5, 0.5, 5.0),
        target: glam::DVec3::new(0.5, 0.5, 0.0),
        up: glam::DVec3::Y,
        projection: volux_core::Projection::Orthographic { height: 1.6 },
    }
}

#[test]
fn single_tets_of_every_class_match_the_exact_ray_integral() {
    let s = [0.0, 0.4, 0.7, 1.0];
    let cases: [(&str, [[f32; 3]; 4]); 4] = [
        // Class 1: the apex projects inside the base triangle.
        (
            "class 1",
            [
                [0.1, 0.1, 0.0],
                [0.9, 0.2, 0.0],
                [0.3, 0.9, 0.0],
                [0.4, 0.4, 0.8],
            ],
        ),
        // Class 2: two edges cross in projection.
        (
            "class 2",
            [
                [0.1, 0.1, 0.0],
                [0.9, 0.9, 0.0],
                [0.9, 0.1, 0.7],
                [0.1, 0.9, 0.3],
            ],
        ),
        // Class 3: a vertex projects onto the opposite edge.
        (
            "class 3",
            [
                [0.1, 0.2, 0.0],
                [0.9, 0.2, 0.0],
                [0.5, 0.2, 0.8],
                [0.4, 0.9, 0.3],
            ],
        ),
        // Class 4: an edge seen end-on.
        (
            "class 4",
            [
                [0.5, 0.5, 0.0],
                [0.5, 0.5, 0.9],
                [0.9, 0.1, 0.3],
                [0.1, 0.2, 0.5],
            ],
        ),
    ];
    for (name, p) in cases {
        let mesh = one_tet(p, s);
        let o = opts(top_view(), tf(), 48);
        let mut r = PtRenderer::new(&mesh);
        let out = r.render_with(&o).unwrap();
        assert_eq!(out.stats.tets_drawn, 1, "{name}");
        let refi = reference(&mesh, &o);
        let ImageDiff {
            mean_error: mean,
            max_error: max,
            ..
        } = out.image.compare(&refi, 0.0).unwrap();
        assert!(out.image.coverage(0.01) > 0.05, "{name}: nothing drawn");
        // Interior pixels match to rounding; silhouette pixels can differ only where a pixel
        // centre lies on the silhouette (f32 vs f64 inside tests).
        assert!(
            mean < 2e-4 && max < 0.05,
            "{name}: mean {mean:.2e} max {max:.2e}"
        );
    }
}

#[test]
fn degenerate_tet_is_discarded() {
    // Seen edge-on: the first four vertices project onto one line (they lie in y = 0.5). A
    // valid tet far off screen keeps the mesh from being flat, which `TetMesh::new` refuses.
    let p = [
        [0.1, 0.5, 0.0],
        [0.9, 0.5, 0.0],
        [0.5, 0.5, 0.8],
        [0.3, 0.5, 0.3],
        [10.0, 10.0, 0.0],
        [11.0, 10.0, 0.0],
        [10.0, 11.0, 0.0],
        [10.0, 10.0, 1.0],
    ];
    let mesh = TetMesh::new(
        p.iter().map(|v| Vec3::from_array(*v)).collect(),
        vec![0.0, 0.4, 0.7, 1.0, 0.5, 0.5, 0.5, 0.5],
        vec![[0, 1, 2, 3], [4, 5, 6, 7]],
    )
    .unwrap();
    let out = PtRenderer::new(&mesh)
        .render_with(&opts(top_view(), tf(), 32))
        .unwrap();
    assert_eq!(out.stats.degenerate, 1);
    assert_eq!(out.stats.tets_drawn, 1, "only the off-screen tet");
    assert!(out.image.pixels().iter().all(|p| p[3] == 0.0));
}

#[test]
fn convex_mesh_with_exact_order_and_colour_matches_reference() {
    let mesh = synth::smooth_tets(3000).unwrap();
    for (az, el, ortho) in [
        (30.0, 20.0, false),
        (-70.0, 45.0, true),
        (200.0, -30.0, false),
    ] {
        let o = opts(camera(&mesh, az, el, ortho), tf(), 64);
        let out = PtRenderer::new(&mesh).render_with(&o).unwrap();
        assert_eq!(out.stats.exact_strategy, "mpvo");
        let ImageDiff {
            mean_error: mean,
            max_error: max,
            ..
        } = out.image.compare(&reference(&mesh, &o), 0.0).unwrap();
        eprintln!("convex az {az}: mean {mean:.2e}, max {max:.2e}");
        assert!(mean < 1.0 / 255.0 / 10.0, "mean {mean}");
        assert!(max < 0.05, "max {max}");
    }
}

#[test]
fn non_convex_torus_with_exact_order_matches_reference() {
    let mesh = synth::torus_tets(24).unwrap();
    let o = opts(camera(&mesh, 20.0, 35.0, false), tf(), 64);
    let out = PtRenderer::new(&mesh).render_with(&o).unwrap();
    assert_eq!(out.stats.exact_strategy, "per-pixel");
    let ImageDiff {
        mean_error: mean,
        max_error: max,
        ..
    } = out.image.compare(&reference(&mesh, &o), 0.0).unwrap();
    eprintln!("torus: mean {mean:.2e}, max {max:.2e}");
    assert!(mean < 1.0 / 255.0, "mean {mean}");
    assert!(max < 0.1, "max {max}");
}

#[test]
fn centroid_order_is_close_on_a_convex_mesh_and_reports_violations() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let mut o = opts(camera(&mesh, 30.0, 20.0, true), tf(), 64);
    o.sort = SortMode::Centroid;
    o.count_violations = true;
    let out = PtRenderer::new(&mesh).render_with(&o).unwrap();
    assert!(out.stats.sort_violations.is_some());
    let mean = out
        .image
        .compare(&reference(&mesh, &o), 0.0)
        .unwrap()
        .mean_error;
    assert!(mean < 1.0 / 255.0, "mean {mean}");
}

#[test]
fn psi_and_average_modes_approach_exact() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let mut o = opts(camera(&mesh, 30.0, 20.0, false), tf(), 64);
    let exact = PtRenderer::new(&mesh).render_with(&o).unwrap().image;
    o.color = SegmentRule::Psi;
    let psi = PtRenderer::new(&mesh).render_with(&o).unwrap().image;
    o.color = SegmentRule::Average;
    let avg = PtRenderer::new(&mesh).render_with(&o).unwrap().image;
    let mp = psi.compare(&exact, 0.0).unwrap().mean_error;
    let ma = avg.compare(&exact, 0.0).unwrap().mean_error;
    eprintln!("psi mean {mp:.2e}, average mean {ma:.2e}");
    // ψ cut at the TF's breakpoints is exact up to its table's interpolation error.
    assert!(mp < 2e-5, "psi mean error {mp}");
    assert!(
        mp * 10.0 < ma,
        "psi ({mp}) must be far closer to exact than average ({ma})"
    );
    assert!(ma < 8.0 / 255.0, "average mean error {ma}");
    assert!(
        mp > 0.0 && ma > 0.0,
        "modes must differ from exact (different models)"
    );
}

#[test]
fn thread_count_does_not_change_the_image() {
    let mesh = synth::smooth_tets(3000).unwrap();
    let mut o = opts(camera(&mesh, 30.0, 20.0, false), tf(), 80);
    o.color = SegmentRule::Psi;
    o.sort = SortMode::Centroid;
    let many = PtRenderer::new(&mesh).render_with(&o).unwrap().image;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let one = pool.install(|| PtRenderer::new(&mesh).render_with(&o).unwrap().image);
    assert_eq!(many.pixels(), one.pixels());
}

#[test]
fn constant_medium_box_has_no_cracks_or_double_blending() {
    // Constant scalar, constant extinction: each pixel's opacity is 1 - exp(-tau L) with L
    // the box's thickness along the pixel ray. A gap or a doubly blended fragment on any of
    // the many shared faces would show as a large local error.
    let grid = grid_f32([6, 6, 6], vec![0.5; 216]);
    let mesh = volux_core::tetrahedralize::grid_to_tets(&grid).unwrap();
    let tf = TransferFunction::from_json(
        r#"{"color": [[0, 1, 1, 1], [1, 1, 1, 1]], "extinction": [[0, 0.3], [1, 0.3]]}"#,
    )
    .unwrap();
    let o = opts(camera(&mesh, 33.0, 27.0, false), tf, 96);
    let out = PtRenderer::new(&mesh).render_with(&o).unwrap();
    let d = out.image.compare(&reference(&mesh, &o), 1e-3).unwrap();
    let (mean, max) = (d.mean_error, d.max_error);
    assert!(mean < 1e-4, "mean {mean}");
    // Only silhouette pixels may differ (a centre exactly on the outline).
    let big = (d.fraction_over_per_channel[3] * d.pixels as f64).round() as usize;
    assert!(big <= 4, "{big} pixels differ, max {max}");
}

#[test]
fn opaque_isosurface_shows_its_lit_colour() {
    // Field s = z on a box seen from above (orthographic, headlight): the isosurface z = 0.5
    // faces the viewer, so its lit colour is rgb (ambient + diffuse) + specular exactly.
    let grid = grid_f32([4, 4, 4], (0..64).map(|i| (i / 16) as f32 / 3.0).collect());
    let mesh = volux_core::tetrahedralize::grid_to_tets(&grid).unwrap();
    let b = mesh.bounds();
    let cam = Camera {
        eye: glam::DVec3::new(1.5, 1.5, 10.0),
        target: glam::DVec3::new(1.5, 1.5, 1.5),
        up: glam::DVec3::Y,
        projection: volux_core::Projection::Orthographic { height: 2.0 },
    };
    let zero = TransferFunction::from_json(
        r#"{"color": [[0, 0, 0, 0], [1, 0, 0, 0]], "extinction": [[0, 0], [1, 0]]}"#,
    )
    .unwrap();
    let mut o = opts(cam, zero, 16);
    o.isosurfaces = Isosurfaces::new(vec![Isovalue {
        value: 0.5,
        rgba: [0.8, 0.4, 0.2, 1.0],
    }])
    .unwrap();
    let out = PtRenderer::new(&mesh).render_with(&o).unwrap();
    let sh = BlinnPhong::default();
    let expect = [0.8, 0.4, 0.2].map(|c| c * (sh.ambient + sh.diffuse) + sh.specular);
    for p in out.image.pixels() {
        assert!((p[3] - 1.0).abs() < 1e-6, "alpha {}", p[3]);
        for c in 0..3 {
            assert!((p[c] - expect[c]).abs() < 2e-3, "{p:?} vs {expect:?}");
        }
    }
    assert!(
        out.stats.tets_kept < out.stats.tets,
        "tets not crossed by the surface discarded"
    );
    let _ = b;
}

#[test]
fn discarded_tets_do_not_change_the_image_and_recolouring_reuses_the_view() {
    let mesh = synth::smooth_tets(3000).unwrap();
    // Zero extinction below the middle of the range.
    let half = TransferFunction::from_json(
        r#"{"space": "normalized", "color": [[0, 1, 0.5, 0.2], [1, 0.2, 0.5, 1]],
        "extinction": [[0, 0], [0.5, 0], [0.6, 2], [1, 1]]}"#,
    )
    .unwrap();
    let o = opts(camera(&mesh, 30.0, 20.0, false), half.clone(), 64);
    let mut r = PtRenderer::new(&mesh);
    let first = r.render_with(&o).unwrap();
    assert!(first.stats.tets_kept < first.stats.tets);
    let mean = first
        .image
        .compare(&reference(&mesh, &o), 0.0)
        .unwrap()
        .mean_error;
    assert!(mean < 1.0 / 255.0 / 10.0, "mean {mean}");
    // Same zero set, new colours: no new per-tetrahedron pass.
    let mut o2 = o.clone();
    o2.tf = half.with_opacity_scale(2.0);
    let second = r.render_with(&o2).unwrap();
    assert_eq!(second.stats.project_s, 0.0, "view data reused");
    let fresh = PtRenderer::new(&mesh).render_with(&o2).unwrap();
    assert_eq!(second.image.pixels(), fresh.image.pixels());
}

#[test]
fn cancellation_and_bad_options() {
    let mesh = synth::smooth_tets(500).unwrap();
    let mut o = opts(camera(&mesh, 0.0, 0.0, false), tf(), 32);
    o.control.cancel = Some(Arc::new(AtomicBool::new(true)));
    assert!(matches!(
        PtRenderer::new(&mesh).render_with(&o),
        Err(RenderError::Cancelled)
    ));
    o.control.cancel = None;
    o.width = 0;
    assert!(matches!(
        PtRenderer::new(&mesh).render_with(&o),
        Err(RenderError::ImageSize { .. })
    ));
}
