//! One test matrix for every method of the engine API (VTK's one harness for many
//! integrators): the same analytic scene rendered by each method through
//! [`create_renderer`] and [`Renderer::render`], compared with an independent reference.
//!
//! The scene is the linear field `f(x, y, z) = 2x + y - z/2` on the unit cube, seen in
//! perspective. Trilinear interpolation of a grid reproduces a linear field exactly, and so
//! does the linear interpolation of its tetrahedral split, so every method sees the same
//! field and differs only by its integration. Along each ray the scalar is then linear
//! between the cube's entry and exit, and the reference colour of a pixel is the
//! emission-absorption integral of that one segment, computed by brute force
//! ([`segment_simpson`], composite Simpson with 4000 steps split at the TF's breakpoints),
//! independently of the renderers' integrators. MIP's reference is the TF colour of the
//! larger end value.
use glam::DVec3;
use volux_core::{CameraSpec, Grid, Image, TransferFunction};
use volux_render::engine::render_once;
use volux_render::integrate::{AdaptiveParams, Integrator, SegmentRule, StepControl};
use volux_render::pt::SortMode;
use volux_render::raycast::ray_box;
use volux_render::scene::{GridRaycast, Method, PtSettings, Scene, Volume};
use volux_render::tiles::Control;
use volux_testkit::images::{assert_images_close, Tolerance};
use volux_testkit::reference::segment_simpson;

const N: usize = 17;
const SIZE: usize = 40;

fn field(p: DVec3) -> f64 {
    2.0 * p.x + p.y - 0.5 * p.z
}

/// The field sampled on an `N^3` grid over the unit cube.
fn grid() -> Grid {
    let h = 1.0 / (N - 1) as f64;
    let mut v = Vec::with_capacity(N * N * N);
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                v.push(field(DVec3::new(i as f64, j as f64, k as f64) * h) as f32);
            }
        }
    }
    let samples = volux_core::Samples::F32(volux_core::Buffer::owned(v));
    Grid::new([N; 3], [h; 3], [0.0; 3], samples).unwrap()
}

/// Colour ramp and an extinction with a gap, a peak and a slope (per world unit).
fn tf() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"color": [[-0.5, 0.1, 0.2, 0.9], [1.25, 0.9, 0.5, 0.1], [3, 1, 1, 1]],
            "extinction": [[-0.5, 0], [0.5, 0], [1.0, 4], [1.5, 0.5], [3, 1.5]]}"#,
    )
    .unwrap()
}

fn scene(volume: &Volume) -> Scene {
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let mut s = Scene::new(spec.resolve(&volume.bounds()).unwrap(), SIZE, SIZE, tf());
    s.early_termination = None;
    s
}

/// The reference image: per pixel, the one linear segment of its ray through the cube.
fn reference(scene: &Scene, mip: bool) -> Image {
    let tf = tf().resolved([-0.5, 3.0]);
    let (w, h) = (scene.view.width, scene.view.height);
    let pixels = (0..w * h)
        .map(|i| {
            let ray = scene
                .view
                .camera
                .ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, w, h);
            let Some((t0, t1)) = ray_box(ray.origin, ray.dir, DVec3::ZERO, DVec3::ONE) else {
                return [0.0; 4];
            };
            let (s0, s1) = (
                field(ray.origin + ray.dir * t0),
                field(ray.origin + ray.dir * t1),
            );
            if mip {
                let c = tf.color_at(s0.max(s1));
                return [c[0] as f32, c[1] as f32, c[2] as f32, 1.0];
            }
            segment_simpson(&tf, s0, s1, t1 - t0, 4000).map(|v| v as f32)
        })
        .collect();
    Image::from_pixels(w, h, pixels).unwrap()
}

fn render(volume: &Volume, scene: &Scene) -> Image {
    render_once(volume, scene, &Control::default())
        .unwrap()
        .image
}

fn adaptive(tol: f64) -> AdaptiveParams {
    AdaptiveParams {
        tol,
        h0: 0.5,
        hmin: 1e-3,
        hmax: 2.0,
        control: StepControl::Coupled,
        early_termination: None,
    }
}

fn grid_method(integrator: Integrator) -> Method {
    Method::GridRaycast(GridRaycast {
        integrator,
        ..GridRaycast::default()
    })
}

fn pt(sort: SortMode, color: SegmentRule) -> Method {
    Method::ProjectedTetrahedra(PtSettings {
        sort,
        color,
        count_violations: false,
    })
}

/// A tolerance: largest and mean absolute error per channel (linear, premultiplied), and
/// the share of pixels allowed off by more than 1e-3.
fn tol(max_error: f64, mean_error: f64, fraction_over: f64) -> Tolerance {
    Tolerance {
        max_error,
        mean_error,
        threshold: 1e-3,
        fraction_over,
    }
}

