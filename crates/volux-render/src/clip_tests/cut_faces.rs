//! The faces that clip planes and the sculpt mask expose are lit with the cut's own normal
//! ([`crate::shading::CutFaces`]): on a constant field, whose gradient is zero inside, a cut
//! face would otherwise keep its unlit colour whatever the light. Each picture is checked
//! against Blinn-Phong with the cut's normal, in every path of the grid ray caster (the lane
//! stream with the gradient volume, adaptive Simpson's lanes, the ray-by-ray reference).
use std::sync::Arc;

use glam::{DVec3, Vec3};
use volux_core::camera::Projection;
use volux_core::grid::{Buffer, Samples};
use volux_core::sculpt::{Ball, SculptMask, VoxelFrame};
use volux_core::voi::ClipPlane;
use volux_core::{Camera, Grid, TransferFunction};

use crate::integrate::{AdaptiveParams, Integrator, StepControl};
use crate::raycast::{render_grid, GridRenderer, RenderOptions};
use crate::shading::{BlinnPhong, Light};

const COLOUR: [f32; 3] = [0.8, 0.6, 0.4];

/// A constant field over `[0, 15]^3`, spacing 1.
fn cube() -> Grid {
    Grid::new(
        [16, 16, 16],
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(vec![1.0; 16 * 16 * 16])),
    )
    .unwrap()
}

/// An orthographic camera looking down -z at the cube's middle.
fn from_above() -> Camera {
    Camera {
        eye: DVec3::new(7.5, 7.5, 60.0),
        target: DVec3::new(7.5, 7.5, 7.5),
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 20.0 },
    }
}

/// Opaque within a voxel: what a pixel shows is the first sample's lit colour.
fn opaque() -> TransferFunction {
    TransferFunction::from_json(
        r#"{"color": [[0, 0.8, 0.6, 0.4], [2, 0.8, 0.6, 0.4]], "extinction": [[0, 60], [2, 60]]}"#,
    )
    .unwrap()
}

fn options(integrator: Integrator, model: BlinnPhong) -> RenderOptions {
    let mut o = RenderOptions::new(from_above(), opaque());
    (o.width, o.height) = (40, 40);
    o.integrator = integrator;
    o.shading = Some(model);
    o
}

fn integrators() -> [Integrator; 4] {
    [
        Integrator::Riemann { step: 0.5 },
        Integrator::Preintegrated { step: 0.5 },
        Integrator::AdaptiveSimpson(AdaptiveParams {
            tol: 1e-4,
            h0: 0.5,
            hmin: 1e-3,
            hmax: 1.0,
            control: StepControl::Coupled,
            early_termination: Some(0.995),
        }),
        Integrator::Reference,
    ]
}

/// The pixel (`x`, `y`)'s colour, in every path: the cached renderer (lane paths with the
/// gradient volume) and the one-off render (ray by ray, gradients on the fly), which agree.
fn pixels(g: &Grid, o: &RenderOptions, at: &[(usize, usize)]) -> Vec<[f32; 3]> {
    let cached = GridRenderer::new(g).render_with(o).unwrap().image;
    let one_off = render_grid(g, o).unwrap().image;
    at.iter()
        .map(|&(x, y)| {
            let a = cached.get(x, y);
            let b = one_off.get(x, y);
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() < 0.02,
                    "{:?} at ({x}, {y}): cached {a:?}, one-off {b:?}",
                    o.integrator
                );
            }
            [a[0], a[1], a[2]]
        })
        .collect()
}

fn assert_near(got: [f32; 3], want: [f32; 3], tol: f32, what: &str) {
    for c in 0..3 {
        assert!(
            (got[c] - want[c]).abs() < tol,
            "{what}: got {got:?}, want {want:?}"
        );
    }
}

#[test]
fn a_plane_cut_through_a_constant_field_is_lit_with_the_planes_normal() {
    let g = cube();
    // The light 60 degrees off the cut face's normal (+z, towards the viewer): diffuse 0.5,
    // the half vector 30 degrees off (0.866^32 of the highlight).
    let light = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
    let model = BlinnPhong {
        light: Light::Direction(light),
        ..BlinnPhong::default()
    };
    let k = model.ambient + model.diffuse * 0.5;
    let s = model.specular * 30f32.to_radians().cos().powf(model.shininess);
    let want = COLOUR.map(|c| c * k + s);
    for integrator in integrators() {
        let mut o = options(integrator, model);
        // Keep z <= 10.3: the cut face at z = 10.3 faces the camera.
        o.clip_planes = vec![ClipPlane::new(0.0, 0.0, -1.0, 10.3).unwrap()];
        for got in pixels(&g, &o, &[(20, 20), (14, 25), (27, 12)]) {
            assert_near(got, want, 0.02, &format!("{integrator:?} cut face"));
        }
        // Uncut, the top face has no cut: the constant field's zero gradient leaves it unlit.
        o.clip_planes.clear();
        let uncut = pixels(&g, &o, &[(20, 20)])[0];
        assert_near(uncut, COLOUR, 0.02, &format!("{integrator:?} uncut"));
    }
}

#[test]
fn a_hole_carved_in_a_constant_field_is_lit_with_the_masks_normal() {
    let g = cube();
    // A ball of radius 6 around the middle of the top face: a bowl seen from above.
    let mut mask = SculptMask::new(g.dims()).unwrap();
    let frame = VoxelFrame::of(&g);
    mask.remove(&Ball::new(DVec3::new(7.5, 7.5, 15.0), 6.0, frame).unwrap());
    let model = BlinnPhong::default();
    // 40 pixels over 20 world units, pixel x at world 7.5 + (x + 0.5 - 20) / 2: pixel 20 is
    // the bowl's bottom, pixel 28 its wall 4.25 from the middle, leaning
    // sqrt(1 - (4.25/6)^2) = 0.71 towards the eye; pixel 5 the top face outside the bowl.
    let lean = (1.0f32 - (4.25f32 / 6.0).powi(2)).sqrt();
    let bottom = COLOUR.map(|c| c + model.specular);
    let wall = COLOUR.map(|c| c * (model.ambient + model.diffuse * lean));
    for integrator in integrators() {
        let mut o = options(integrator, model);
        o.mask = Some(Arc::new(mask.clone()));
        let got = pixels(&g, &o, &[(20, 20), (28, 20), (20, 28), (5, 5)]);
        let what = format!("{integrator:?}");
        // The trilinear mask's surface only approximates the ball: loose bounds.
        assert_near(got[0], bottom, 0.08, &format!("{what} bowl's bottom"));
        assert_near(got[1], wall, 0.12, &format!("{what} bowl's wall"));
        assert_near(got[2], wall, 0.12, &format!("{what} bowl's wall"));
        assert!(got[0][0] - got[1][0] > 0.3, "{what}: the wall is darker");
        // The uncut top face, out of the bowl: unlit.
        assert_near(got[3], COLOUR, 0.02, &format!("{what} top face"));
    }
}
