//! The sculpt mask in the grid ray caster, picking, digging, undo and measurement, against
//! brute force: chords through a constant medium marched against an independent trilinear
//! blend of the removed voxels, a fine march for the first hit, a box of known size.
use glam::DVec3;
use volux_core::grid::{Buffer, Samples};
use volux_core::sculpt::{Ball, RegionRule, SculptMask, VoxelFrame};
use volux_core::{Camera, CameraSpec, Grid, TransferFunction};

use super::*;
use crate::integrate::{AdaptiveParams, Integrator, StepControl};
use crate::raycast::{render_field, render_grid, Placement, RenderOptions};
use crate::sampling::Trilinear;
use crate::scene::{GridRaycast, Method, Scene};

const N: usize = 20;

fn constant_grid() -> Grid {
    Grid::new(
        [N; 3],
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(vec![1.0; N * N * N])),
    )
    .unwrap()
}

fn tf() -> TransferFunction {
    TransferFunction::from_json(r#"{"color": [[0,1,0.5,0.25]], "extinction": [[0,0.3]]}"#).unwrap()
}

fn camera(g: &Grid, spec: &str) -> Camera {
    CameraSpec::from_json(spec)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap()
}

/// The removed ball, as voxel centres (independent of the mask's bricks).
fn in_ball(v: DVec3, c: DVec3, r: f64) -> bool {
    (v - c).length() <= r
}

/// Trilinear blend of the kept voxels at `p` (brute force over the cell's corners).
fn kept_blend(p: DVec3, c: DVec3, r: f64) -> f64 {
    let cell = p.floor().clamp(DVec3::ZERO, DVec3::splat((N - 2) as f64));
    let f = p - cell;
    let mut sum = 0.0;
    for k in 0..8 {
        let o = DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64);
        let w = (o.x * f.x + (1.0 - o.x) * (1.0 - f.x))
            * (o.y * f.y + (1.0 - o.y) * (1.0 - f.y))
            * (o.z * f.z + (1.0 - o.z) * (1.0 - f.z));
        sum += w * if in_ball(cell + o, c, r) { 0.0 } else { 1.0 };
    }
    sum
}

/// The visible chord length along a ray: inside the box and where the blend is >= 0.5.
fn chord(origin: DVec3, dir: DVec3, c: DVec3, r: f64) -> f64 {
    let dt = 2e-3;
    let top = (N - 1) as f64;
    (0..(200.0 / dt) as usize)
        .map(|i| origin + dir * ((i as f64 + 0.5) * dt))
        .filter(|p| p.cmpge(DVec3::ZERO).all() && p.cmple(DVec3::splat(top)).all())
        .filter(|&p| kept_blend(p, c, r) >= 0.5)
        .count() as f64
        * dt
}

fn dug_mask(g: &Grid, c: DVec3, r: f64) -> std::sync::Arc<SculptMask> {
    let mut m = SculptMask::new(g.dims()).unwrap();
    m.remove(&Ball::new(c, r, VoxelFrame::of(g)).unwrap());
    std::sync::Arc::new(m)
}

