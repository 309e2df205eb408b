//! `volux sculpt`, `measure`, `regions` and `render --mask` end to end (issue 18, seed `004`
//! ch. 4-6): a box of ones in a zero grid of anisotropic spacing and a non-zero origin, an
//! opaque transfer function and look-at cameras in a temporary folder; what the commands
//! write is read back through our NRRD reader and checked against the engine
//! (`volux_render::sculpt::Sculpt`) driven directly.
use std::path::Path;
use std::process::Output;
use std::sync::Arc;

use glam::DVec3;
use volux_core::image::PngOptions;
use volux_core::sculpt::SculptMask;
use volux_core::{Buffer, Camera, CameraSpec, Grid, Projection, Samples};
use volux_render::engine::create_renderer;
use volux_render::scene::{GridRaycast, Method, Scene, Volume};
use volux_render::sculpt::{Sculpt, SculptStep};
use volux_render::tiles::Control;

mod common;
use common::{png_pixels, volux};

/// Grid samples per axis.
const DIMS: [usize; 3] = [24, 20, 16];
/// Spacing (mm), anisotropic.
const SPACING: [f64; 3] = [0.5, 0.8, 1.2];
/// Origin (mm).
const ORIGIN: [f64; 3] = [-5.0, 2.0, 10.0];
/// The box of ones, inclusive voxel index ranges (centred in the grid).
const BOX: [[usize; 2]; 3] = [[6, 17], [5, 14], [4, 11]];
/// A translucent TF (the thickness crossed shows).
const GLASS: &str = r#"{"color": [[0, 1, 0.8, 0.6], [1, 1, 0.8, 0.6]],
  "extinction": [[0, 0], [0.5, 0], [0.51, 0.15], [1, 0.15]]}"#;
/// Image size of every command.
const SIZE: (usize, usize) = (160, 120);

/// An opaque TF: nothing below 0.5, very dense above.
const TF: &str = r#"{"color": [[0, 1, 1, 1], [1, 1, 1, 1]],
  "extinction": [[0, 0], [0.5, 0], [0.51, 1000], [1, 1000]]}"#;

fn grid() -> Grid {
    let [nx, ny, nz] = DIMS;
    let inside = |v: usize, a: usize| (BOX[a][0]..=BOX[a][1]).contains(&v);
    let values: Vec<f32> = (0..nx * ny * nz)
        .map(|n| (n % nx, n / nx % ny, n / (nx * ny)))
        .map(|(i, j, k)| f32::from(u8::from(inside(i, 0) && inside(j, 1) && inside(k, 2))))
        .collect();
    Grid::new(DIMS, SPACING, ORIGIN, Samples::F32(Buffer::owned(values))).unwrap()
}

/// The grid's centre, world.
fn centre() -> DVec3 {
    let last = DVec3::new(DIMS[0] as f64, DIMS[1] as f64, DIMS[2] as f64) - 1.0;
    DVec3::from(ORIGIN) + DVec3::from(SPACING) * last / 2.0
}

/// Writes the grid, the TF and two cameras (perspective from an oblique corner, orthographic
/// from -y) into `dir`.
fn inputs(dir: &Path) {
    volux_io::nrrd::write(&grid(), &dir.join("box.nrrd")).unwrap();
    std::fs::write(dir.join("tf.json"), TF).unwrap();
    std::fs::write(dir.join("glass.json"), GLASS).unwrap();
    let c = centre();
    let eye = c + DVec3::new(-14.0, -30.0, 9.0);
    let cams = [
        ("persp.json", "perspective", eye),
        ("ortho.json", "orthographic", c - DVec3::Y * 60.0),
    ];
    for (name, projection, eye) in cams {
        let json = format!(
            r#"{{"projection": "{projection}", "eye": {:?}, "target": {:?}, "up": [0, 0, 1]}}"#,
            eye.to_array(),
            c.to_array()
        );
        std::fs::write(dir.join(name), json).unwrap();
    }
}

/// The camera a file resolves to with `--frame all` (the grid's bounds).
fn camera(dir: &Path, name: &str) -> Camera {
    let text = std::fs::read_to_string(dir.join(name)).unwrap();
    CameraSpec::from_json(&text)
        .unwrap()
        .resolve(&grid().bounds())
        .unwrap()
}

