//! Patient orientation in rendering: a volume stored in two orientations (the same world
//! object, the samples permuted and flipped with the matching direction matrix and origin)
//! renders the same picture through `render_once`, for grid ray casting (every integrator
//! path, shading with a world-fixed light, isosurfaces, MIP) and for PT of the grid's
//! tetrahedra; an oblique grid turned with the camera renders the picture of the upright one.
use glam::{DMat3, DVec3, Vec3};
use volux_core::{Buffer, Camera, CameraSpec, Grid, Samples};
use volux_render::engine::render_once;
use volux_render::integrate::{AdaptiveParams, Integrator};
use volux_render::isosurface::{Isosurfaces, Isovalue};
use volux_render::scene::{GridRaycast, Method, PtSettings, Scene, Volume};
use volux_render::shading::blinn_phong::Light;
use volux_render::tiles::Control;

const DIMS: [usize; 3] = [18, 14, 10];
const SPACING: [f64; 3] = [1.0, 1.25, 1.5];
const ORIGIN: [f64; 3] = [-5.0, 3.0, 7.0];

/// An asymmetric field: an off-centre blob, a smaller second blob, and a ramp along y.
fn blob(p: DVec3) -> f32 {
    let c = DVec3::from(ORIGIN) + DVec3::new(5.0, 10.0, 5.0);
    let d = DVec3::from(ORIGIN) + DVec3::new(13.0, 5.0, 10.0);
    let g = |q: DVec3, r: f64| (-(p - q).length_squared() / (r * r)).exp();
    (100.0 * g(c, 4.0) + 60.0 * g(d, 2.5) + 2.0 * (p.y - ORIGIN[1])) as f32
}

/// The axis-aligned ("axial") grid of `field`, sampled at its world sample positions.
fn axial(field: impl Fn(DVec3) -> f32) -> Grid {
    let mut v = Vec::new();
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                let idx = DVec3::new(i as f64, j as f64, k as f64);
                v.push(field(DVec3::from(ORIGIN) + DVec3::from(SPACING) * idx));
            }
        }
    }
    Grid::new(DIMS, SPACING, ORIGIN, Samples::F32(Buffer::owned(v))).unwrap()
}

/// The same samples stored with index axis `a` of the new grid running along axis `perm[a]`
/// of `g`, reversed where `flip[a]`; with the direction matrix and origin that keep every
/// sample at its world position.
fn reslice(g: &Grid, perm: [usize; 3], flip: [bool; 3]) -> Grid {
    let (dims, spacing) = (g.dims(), g.spacing());
    let nd = perm.map(|p| dims[p]);
    let old_index = |n: [usize; 3]| {
        let mut o = [0usize; 3];
        for a in 0..3 {
            o[perm[a]] = if flip[a] { nd[a] - 1 - n[a] } else { n[a] };
        }
        o
    };
    let mut v = Vec::with_capacity(g.len());
    for k in 0..nd[2] {
        for j in 0..nd[1] {
            for i in 0..nd[0] {
                let o = old_index([i, j, k]);
                v.push(g.value(o[0], o[1], o[2]));
            }
        }
    }
    let col = |a: usize| {
        let s = if flip[a] { -1.0 } else { 1.0 };
        g.direction().col(perm[a]) * s
    };
    let o = old_index([0, 0, 0]);
    let origin = g.position(o[0], o[1], o[2]).to_array();
    let ns = perm.map(|p| spacing[p]);
    Grid::new(nd, ns, origin, Samples::F32(Buffer::owned(v)))
        .unwrap()
        .with_direction(DMat3::from_cols(col(0), col(1), col(2)))
        .unwrap()
}

fn camera(volume: &Volume) -> Camera {
    let spec = CameraSpec {
        azimuth: Some(35.0),
        elevation: Some(25.0),
        ..Default::default()
    };
    spec.resolve(&volume.bounds()).unwrap()
}

/// A scene of `volume` seen by `camera` with the TF of `tf_of` and `method`, 64 x 56.
fn scene(camera: Camera, tf_of: &Volume, method: Method) -> Scene {
    let mut s = Scene::new(camera, 64, 56, tf_of.preset_tf("auto").unwrap());
    s.method = method;
    s
}

