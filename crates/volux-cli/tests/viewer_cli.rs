//! `volux view` and `volux render --session` as a user meets them.
mod common;

use std::process::Command;

use common::volux;

/// Without volux-view beside it or on the PATH, `volux view` says in one line how to build
/// it.
#[test]
fn view_without_the_viewer_says_how_to_build_it() {
    let dir = tempfile::tempdir().unwrap();
    let alone = dir.path().join("volux");
    std::fs::copy(env!("CARGO_BIN_EXE_volux"), &alone).unwrap();
    let out = Command::new(&alone)
        .args(["view", "head.nrrd"])
        .env("PATH", dir.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("cargo build --release -p volux-viewer"),
        "{err}"
    );
}

/// `--session` goes with -o only; a missing or foreign session is one clear line.
#[test]
fn session_mistakes_are_one_line_each() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 3] = [
        (
            &["render", "--session", "s.json", "--tf", "ct-bone"],
            "--tf does not go with --session",
        ),
        (
            &["render", "--session", "missing.json"],
            "session missing.json",
        ),
        (&["render", "--session", "other.json"], "not a session"),
    ];
    std::fs::write(dir.path().join("other.json"), r#"{"color": []}"#).unwrap();
    for (args, expected) in cases {
        let out = volux(args, dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(expected),
            "{args:?}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

/// A session names its backend: `render --session` follows it (a GPU session needs a build
/// with the GPU backend and says so in one line otherwise), and `--backend` overrides it.
#[test]
fn a_session_renders_on_its_backend_unless_told_otherwise() {
    use volux_app::session::{DatasetRef, Session};
    use volux_render::scene::Scene;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = volux_core::synth::marschner_lobb(12).unwrap();
    volux_io::nrrd::write(&grid, &d.join("ml.nrrd")).unwrap();
    let camera = volux_core::CameraSpec::default()
        .resolve(&grid.bounds())
        .unwrap();
    let scene = Scene::new(
        camera,
        24,
        16,
        volux_core::TransferFunction::automatic(&volux_core::histogram::Histogram::of_grid(
            &grid, 64,
        )),
    );
    let dataset = DatasetRef {
        path: d.join("ml.nrrd"),
        ..Default::default()
    };
    let mut session = Session::new(dataset, &scene, None);
    session.backend = Some(volux_app::Backend::Gpu);
    session.save(&d.join("gpu.json")).unwrap();

    let on_gpu = volux(&["render", "--session", "gpu.json", "-o", "gpu.png"], d);
    let err = String::from_utf8_lossy(&on_gpu.stderr);
    if cfg!(not(feature = "gpu")) {
        assert!(!on_gpu.status.success(), "{err}");
        assert!(err.contains("--features gpu"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!d.join("gpu.png").exists());
    }
    let on_cpu = volux(
        &[
            "render",
            "--session",
            "gpu.json",
            "--backend",
            "cpu",
            "-o",
            "cpu.png",
        ],
        d,
    );
    let err = String::from_utf8_lossy(&on_cpu.stderr);
    assert!(on_cpu.status.success(), "{err}");
    assert!(d.join("cpu.png").is_file());
}

/// Opaque grey where the box is, transparent elsewhere.
const GREY_BOX_TF: &str = r#"{"color": [[0, 0.6, 0.6, 0.6], [1, 0.6, 0.6, 0.6]],
    "extinction": [[0, 0], [0.4, 0], [0.5, 50], [1, 50]]}"#;

/// A 24³ grid holding a box of 1 (voxels 6 to 17 on each axis) in 0, spacing 1: its front
/// face (seen from -y) is the plane y = 6.
fn boxed_grid() -> volux_core::Grid {
    use volux_core::grid::{Buffer, Samples};
    let n = 24;
    let inside = |i: usize| (6..=17).contains(&i);
    let values: Vec<u8> = (0..n * n * n)
        .map(|v| u8::from(inside(v % n) && inside(v / n % n) && inside(v / (n * n))))
        .collect();
    volux_core::Grid::new(
        [n; 3],
        [1.0; 3],
        [0.0; 3],
        Samples::U8(Buffer::owned(values)),
    )
    .unwrap()
}

/// A session of the box seen from the front (orthographic, 120 x 90), opaque grey, with a
/// region seed on the front face and a measurement across it (world x 8 to 15 at y = 6,
/// z = 12: 7 mm), as the viewer saves them.
fn boxed_session(d: &std::path::Path) {
    use glam::DVec3;
    use volux_app::session::{DatasetRef, Session};
    use volux_core::camera::{Camera, Projection};
    use volux_render::scene::Scene;
    use volux_render::sculpt::SculptStep;
    volux_io::nrrd::write(&boxed_grid(), &d.join("box.nrrd")).unwrap();
    let camera = Camera {
        eye: DVec3::new(11.5, -40.0, 11.5),
        target: DVec3::new(11.5, 11.5, 11.5),
        up: DVec3::Z,
        projection: Projection::Orthographic { height: 30.0 },
    };
    let tf = volux_core::TransferFunction::from_json(GREY_BOX_TF).unwrap();
    let scene = Scene::new(camera, 120, 90, tf);
    let dataset = DatasetRef {
        path: d.join("box.nrrd"),
        ..Default::default()
    };
    let mut session = Session::new(dataset, &scene, None);
    session.background = Some([0.0; 3]);
    session.sculpt = vec![
        SculptStep::Label {
            point: DVec3::new(11.5, 6.0, 11.5),
            label: 1,
            colour: [0.9, 0.1, 0.1],
            rule: volux_core::sculpt::RegionRule::Connected,
        },
        SculptStep::Measure {
            point: DVec3::new(8.0, 6.0, 12.0),
            new_line: true,
        },
        SculptStep::Measure {
            point: DVec3::new(15.0, 6.0, 12.0),
            new_line: false,
        },
    ];
    session.save(&d.join("box.json")).unwrap();
}

/// `render --session` draws what the viewer shows: the region labels in their colour and
/// the measurement line (its length printed), and renders larger or nearer for a figure
/// with --size and --zoom, each said on stderr, the lines where the points are.
#[test]
fn a_session_renders_with_its_labels_and_measurements_and_larger_for_a_figure() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    boxed_session(d);
    let out = volux(&["render", "--session", "box.json", "-o", "s.png"], d);
    let (text, err) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{err}");
    assert!(text.contains("length: 7.000"), "{text}");
    // 30 world units over 90 pixels, the box's middle (11.5, 11.5) at the image's middle:
    // world x = 11.5 + (px + 0.5 - 60) / 3, z = 11.5 - (py + 0.5 - 45) / 3.
    let (w, h, px) = common::png_pixels(&d.join("s.png"));
    assert_eq!((w, h), (120, 90));
    let at = |px: &[Vec<u8>], w: u32, x: u32, y: u32| px[(y * w + x) as usize].clone();
    // The labelled face is red, away from the line (x 12, z 8).
    let face = at(&px, w, 61, 55);
    assert!(
        face[0] > 2 * face[1] && face[0] > 100,
        "label colour: {face:?}"
    );
    // The line at z = 12 (row 43), x from 8 to 15 (columns 49 to 70): yellow.
    let line = at(&px, w, 60, 43);
    assert!(
        line[0] > 180 && line[1] > 140 && line[2] < 90,
        "line: {line:?}"
    );
    // Twice the size: the same view, the line where its points are.
    let out = volux(
        &[
            "render",
            "--session",
            "box.json",
            "--size",
            "240x180",
            "-o",
            "big.png",
        ],
        d,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("--size 240x180 replaces the session's 120x90"),
        "{err}"
    );
    let (w, h, px) = common::png_pixels(&d.join("big.png"));
    assert_eq!((w, h), (240, 180));
    let line = at(&px, w, 120, 86);
    assert!(
        line[0] > 180 && line[1] > 140 && line[2] < 90,
        "big line: {line:?}"
    );
    let face = at(&px, w, 122, 110);
    assert!(
        face[0] > 2 * face[1] && face[0] > 100,
        "big label colour: {face:?}"
    );
    // Zoomed twice: column 34 (world x 3 unzoomed, 7.25 zoomed) moves onto the box.
    let out = volux(
        &[
            "render",
            "--session",
            "box.json",
            "--zoom",
            "2",
            "-o",
            "near.png",
        ],
        d,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && err.contains("--zoom 2 zooms"),
        "{err}"
    );
    let (_, _, plain) = common::png_pixels(&d.join("s.png"));
    let (_, _, near) = common::png_pixels(&d.join("near.png"));
    assert!(
        plain[55 * 120 + 34][0] < 20,
        "unzoomed, column 34 is background"
    );
    assert!(
        near[55 * 120 + 34][0] > 50,
        "zoomed, the box fills column 34"
    );
}

/// `render --labels` colours a label volume on the data's voxels; one on other voxels, or
/// with values that are not labels, or under MIP, is one clear line and no picture.
#[test]
fn render_colours_a_label_volume_and_refuses_one_that_does_not_fit() {
    use volux_core::grid::{Buffer, Samples};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let g = boxed_grid();
    volux_io::nrrd::write(&g, &d.join("box.nrrd")).unwrap();
    std::fs::write(d.join("grey.json"), GREY_BOX_TF).unwrap();
    // From -y, orthographic: +x runs to the right.
    std::fs::write(
        d.join("front.json"),
        r#"{"eye": [11.5, -40, 11.5], "target": [11.5, 11.5, 11.5], "up": [0, 0, 1],
            "projection": "orthographic"}"#,
    )
    .unwrap();
    // Label 2 on the left half of the box (x < 12), nothing elsewhere.
    let labels: Vec<u8> = (0..24 * 24 * 24)
        .map(|v| {
            if g.value(v % 24, v / 24 % 24, v / 576) > 0.5 && v % 24 < 12 {
                2
            } else {
                0
            }
        })
        .collect();
    let label_grid = |values: Samples, spacing: f64| {
        volux_core::Grid::new([24; 3], [spacing; 3], [0.0; 3], values).unwrap()
    };
    let write = |name: &str, grid: &volux_core::Grid| {
        volux_io::nrrd::write(grid, &d.join(name)).unwrap();
    };
    write(
        "l.nrrd",
        &label_grid(Samples::U8(Buffer::owned(labels.clone())), 1.0),
    );
    write(
        "far.nrrd",
        &label_grid(Samples::U8(Buffer::owned(labels)), 2.0),
    );
    write(
        "half.nrrd",
        &label_grid(Samples::F32(Buffer::owned(vec![0.5; 24 * 24 * 24])), 1.0),
    );
    let args = |labels: &str, out: &str| -> Vec<String> {
        [
            "render",
            "box.nrrd",
            "--view",
            "-y",
            "--tf",
            "grey.json",
            "--size",
            "40x40",
            "--labels",
            labels,
            "-o",
            out,
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |a: &[String]| volux(&a.iter().map(String::as_str).collect::<Vec<_>>(), d);
    let out = run(&args("l.nrrd", "l.png"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, _, px) = common::png_pixels(&d.join("l.png"));
    // Label 2's colour (light blue) on the labelled half, the TF's grey on the other.
    let labelled = px.iter().filter(|p| p[2] > p[0] + 40).count();
    let grey = px
        .iter()
        .filter(|p| p[0] > 100 && (p[2] as i32 - p[0] as i32).abs() < 30)
        .count();
    let n = px.len();
    assert!(
        labelled > n / 20 && grey > n / 20,
        "{labelled} labelled, {grey} grey of {n}"
    );
    let mut mip = args("l.nrrd", "mip.png");
    mip.push("--mip".into());
    for (a, expected, png) in [
        (args("far.nrrd", "far.png"), "does not lie on", "far.png"),
        (args("half.nrrd", "half.png"), "not a label", "half.png"),
        (mip, "MIP", "mip.png"),
    ] {
        let out = run(&a);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(expected),
            "{a:?}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!d.join(png).exists());
    }
}