/// The scene `volux render box.nrrd --camera NAME --frame all --tf TF --size 160x120`
/// draws.
fn scene(dir: &Path, name: &str, tf: &str) -> Scene {
    let tf = volux_core::transfer_import::import_file(&dir.join(tf))
        .unwrap()
        .tf;
    let mut s = Scene::new(camera(dir, name), SIZE.0, SIZE.1, tf);
    s.method = Method::GridRaycast(GridRaycast::default());
    s
}

/// The view options of every command.
fn view<'a>(cam: &'a str, rest: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "box.nrrd", "--camera", cam, "--frame", "all", "--tf", "tf.json", "--size", "160x120",
    ];
    v.extend_from_slice(rest);
    v
}

fn run(command: &str, args: &[&str], dir: &Path) -> Output {
    let mut all = vec!["--quiet", command];
    all.extend_from_slice(args);
    volux(&all, dir)
}

fn ok(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The values of a `u8` NRRD, checked to have the grid's dims, spacing and origin.
fn read_u8(path: &Path) -> Vec<u8> {
    let g = volux_io::nrrd::read(path, Default::default()).unwrap();
    assert_eq!(g.dims(), DIMS);
    assert!((g.spacing() - DVec3::from(SPACING)).length() < 1e-9);
    assert!((g.origin() - DVec3::from(ORIGIN)).length() < 1e-9);
    let Samples::U8(b) = g.samples() else {
        panic!("{}: not u8", path.display())
    };
    b.as_slice().to_vec()
}

/// The sculpt mask written reads back with the grid's geometry and removes exactly the
/// voxels the same steps remove through the engine.
#[test]
fn sculpt_writes_the_engines_mask() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let tools = [
        "--erase",
        "40,30,12",
        "--dig",
        "80,60,15",
        "--stroke",
        "20,100,60,90,140,110,6",
        "--dig",
        "80,60,15",
    ];
    let args = view("persp.json", &[&tools[..], &["-o", "m.nrrd"]].concat());
    let err = ok(&run("sculpt", &args, d));
    let got = read_u8(&d.join("m.nrrd"));

    let (g, s) = (grid(), scene(d, "persp.json", "tf.json"));
    let mut sculpt = Sculpt::new(&g).unwrap();
    let erase = |points: Vec<[f64; 2]>, radius_px| SculptStep::Erase {
        camera: s.view.camera,
        size: [SIZE.0, SIZE.1],
        points,
        radius_px,
    };
    sculpt.apply(erase(vec![[40.0, 30.0]], 12.0)).unwrap();
    sculpt.dig(&g, &s, [80.0, 60.0], 15.0).unwrap().unwrap();
    let stroke = vec![[20.0, 100.0], [60.0, 90.0], [140.0, 110.0]];
    sculpt.apply(erase(stroke, 6.0)).unwrap();
    sculpt.dig(&g, &s, [80.0, 60.0], 15.0).unwrap().unwrap();
    let want = sculpt.mask().to_values();
    let removed = want.iter().filter(|&&v| v == 0).count();
    assert!(removed > 100, "the tools removed {removed} voxels: {err}");
    assert_eq!(got, want, "{err}");
}

/// The tools apply in command-line order: a dig under a later eraser disc works; the same
/// disc first leaves the dig's pixel showing nothing, an error naming it.
#[test]
fn the_order_of_erase_and_dig_matters() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let first = view(
        "ortho.json",
        &["--dig", "80,60,20", "--erase", "80,60,6", "-o", "a.nrrd"],
    );
    ok(&run("sculpt", &first, d));
    let a = read_u8(&d.join("a.nrrd"));
    let disc = view("ortho.json", &["--erase", "80,60,6", "-o", "b.nrrd"]);
    ok(&run("sculpt", &disc, d));
    let b = read_u8(&d.join("b.nrrd"));
    let zeros = |v: &[u8]| v.iter().filter(|&&x| x == 0).count();
    assert!(zeros(&a) > zeros(&b), "{} vs {}", zeros(&a), zeros(&b));

    let reversed = view(
        "ortho.json",
        &["--erase", "80,60,6", "--dig", "80,60,20", "-o", "c.nrrd"],
    );
    let out = run("sculpt", &reversed, d);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("--dig 80,60,20: pixel (80, 60) shows no visible surface"),
        "{err}"
    );
    assert!(!d.join("c.nrrd").exists());
}