/// The largest channel difference between the frames of `s` for `a` and for `b`, and the
/// fraction of pixels with any alpha (so an empty picture cannot pass).
fn max_error(a: &Volume, b: &Volume, s: &Scene) -> (f64, f64) {
    let ia = render_once(a, s, &Control::default()).unwrap().image;
    let ib = render_once(b, s, &Control::default()).unwrap().image;
    let err = ia
        .pixels()
        .iter()
        .zip(ib.pixels())
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs() as f64))
        .fold(0.0, f64::max);
    (err, ia.coverage(0.02))
}

fn raycast(integrator: Integrator) -> Method {
    Method::GridRaycast(GridRaycast {
        integrator,
        ..GridRaycast::default()
    })
}

/// The appearances and methods compared: each grid ray-casting path.
fn grid_cases(tf_of: &Volume, cam: Camera) -> Vec<(&'static str, Scene)> {
    let adaptive = AdaptiveParams {
        tol: 1e-4,
        ..Integrator::REFERENCE
    };
    let mut cases = vec![
        ("riemann", scene(cam, tf_of, Method::Auto)),
        (
            "adaptive",
            scene(cam, tf_of, raycast(Integrator::AdaptiveSimpson(adaptive))),
        ),
        (
            "preintegrated",
            scene(cam, tf_of, raycast(Integrator::Preintegrated { step: 0.5 })),
        ),
        (
            "f64 reference",
            scene(cam, tf_of, raycast(Integrator::Reference)),
        ),
        (
            "trapezoid",
            scene(cam, tf_of, raycast(Integrator::Trapezoid { step: 0.5 })),
        ),
    ];
    let mut shaded = scene(cam, tf_of, Method::Auto);
    shaded.appearance.shade_volume = true;
    shaded.appearance.lighting.light = Light::Direction(Vec3::new(0.3, -0.8, 0.5));
    cases.push(("shaded, world light", shaded.clone()));
    shaded.appearance.lighting.light = Light::Headlight;
    cases.push(("shaded, headlight", shaded));
    let mut iso = scene(cam, tf_of, Method::Auto);
    iso.appearance.isosurfaces = Isosurfaces::new(vec![Isovalue {
        value: 60.0,
        rgba: [1.0, 0.8, 0.6, 0.7],
    }])
    .unwrap();
    iso.appearance.lighting.light = Light::Direction(Vec3::new(-0.5, 0.2, 0.8));
    cases.push(("isosurface", iso));
    let mut mip = scene(cam, tf_of, Method::Auto);
    mip.appearance.mip = true;
    cases.push(("mip", mip));
    cases
}

/// Requires the two storages of the same object to render alike in every case.
fn assert_same_pictures(a: &Volume, b: &Volume, label: &str) {
    let cam = camera(a);
    for (name, s) in grid_cases(a, cam) {
        let (err, coverage) = max_error(a, b, &s);
        eprintln!("{label}, {name}: max error {err:.2e} (coverage {coverage:.2})");
        assert!(coverage > 0.05, "{label}, {name}: picture nearly empty");
        assert!(err <= 1.0 / 255.0, "{label}, {name}: max error {err}");
    }
}

#[test]
fn sagittal_reslice_renders_the_axial_picture() {
    let a = axial(blob);
    // Sagittal storage: i along y (P), j down z (I), k along x (L): "PIL", a reflection.
    let b = reslice(&a, [1, 2, 0], [false, true, false]);
    assert_eq!(b.orientation_code(), "PIL");
    assert!(b.direction().determinant() < 0.0);
    let (va, vb) = (Volume::from(a), Volume::from(b));
    let (ba, bb) = (va.bounds(), vb.bounds());
    assert!(
        (ba.min - bb.min).abs().max_element() < 1e-12,
        "{ba:?} {bb:?}"
    );
    assert!(
        (ba.max - bb.max).abs().max_element() < 1e-12,
        "{ba:?} {bb:?}"
    );
    assert_same_pictures(&va, &vb, "sagittal PIL");
}

#[test]
fn rotated_storage_renders_the_axial_picture() {
    let a = axial(blob);
    // A proper rotation (90 degrees about z, then x reversed with z): "ARI".
    let b = reslice(&a, [1, 0, 2], [true, true, true]);
    assert_eq!(b.orientation_code(), "ARI");
    assert!(b.direction().determinant() > 0.0);
    assert_same_pictures(&Volume::from(a), &Volume::from(b), "rotated ARI");
}