#[test]
fn every_integrator_draws_a_constant_medium_minus_the_masked_ball() {
    let g = constant_grid();
    let (c, r) = (DVec3::new(9.3, 8.7, 10.2), 6.3);
    let mask = dug_mask(&g, c, r);
    let cam = camera(&g, r#"{"azimuth": 25, "elevation": 15}"#);
    let adaptive = AdaptiveParams {
        tol: 1e-3,
        h0: 0.2,
        hmin: 0.02,
        hmax: 1.0,
        control: StepControl::Coupled,
        early_termination: None,
    };
    let cases = [
        (Integrator::Riemann { step: 0.05 }, 0.05),
        (Integrator::Trapezoid { step: 0.05 }, 0.05),
        (Integrator::Preintegrated { step: 0.05 }, 0.05),
        (Integrator::AdaptiveSimpson(adaptive), 0.2),
        (Integrator::Reference, 0.05),
    ];
    let (w, h) = (20, 20);
    let rays = cam.rays(w, h);
    for (integrator, step) in cases {
        let mut o = RenderOptions::new(cam, tf());
        (o.width, o.height, o.early_termination) = (w, h, None);
        o.integrator = integrator;
        o.mask = Some(mask.clone());
        let img = render_grid(&g, &o).unwrap().image;
        let (mut worst, mut sum, mut dug) = (0.0f64, 0.0, 0);
        for y in 0..h {
            for x in 0..w {
                let ray = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                let len = chord(ray.origin, ray.dir, c, r);
                let full = chord(ray.origin, ray.dir, DVec3::splat(-100.0), 1.0);
                dug += usize::from(full - len > 2.0);
                let err = (img.get(x, y)[3] as f64 - (1.0 - (-0.3 * len).exp())).abs();
                worst = worst.max(err);
                sum += err;
            }
        }
        let mean = sum / (w * h) as f64;
        // Each of a ray's two crossings of the mask's surface is found to within a step.
        let bound = 0.3 * 2.0 * step + 2e-3;
        assert!(dug > 40, "the ball shortens only {dug} rays");
        assert!(
            worst < bound && mean < bound / 4.0,
            "{integrator:?}: worst {worst}, mean {mean} (bound {bound})"
        );
    }
}

#[test]
fn skipping_the_macrocells_the_mask_removes_changes_no_pixel() {
    // The macrocells split each ray into runs the mask hides in part and runs it does not
    // (sampled without it), touching end to end: every rule must take each sample once.
    let g = constant_grid();
    let mask = dug_mask(&g, DVec3::splat(9.5), 12.0);
    assert!((0..27).any(|m| mask.block_removed(m)));
    assert!((0..27).any(|m| mask.block_partial(m)));
    let mut o = RenderOptions::new(camera(&g, r#"{"azimuth": 40}"#), tf());
    (o.width, o.height) = (24, 24);
    o.mask = Some(mask);
    let values = vec![1.0f32; N * N * N];
    let field = Trilinear::new(&values, g.dims());
    for integrator in [
        Integrator::Riemann { step: 0.25 },
        Integrator::Preintegrated { step: 0.25 },
        Integrator::Trapezoid { step: 0.25 },
    ] {
        o.integrator = integrator;
        let skipped = render_grid(&g, &o).unwrap();
        let walked = render_field(&field, Placement::of(&g), g.range(), &o).unwrap();
        let d = (0..24)
            .flat_map(|y| (0..24).map(move |x| (x, y)))
            .flat_map(|(x, y)| {
                let (a, b) = (skipped.image.get(x, y), walked.image.get(x, y));
                (0..4).map(move |c| (a[c] - b[c]).abs())
            })
            .fold(0.0f32, f32::max);
        assert!(d < 1e-6, "{integrator:?}: max difference {d}");
        assert!(skipped.stats.samples < walked.stats.samples);
    }
    let other = SculptMask::new([3, 3, 3]).unwrap();
    o.mask = Some(std::sync::Arc::new(other));
    assert!(
        render_grid(&g, &o).is_err(),
        "a mask of another size is refused"
    );
}

/// A zero volume with a box of ones over voxels `lo..=hi`, spacing `s`.
fn box_grid(lo: usize, hi: usize, s: [f64; 3]) -> Grid {
    let mut v = vec![0.0f32; N * N * N];
    for k in lo..=hi {
        for j in lo..=hi {
            for i in lo..=hi {
                v[i + N * (j + N * k)] = 1.0;
            }
        }
    }
    Grid::new([N; 3], s, [3.0, -2.0, 1.0], Samples::F32(Buffer::owned(v))).unwrap()
}

fn opaque_box_scene(g: &Grid, view: &str) -> Scene {
    let tf = TransferFunction::from_json(
        r#"{"color": [[0,1,1,1]], "extinction": [[0,0],[0.49,0],[0.51,500],[1,500]]}"#,
    )
    .unwrap();
    let mut s = Scene::new(camera(g, view), 31, 31, tf);
    s.method = Method::GridRaycast(GridRaycast {
        integrator: Integrator::Riemann { step: 0.1 },
        ..GridRaycast::default()
    });
    s
}

#[test]
fn the_first_hit_matches_a_fine_march_and_a_box_measures_its_size() {
    let s = [0.6, 0.9, 1.3];
    let g = box_grid(5, 14, s);
    // The field crosses 0.5 half a voxel outside the ones: the box is 10 voxels wide.
    let size_x = 10.0 * s[0];
    let front = opaque_box_scene(&g, r#"{"azimuth": 90, "projection": "orthographic"}"#);
    let back = opaque_box_scene(&g, r#"{"azimuth": -90, "projection": "orthographic"}"#);
    let a = pick(&g, &front, (15.5, 15.5), 0.5).unwrap().expect("a hit");
    let b = pick(&g, &back, (15.5, 15.5), 0.5).unwrap().expect("a hit");
    let len = polyline_length(&[a.world, b.world]);
    assert!(
        (len - size_x).abs() < 0.5 * s[0],
        "measured {len} mm for a {size_x} mm box ({a:?}, {b:?})"
    );
    // The hit against a march a hundred times finer.
    let mut fine = front.clone();
    fine.method = Method::GridRaycast(GridRaycast {
        integrator: Integrator::Riemann { step: 0.001 },
        ..GridRaycast::default()
    });
    let f = pick(&g, &fine, (15.5, 15.5), 0.5).unwrap().unwrap();
    assert!((f.world - a.world).length() < 0.1 * s[0], "{f:?} vs {a:?}");
    // A pixel that misses the box hits nothing.
    assert!(pick(&g, &front, (0.5, 0.5), 0.5).unwrap().is_none());
    assert!(pick(&g, &front, (0.5, 0.5), 1.5).is_err());
}

#[test]
fn a_dig_removes_the_ball_at_the_first_hit_and_undo_and_replay_are_exact() {
    let g = box_grid(3, 16, [1.0, 1.0, 1.0]);
    let scene = opaque_box_scene(&g, r#"{"azimuth": 20, "elevation": 10}"#);
    let mut sculpt = Sculpt::new(&g).unwrap();
    sculpt
        .apply(SculptStep::Erase {
            camera: scene.view.camera,
            size: [31, 31],
            points: vec![[3.0, 3.0], [8.0, 6.0]],
            radius_px: 2.0,
        })
        .unwrap();
    let before = (**sculpt.mask()).clone();
    let hit = sculpt
        .dig(&g, &scene, [15.5, 15.5], 3.0)
        .unwrap()
        .expect("a hit");
    let expect = pick(
        &g,
        &{
            let mut s = scene.clone();
            sculpt.undo();
            sculpt.apply_to(&mut s);
            s
        },
        (15.5, 15.5),
        DEFAULT_PICK_OPACITY,
    )
    .unwrap()
    .unwrap();
    assert_eq!(hit, expect);
    assert_eq!(
        **sculpt.mask(),
        before,
        "undo restores the mask bit for bit"
    );
    assert!(sculpt.redo().unwrap());
    let after = (**sculpt.mask()).clone();
    assert_ne!(after, before);
    let radius = 3.0 * pixel_size_at(&scene.view.camera, 31, hit.depth);
    for (i, j, k) in [(0usize, 0usize, 0usize), (10, 10, 3), (9, 9, 9)] {
        let w = DVec3::new(i as f64, j as f64, k as f64);
        let inside = (w - hit.world).length() <= radius;
        assert_eq!(after.voxel(i, j, k), before.voxel(i, j, k) && !inside);
    }
    // Digging again digs deeper.
    let second = sculpt.dig(&g, &scene, [15.5, 15.5], 3.0).unwrap().unwrap();
    assert!(second.distance > hit.distance + 0.5 * radius);
    let replayed = Sculpt::replay(&g, &sculpt.steps()).unwrap();
    assert_eq!(replayed.mask(), sculpt.mask());
    // Plane steps undo too; a bad step changes nothing.
    let plane = volux_core::voi::ClipPlane::new(1.0, 0.0, 0.0, -8.0).unwrap();
    sculpt.apply(SculptStep::AddPlane { plane }).unwrap();
    assert!(sculpt.apply(SculptStep::RemovePlane { index: 3 }).is_err());
    assert_eq!(sculpt.planes(), &[plane]);
    assert!(sculpt.undo());
    assert!(sculpt.planes().is_empty());
}

#[test]
fn labels_go_to_visible_voxels_of_the_volume_of_interest_only() {
    let g = box_grid(4, 15, [1.0, 0.8, 1.5]);
    let scene = opaque_box_scene(&g, "{}");
    let mut sculpt = Sculpt::new(&g).unwrap();
    let plane = volux_core::voi::ClipPlane::new(0.0, 0.0, -1.0, 1.0 + 12.0 * 1.5).unwrap();
    sculpt.apply(SculptStep::AddPlane { plane }).unwrap();
    let at = |i: f64, j: f64, k: f64| g.index_to_world(DVec3::new(i, j, k));
    for (p, label) in [(at(5.0, 5.0, 5.0), 2u8), (at(14.0, 14.0, 5.0), 9)] {
        let colour = [1.0, 0.0, 0.0];
        sculpt
            .apply(SculptStep::Label {
                point: p,
                label,
                colour,
                rule: RegionRule::Nearest,
            })
            .unwrap();
    }
    let labels = sculpt.labels(&g, &scene).unwrap();
    let get = |i: usize, j: usize, k: usize| labels[i + N * (j + N * k)];
    assert_eq!(get(5, 5, 5), 2);
    assert_eq!(get(14, 14, 5), 9);
    assert_eq!(get(1, 1, 1), 0, "outside the box: transparent");
    assert_eq!(get(5, 5, 14), 0, "beyond the plane");
    // Nearest in world distance (x spacing 1.0, y 0.8): voxel (11, 8, 5) is as far from both
    // seeds in index space (45 squared voxels; the first seed would win the tie) but nearer to
    // the second in millimetres (32.0 against 41.8 mm squared).
    assert_eq!(get(11, 8, 5), 9);
    assert_eq!(get(7, 9, 5), 2);
}

/// A label step saved before the rule existed (no `rule` field) replays as a nearest seed;
/// a nearest step is saved without the field, a connected one with it (the session's round
/// trip is tested in volux-app's session module).
#[test]
fn a_label_step_without_a_rule_is_nearest() {
    let old = r#"{"tool": "label", "point": [1, 2, 3], "label": 4, "colour": [1, 0, 0]}"#;
    let step: SculptStep = serde_json::from_str(old).unwrap();
    let SculptStep::Label {
        point,
        label: 4,
        colour,
        rule: RegionRule::Nearest,
    } = step.clone()
    else {
        panic!("{step:?}")
    };
    let json = serde_json::to_string(&step).unwrap();
    assert!(!json.contains("\"rule\""), "{json}");
    let connected = SculptStep::Label {
        point,
        label: 4,
        colour,
        rule: RegionRule::Connected,
    };
    let json = serde_json::to_string(&connected).unwrap();
    assert!(json.contains(r#""rule":"connected""#), "{json}");
    assert_eq!(
        serde_json::from_str::<SculptStep>(&json).unwrap(),
        connected
    );
}

/// A connected seed on one of two boxes labels that box only; nearest labels both.
#[test]
fn connected_labels_leave_the_box_no_seed_touches() {
    let [nx, ny, nz] = [24, 10, 10];
    let values: Vec<f32> = (0..nx * ny * nz)
        .map(|n| (n % nx, n / nx % ny, n / (nx * ny)))
        .map(|(i, j, k)| {
            let inner = (2..8).contains(&j) && (2..8).contains(&k);
            f32::from(u8::from(
                inner && ((2..9).contains(&i) || (14..21).contains(&i)),
            ))
        })
        .collect();
    let g = Grid::new(
        [nx, ny, nz],
        [1.0, 0.8, 1.5],
        [0.0; 3],
        Samples::F32(Buffer::owned(values)),
    )
    .unwrap();
    let scene = opaque_box_scene(&g, "{}");
    let count = |rule| {
        let mut sculpt = Sculpt::new(&g).unwrap();
        let point = g.index_to_world(DVec3::new(5.0, 5.0, 5.0));
        let colour = [1.0, 0.0, 0.0];
        sculpt
            .apply(SculptStep::Label {
                point,
                label: 3,
                colour,
                rule,
            })
            .unwrap();
        let labels = sculpt.labels(&g, &scene).unwrap();
        labels.iter().filter(|&&l| l == 3).count()
    };
    let one_box = 7 * 6 * 6;
    assert_eq!(count(RegionRule::Connected), one_box);
    assert_eq!(count(RegionRule::Nearest), 2 * one_box);
}

#[test]
fn labels_colour_the_rendering_with_every_integrator() {
    let g = constant_grid();
    let scene = {
        let mut s = Scene::new(camera(&g, "{}"), 16, 16, tf());
        s.early_termination = None;
        s
    };
    let mut sculpt = Sculpt::new(&g).unwrap();
    let left = g.index_to_world(DVec3::new(2.0, 10.0, 10.0));
    let right = g.index_to_world(DVec3::new(17.0, 10.0, 10.0));
    for (point, label, colour) in [(left, 1u8, [1.0, 0.0, 0.0]), (right, 2, [0.0, 0.0, 1.0])] {
        sculpt
            .apply(SculptStep::Label {
                point,
                label,
                colour,
                rule: RegionRule::Nearest,
            })
            .unwrap();
    }
    let labels = std::sync::Arc::new(sculpt.label_volume(&g, &scene).unwrap());
    let adaptive = AdaptiveParams {
        tol: 1e-3,
        h0: 0.5,
        hmin: 0.05,
        hmax: 2.0,
        control: StepControl::Coupled,
        early_termination: None,
    };
    for integrator in [
        Integrator::Riemann { step: 0.5 },
        Integrator::Trapezoid { step: 0.5 },
        Integrator::Preintegrated { step: 0.5 },
        Integrator::AdaptiveSimpson(adaptive),
    ] {
        let mut o = RenderOptions::new(scene.view.camera, tf());
        (o.width, o.height, o.early_termination, o.integrator) = (16, 16, None, integrator);
        let plain = render_grid(&g, &o).unwrap().image;
        o.labels = Some(labels.clone());
        let img = render_grid(&g, &o).unwrap().image;
        // The default camera looks along +y: +x is to the right of the picture.
        let (l, r) = (img.get(3, 8), img.get(12, 8));
        assert!(
            l[0] > 4.0 * l[2] && r[2] > 4.0 * r[0],
            "{integrator:?}: left {l:?}, right {r:?}"
        );
        assert!(
            (l[3] - plain.get(3, 8)[3]).abs() < 1e-6,
            "labels keep the opacity"
        );
    }
}

#[test]
fn the_mesh_renderers_refuse_a_mask_with_the_reason() {
    use crate::engine::create_renderer;
    use crate::integrate::SegmentRule;
    use crate::scene::{PtSettings, Volume};
    let g = constant_grid();
    let mesh = Volume::from(g.clone()).to_tets().unwrap();
    let mut scene = Scene::new(camera(&g, "{}"), 8, 8, tf());
    scene.mask = Some(dug_mask(&g, DVec3::splat(9.5), 4.0));
    for method in [
        Method::ProjectedTetrahedra(PtSettings::default()),
        Method::TetRaycast(SegmentRule::Psi),
        Method::MeshReference,
    ] {
        scene.method = method;
        let mut r = create_renderer(&mesh, &method).unwrap();
        let e = r
            .render(&scene, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("masks and labels apply to grids"), "{e}");
    }
}