/// Renders `scene` on the grid through the engine to `path`, as `volux render` writes it.
fn engine_png(scene: &Scene, path: &Path) {
    let volume = Volume::from(grid());
    let frame = create_renderer(&volume, &scene.method)
        .unwrap()
        .render(scene, &Control::default())
        .unwrap();
    let png = PngOptions {
        background: Some([0.0; 3]),
        sixteen_bit: false,
    };
    frame.image.write_png(path, &png).unwrap();
}

/// `render --mask` changes the picture, and draws what the engine draws with that mask in
/// the scene; `render --session` draws the session's sculpt steps the same way.
#[test]
fn render_mask_equals_the_engine_with_the_mask() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let tools = ["--dig", "80,60,20", "--erase", "70,45,8", "-o", "m.nrrd"];
    let with_session = [&tools[..], &["--session-out", "s.json"]].concat();
    ok(&run("sculpt", &view("persp.json", &with_session), d));
    let glass = |rest: &[&'static str]| {
        let mut v = view("persp.json", rest);
        v[6] = "glass.json";
        v
    };
    ok(&run("render", &glass(&["-o", "plain.png"]), d));
    ok(&run(
        "render",
        &glass(&["--mask", "m.nrrd", "-o", "masked.png"]),
        d,
    ));

    let mut s = scene(d, "persp.json", "glass.json");
    let mask = SculptMask::from_values(DIMS, &read_u8(&d.join("m.nrrd"))).unwrap();
    s.mask = Some(Arc::new(mask));
    engine_png(&s, &d.join("engine.png"));
    let pixels = |name: &str| png_pixels(&d.join(name)).2;
    let differ = |a: &str, b: &str| {
        let (a, b) = (pixels(a), pixels(b));
        a.iter().zip(&b).filter(|(p, q)| p != q).count()
    };
    assert!(
        differ("plain.png", "masked.png") > 100,
        "the mask changes the picture"
    );
    assert_eq!(differ("masked.png", "engine.png"), 0);

    // The session holds the opaque view and the steps: its render equals the engine's with
    // the mask in the opaque scene.
    ok(&run(
        "render",
        &["--session", "s.json", "-o", "session.png"],
        d,
    ));
    s.appearance = scene(d, "persp.json", "tf.json").appearance;
    engine_png(&s, &d.join("engine_opaque.png"));
    assert_eq!(differ("session.png", "engine_opaque.png"), 0);
    assert!(differ("session.png", "masked.png") > 100);
}

#[test]
fn measure_finds_a_box_of_known_size() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let Projection::Orthographic { height } = camera(d, "ortho.json").projection else {
        panic!("an orthographic camera")
    };
    let px_mm = height / SIZE.1 as f64;
    let x = |dx: f64| (SIZE.0 as f64 / 2.0 + dx / px_mm).to_string();
    let (a, b) = (format!("{},61", x(-2.0)), format!("{},61", x(2.0)));
    let args = view("ortho.json", &["--point", &a, "--point", &b, "--json"]);
    let m: serde_json::Value = serde_json::from_str(&ok(&run("measure", &args, d))).unwrap();
    let length = m["length_mm"].as_f64().unwrap();
    assert!((length - 4.0).abs() <= 0.5 * SPACING[0], "{m}");
    let face = ORIGIN[1] + (BOX[1][0] as f64 - 0.5) * SPACING[1];
    let points = m["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{m}");
    for p in points {
        let y = p[1].as_f64().unwrap();
        assert!((y - face).abs() <= 0.5 * SPACING[1], "{p} vs y = {face}");
    }
    let text = ok(&run(
        "measure",
        &view("ortho.json", &["--point", &a, "--point", &b]),
        d,
    ));
    assert!(
        text.contains("length: 4.0") || text.contains("length: 3.9"),
        "{text}"
    );
}

