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
    use volux_render::scene::Scene;
    use volux_render::session::{DatasetRef, Session, SessionBackend};
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
    session.backend = Some(SessionBackend::Gpu);
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