#[test]
fn a_wrong_direction_changes_the_picture() {
    // The test can fail: the resliced data with the identity direction is another object.
    let a = axial(blob);
    let b = reslice(&a, [1, 2, 0], [false, true, false]);
    let wrong = Grid::new(
        b.dims(),
        b.spacing().to_array(),
        b.origin().to_array(),
        b.samples().clone(),
    )
    .unwrap();
    let (va, vw) = (Volume::from(a), Volume::from(wrong));
    let s = scene(camera(&va), &va, Method::Auto);
    let (err, _) = max_error(&va, &vw, &s);
    eprintln!("identity direction on resliced data: max error {err:.3}");
    assert!(err > 0.1, "{err}");
}

/// A field linear in world coordinates: every tetrahedralization of its samples (and
/// trilinear reconstruction) reproduces it exactly, so PT pictures of two storages compare.
fn ramp(p: DVec3) -> f32 {
    (3.0 * (p.x - ORIGIN[0]) + 2.0 * (p.y - ORIGIN[1]) + 1.5 * (p.z - ORIGIN[2])) as f32
}

#[test]
fn pt_of_the_grid_tets_is_the_same_in_both_storages() {
    let a = axial(ramp);
    let b = reslice(&a, [1, 2, 0], [false, true, false]);
    let (ga, gb) = (Volume::from(a), Volume::from(b));
    let (ta, tb) = (ga.to_tets().unwrap(), gb.to_tets().unwrap());
    let s = scene(
        camera(&ga),
        &ga,
        Method::ProjectedTetrahedra(PtSettings::default()),
    );
    let (err, coverage) = max_error(&ta, &tb, &s);
    eprintln!("PT of grid_to_tets, sagittal PIL: max error {err:.2e} (coverage {coverage:.2})");
    assert!(coverage > 0.05);
    assert!(err <= 1.0 / 255.0, "{err}");
}

/// `c` turned by `r` about `pivot` (eye, target and up).
fn turn_camera(c: Camera, r: DMat3, pivot: DVec3) -> Camera {
    Camera {
        eye: pivot + r * (c.eye - pivot),
        target: pivot + r * (c.target - pivot),
        up: r * c.up,
        ..c
    }
}

#[test]
fn oblique_grid_turned_with_the_camera_renders_the_upright_picture() {
    let deg = 30f64.to_radians();
    let r = DMat3::from_rotation_z(deg);
    let upright = axial(blob);
    let oblique = upright.clone().with_direction(r).unwrap();
    // World bounds: the rotated corners' box.
    let ext = DVec3::new(17.0, 13.0 * 1.25, 9.0 * 1.5);
    let corners = volux_core::Aabb {
        min: DVec3::ZERO,
        max: ext,
    }
    .corners()
    .map(|c| DVec3::from(ORIGIN) + r * c);
    let want = volux_core::Aabb::from_points(corners).unwrap();
    let got = oblique.bounds();
    assert!((got.min - want.min).abs().max_element() < 1e-12, "{got:?}");
    assert!((got.max - want.max).abs().max_element() < 1e-12, "{got:?}");
    assert!((got.min.x - (ORIGIN[0] - 13.0 * 1.25 * deg.sin())).abs() < 1e-12);
    assert!((got.max.y - (ORIGIN[1] + 17.0 * deg.sin() + 16.25 * deg.cos())).abs() < 1e-12);
    let (vu, vo) = (Volume::from(upright), Volume::from(oblique));
    let cam = camera(&vu);
    let turned = turn_camera(cam, r, DVec3::from(ORIGIN));
    for (name, su) in grid_cases(&vu, cam) {
        let mut so = su.clone();
        so.view.camera = turned;
        // The world-fixed light turns with the scene.
        if let Light::Direction(l) = su.appearance.lighting.light {
            so.appearance.lighting.light = Light::Direction((r * l.as_dvec3()).as_vec3());
        }
        let iu = render_once(&vu, &su, &Control::default()).unwrap().image;
        let io = render_once(&vo, &so, &Control::default()).unwrap().image;
        let err = iu
            .pixels()
            .iter()
            .zip(io.pixels())
            .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs() as f64))
            .fold(0.0, f64::max);
        eprintln!("oblique 30 deg, {name}: max error {err:.2e}");
        assert!(err <= 1.0 / 255.0, "oblique, {name}: max error {err}");
    }
}