/// Two seeds on the front face, left and right, by the nearest rule: every voxel of the box
/// is labelled, by the side it lies on, and nothing else is.
#[test]
fn regions_label_the_visible_voxels_by_the_nearest_seed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let seeds = [
        "--seed", "70,60,3", "--seed", "90,60,7", "--rule", "nearest", "-o", "l.nrrd",
    ];
    let out = ok(&run("regions", &view("ortho.json", &seeds), d));
    assert!(
        out.contains("label 3: ") && out.contains("label 7: "),
        "{out}"
    );
    let labels = read_u8(&d.join("l.nrrd"));
    let g = grid();
    let mid = (BOX[0][0] + BOX[0][1]) as f64 / 2.0;
    for (n, &l) in labels.iter().enumerate() {
        let (i, j, k) = (n % DIMS[0], n / DIMS[0] % DIMS[1], n / (DIMS[0] * DIMS[1]));
        let want = match (g.value(i, j, k) > 0.5, (i as f64) < mid) {
            (false, _) => 0,
            (true, true) => 3,
            (true, false) => 7,
        };
        assert_eq!(l, want, "voxel ({i}, {j}, {k})");
    }
}

/// Two balls apart in the box's grid (index-space radius 3.5 about (6, 10, 8) and (17, 10,
/// 8)): whether voxel `ijk` is in the first, the second or neither.
fn ball_of(i: usize, j: usize, k: usize) -> Option<usize> {
    let v = DVec3::new(i as f64, j as f64, k as f64);
    [DVec3::new(6.0, 10.0, 8.0), DVec3::new(17.0, 10.0, 8.0)]
        .iter()
        .position(|c| (v - *c).length() <= 3.5)
}

/// Seeds on two balls apart (issue 41): the connected rule (the default) labels the ball a
/// seed is on and leaves the other at 0, in the file and in the printed counts; the nearest
/// rule labels both; one seed per ball labels each its own.
#[test]
fn regions_connected_leave_the_ball_no_seed_touches() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let [nx, ny, nz] = DIMS;
    let values: Vec<f32> = (0..nx * ny * nz)
        .map(|n| {
            f32::from(u8::from(
                ball_of(n % nx, n / nx % ny, n / (nx * ny)).is_some(),
            ))
        })
        .collect();
    let balls = Grid::new(DIMS, SPACING, ORIGIN, Samples::F32(Buffer::owned(values))).unwrap();
    volux_io::nrrd::write(&balls, &d.join("balls.nrrd")).unwrap();
    // The pixel of each ball's centre in the orthographic view from -y.
    let cam = camera(d, "ortho.json");
    let pixel = |i: f64| {
        let (x, y, _) = cam.project(
            balls.index_to_world(DVec3::new(i, 10.0, 8.0)),
            SIZE.0,
            SIZE.1,
        );
        format!("{x:.1},{y:.1}")
    };
    let (a, b) = (format!("{},5", pixel(6.0)), format!("{},6", pixel(17.0)));
    let regions = |rest: &[&str]| {
        let mut args = view("ortho.json", rest);
        args[0] = "balls.nrrd";
        let out = ok(&run("regions", &args, d));
        (out, read_u8(&d.join("l.nrrd")))
    };
    let size = |ball| {
        (0..nx * ny * nz)
            .filter(|&n| ball_of(n % nx, n / nx % ny, n / (nx * ny)) == Some(ball))
            .count()
    };
    let (first, second) = (size(0), size(1));
    assert!(first > 100 && first == second, "{first} {second}");
    let total = nx * ny * nz;
    let check = |labels: &[u8], want: [u8; 2]| {
        for (n, &l) in labels.iter().enumerate() {
            let (i, j, k) = (n % nx, n / nx % ny, n / (nx * ny));
            let expected = ball_of(i, j, k).map_or(0, |ball| want[ball]);
            assert_eq!(l, expected, "voxel ({i}, {j}, {k})");
        }
    };
    let (out, labels) = regions(&["--seed", &a, "-o", "l.nrrd"]);
    check(&labels, [5, 0]);
    assert!(out.contains(&format!("label 5: {first} voxels")), "{out}");
    assert!(
        out.contains(&format!("unlabelled: {} voxels", total - first)),
        "{out}"
    );
    let (out, labels) = regions(&["--seed", &a, "--rule", "nearest", "-o", "l.nrrd"]);
    check(&labels, [5, 5]);
    assert!(
        out.contains(&format!("label 5: {} voxels", 2 * first)),
        "{out}"
    );
    let (out, labels) = regions(&[
        "--seed",
        &a,
        "--seed",
        &b,
        "--rule",
        "connected",
        "-o",
        "l.nrrd",
    ]);
    check(&labels, [5, 6]);
    assert!(out.contains(&format!("label 6: {second} voxels")), "{out}");
}