/// Every method with its tolerance, about three times the error measured when the matrix was
/// written (steps are in the volume's unit length: 1/16 for the grid, the cube's diagonal /
/// 256 for the mesh). Exact methods are held to 1e-6. Adaptive Simpson at `tol = 1e-3` is
/// held to its tolerance. Projected Tetrahedra snaps vertices to 1/256 pixel, so a pixel
/// whose centre grazes the silhouette may gain or lose a sliver of the cube: up to 0.5 % of
/// the pixels may be off by more than 1e-3 (one was, by 1.2e-2).
fn methods() -> Vec<(&'static str, bool, Method, Tolerance)> {
    let (grid, mesh) = (true, false);
    let pt_edges = tol(3e-2, 1e-4, 0.005);
    vec![
        (
            "riemann",
            grid,
            grid_method(Integrator::Riemann { step: 0.25 }),
            tol(2e-2, 1e-3, 0.3),
        ),
        (
            "trapezoid",
            grid,
            grid_method(Integrator::Trapezoid { step: 0.25 }),
            tol(1e-3, 3e-5, 0.0),
        ),
        (
            "simpson",
            grid,
            grid_method(Integrator::Simpson { step: 0.25 }),
            tol(5e-5, 1e-6, 0.0),
        ),
        (
            "preintegrated",
            grid,
            grid_method(Integrator::Preintegrated { step: 0.5 }),
            tol(4e-3, 5e-5, 0.005),
        ),
        (
            "adaptive",
            grid,
            grid_method(Integrator::AdaptiveSimpson(adaptive(1e-3))),
            tol(1e-3, 1e-5, 0.0),
        ),
        (
            "grid-reference",
            grid,
            grid_method(Integrator::Reference),
            Tolerance::max(1e-6),
        ),
        (
            "pt-exact",
            mesh,
            pt(SortMode::Exact, SegmentRule::Exact),
            pt_edges,
        ),
        (
            "pt-psi",
            mesh,
            pt(SortMode::Centroid, SegmentRule::Psi),
            pt_edges,
        ),
        (
            "pt-average",
            mesh,
            pt(SortMode::Centroid, SegmentRule::Average),
            tol(3e-2, 2e-4, 0.01),
        ),
        (
            "tet-exact",
            mesh,
            Method::TetRaycast(SegmentRule::Exact),
            Tolerance::max(1e-6),
        ),
        (
            "tet-psi",
            mesh,
            Method::TetRaycast(SegmentRule::Psi),
            tol(5e-5, 1e-6, 0.0),
        ),
        (
            "tet-average",
            mesh,
            Method::TetRaycast(SegmentRule::Average),
            tol(2e-3, 2e-5, 0.002),
        ),
        (
            "tet-adaptive",
            mesh,
            Method::TetRaycast(SegmentRule::AdaptiveSimpson(adaptive(1e-3))),
            tol(1e-3, 1e-5, 0.0),
        ),
        (
            "mesh-reference",
            mesh,
            Method::MeshReference,
            Tolerance::max(1e-6),
        ),
        (
            "resample",
            mesh,
            Method::Resample {
                samples: N,
                raycast: GridRaycast {
                    integrator: Integrator::Simpson { step: 0.25 },
                    ..GridRaycast::default()
                },
            },
            tol(5e-5, 1e-6, 0.0),
        ),
    ]
}

#[test]
fn every_method_matches_the_analytic_reference() {
    let grid = Volume::from(grid());
    let mesh = grid.to_tets().unwrap();
    let expected = reference(&scene(&grid), false);
    for (name, on_grid, method, tol) in methods() {
        let volume = if on_grid { &grid } else { &mesh };
        let mut s = scene(volume);
        s.method = method;
        assert_images_close(
            &format!("matrix-{name}"),
            &render(volume, &s),
            &expected,
            tol,
        );
    }
}

#[test]
fn maximum_intensity_projection_shows_the_largest_end_value() {
    let grid = Volume::from(grid());
    let mesh = grid.to_tets().unwrap();
    let expected = reference(&scene(&grid), true);
    for (name, volume, method, max_error) in [
        (
            "grid",
            &grid,
            grid_method(Integrator::Riemann { step: 0.1 }),
            2e-2,
        ),
        ("tet", &mesh, Method::TetRaycast(SegmentRule::Exact), 1e-6),
    ] {
        let mut s = scene(volume);
        s.method = method;
        s.appearance.mip = true;
        let got = render(volume, &s);
        assert_images_close(
            &format!("mip-{name}"),
            &got,
            &expected,
            Tolerance::max(max_error),
        );
    }
}