/// Each bad input exits non-zero with one error line and writes no output file.
#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let small = Grid::new(
        [4, 4, 4],
        [1.0; 3],
        [0.0; 3],
        Samples::U8(Buffer::owned(vec![1; 64])),
    );
    volux_io::nrrd::write(&small.unwrap(), &d.join("small.nrrd")).unwrap();
    // The grid's dims, but mirrored in x and y: a mask of the same scan stored RAS.
    let g = grid();
    let n = g.len();
    let flipped = Grid::new(
        g.dims(),
        g.spacing().to_array(),
        g.origin().to_array(),
        Samples::U8(Buffer::owned(vec![1; n])),
    )
    .unwrap()
    .with_direction(glam::DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0)))
    .unwrap();
    volux_io::nrrd::write(&flipped, &d.join("flipped.nrrd")).unwrap();
    ok(&run(
        "generate",
        &["tets-smooth", "--size", "200", "-o", "mesh.vtet"],
        d,
    ));
    let o = ["-o", "out.nrrd"];
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        (
            "sculpt",
            vec!["missing.nrrd", "--erase", "1,1,1", "-o", "out.nrrd"],
            "missing.nrrd",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--erase", "1,x,3"][..], &o].concat()),
            "expected X,Y,R",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--erase", "1,2"][..], &o].concat()),
            "expected X,Y,R",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--dig", "80,60,0"][..], &o].concat()),
            "R > 0",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--stroke", "1,2,3,4"][..], &o].concat()),
            "expected X1,Y1",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--dig", "2,2,5"][..], &o].concat()),
            "pixel (2, 2) shows no visible surface",
        ),
        (
            "sculpt",
            view("ortho.json", &[&["--erase", "900,2,5"][..], &o].concat()),
            "outside the 160x120 image",
        ),
        (
            "sculpt",
            view(
                "ortho.json",
                &[&["--mask", "small.nrrd", "--erase", "80,60,5"][..], &o].concat(),
            ),
            "does not lie on box.nrrd's voxels: dims 4x4x4, the volume's",
        ),
        (
            "sculpt",
            view("ortho.json", &["-o", "out.nrrd"]),
            "at least one tool",
        ),
        (
            "sculpt",
            view("ortho.json", &["--erase", "80,60,5", "-o", "out.png"]),
            "name the file .nrrd",
        ),
        (
            "sculpt",
            vec!["mesh.vtet", "--erase", "80,60,5", "-o", "out.nrrd"],
            "apply to grids",
        ),
        (
            "measure",
            view("ortho.json", &["--point", "80,60"]),
            "at least two --point",
        ),
        (
            "measure",
            view("ortho.json", &["--point", "80,60", "--point", "3,3"]),
            "--point 3,3: pixel (3, 3) shows no",
        ),
        (
            "regions",
            view("ortho.json", &[&["--seed", "80,60,0"][..], &o].concat()),
            "label from 1 to 255",
        ),
        (
            "regions",
            view("ortho.json", &[&["--seed", "2,2,1"][..], &o].concat()),
            "shows no visible surface",
        ),
        (
            "render",
            view("ortho.json", &["--mask", "small.nrrd", "-o", "out.png"]),
            "does not lie on box.nrrd's voxels: dims 4x4x4, the volume's",
        ),
        (
            "render",
            view("ortho.json", &["--mask", "flipped.nrrd", "-o", "out.png"]),
            "does not lie on box.nrrd's voxels: direction",
        ),
        (
            "render",
            vec!["mesh.vtet", "--mask", "small.nrrd", "-o", "out.png"],
            "--mask applies to grids",
        ),
        (
            "render",
            view("ortho.json", &["--measure", "80,60", "-o", "out.png"]),
            "at least two --measure",
        ),
        (
            "render",
            view(
                "ortho.json",
                &["--measure", "80,60", "--measure", "2,2", "-o", "out.png"],
            ),
            "--measure 2,2: pixel (2, 2) shows no visible surface",
        ),
        (
            "render",
            view(
                "ortho.json",
                &["--measure", "80,60", "--measure", "80,600", "-o", "out.png"],
            ),
            "lies outside the 160x120 image",
        ),
        (
            "render",
            view(
                "ortho.json",
                &["--measure", "80,60", "--measure", "x", "-o", "out.png"],
            ),
            "--measure 'x': expected X,Y",
        ),
        (
            "render",
            vec![
                "mesh.vtet",
                "--measure",
                "1,1",
                "--measure",
                "2,2",
                "-o",
                "out.png",
            ],
            "--measure picks on grids",
        ),
        (
            "render",
            view(
                "ortho.json",
                &[
                    "--measure",
                    "80,60",
                    "--measure",
                    "90,60",
                    "--orbit",
                    "3",
                    "-o",
                    "out.png",
                ],
            ),
            "--measure draws on one picture",
        ),
    ];
    for (command, args, expected) in cases {
        let out = run(command, &args, d);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{command} {args:?} should fail");
        assert_eq!(err.trim().lines().count(), 1, "{command} {args:?}: {err}");
        assert!(err.starts_with("volux: error: "), "{err}");
        assert!(
            err.contains(expected),
            "{command} {args:?}: {err} (wanted {expected})"
        );
        for stray in ["out.nrrd", "out.png"] {
            assert!(!d.join(stray).exists(), "{command} {args:?} wrote {stray}");
        }
    }
}

/// `render --measure` prints the length `volux measure` prints for the same pixels and view,
/// and draws the line between them on the picture (yellow over the white box), leaving
/// pixels away from it as they were.
#[test]
fn render_measure_draws_the_line_and_prints_the_length() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    inputs(d);
    let Projection::Orthographic { height } = camera(d, "ortho.json").projection else {
        panic!("an orthographic camera")
    };
    // Two points 2 mm either side of the centre, on the box's front face.
    let half = (2.0 / (height / SIZE.1 as f64)).round() as usize;
    let (x0, x1) = (SIZE.0 / 2 - half, SIZE.0 / 2 + half);
    let (a, b) = (format!("{x0}.5,60.5"), format!("{x1}.5,60.5"));
    let (a, b) = (a.as_str(), b.as_str());
    let measured = ok(&run(
        "measure",
        &view("ortho.json", &["--point", a, "--point", b]),
        d,
    ));
    let rest = ["--measure", a, "--measure", b, "-o", "m.png"];
    let printed = ok(&run("render", &view("ortho.json", &rest), d));
    assert_eq!(
        printed, measured,
        "render --measure prints what measure prints"
    );
    ok(&run("render", &view("ortho.json", &["-o", "plain.png"]), d));
    let (w, _, marked) = png_pixels(&d.join("m.png"));
    let (_, _, plain) = png_pixels(&d.join("plain.png"));
    let at = |px: &[Vec<u8>], x: usize, y: usize| px[y * w as usize + x].clone();
    assert!(x1 - x0 > 10, "a line of {} pixels", x1 - x0);
    for x in x0..=x1 {
        let p = at(&marked, x, 60);
        assert!(p[0] > 200 && p[1] > 150 && p[2] < 120, "({x}, 60) is {p:?}");
        assert_eq!(at(&plain, x, 60)[2], 255, "the box is white under the line");
    }
    let off = [(80, 50), (80, 70), (x0 - 8, 60), (x1 + 8, 60), (5, 5)];
    for (x, y) in off {
        assert_eq!(
            at(&marked, x, y),
            at(&plain, x, y),
            "({x}, {y}) is off the line"
        );
    }
}
