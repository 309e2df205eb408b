//! `volux render --orbit`: a turntable in one process.
mod common;

use common::{png_pixels, volux};

fn grid(dir: &std::path::Path) {
    let out = volux(
        &["generate", "marschner-lobb", "--size", "24", "-o", "ml.raw"],
        dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Each command fails with one line holding its expected text.
fn one_line_errors(cases: &[(&[&str], &str)], dir: &std::path::Path) {
    for (args, expected) in cases {
        let out = volux(args, dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(expected),
            "{args:?}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

/// Frame 0 is the plain render; the others turn; each frame's figures are one JSON object
/// that says which frame it is.
#[test]
fn orbit_writes_numbered_frames_and_reports_each() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    grid(d);
    let size = ["--size", "40x32"];
    let one = volux(
        &[&["render", "ml.raw", "-o", "one.png"][..], &size].concat(),
        d,
    );
    assert!(one.status.success());
    let args = [
        &[
            "render", "ml.raw", "--orbit", "4:30", "-o", "t.png", "--stats", "--json",
        ][..],
        &size,
    ];
    let out = volux(&args.concat(), d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let objects: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(objects.len(), 4, "{stdout}");
    for (k, o) in objects.iter().enumerate() {
        assert_eq!(o["frame"], k);
        assert_eq!(o["first"], k == 0);
        assert!(o["output"]
            .as_str()
            .unwrap()
            .ends_with(&format!("t_{k:04}.png")));
    }
    let frame = |k: usize| png_pixels(&d.join(format!("t_{k:04}.png"))).2;
    // (30 degrees: Marschner-Lobb looks the same every quarter turn)
    assert!(
        frame(0) == png_pixels(&d.join("one.png")).2,
        "frame 0 is the plain render"
    );
    assert!(frame(0) != frame(1), "the camera turns");
}

/// `--no-write` writes nothing and says so; it needs --orbit; bad specs are one line.
#[test]
fn no_write_and_mistakes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    grid(d);
    let out = volux(
        &[
            "render",
            "ml.raw",
            "--orbit",
            "3:10",
            "--no-write",
            "--size",
            "16x16",
        ],
        d,
    );
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no files"));
    assert!(!d.join("out_0000.png").exists());
    let cases = [
        (
            &["render", "ml.raw", "--no-write"][..],
            "--no-write goes with --orbit",
        ),
        (
            &["render", "ml.raw", "--orbit", "0"][..],
            "N is a whole number",
        ),
        (
            &["render", "ml.raw", "--orbit", "5:x"][..],
            "DEG is a number",
        ),
    ];
    one_line_errors(&cases, d);
}

/// `volux bench FILE -- [render options]` times a first frame and warm frames of any file.
#[test]
fn bench_of_a_file_times_warm_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    grid(d);
    let args = [
        "bench",
        "ml.raw",
        "--frames",
        "3",
        "--json",
        "--",
        "--size",
        "32x24",
        "--tf",
        "grayscale",
    ];
    let out = volux(&args, d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (v["method"].as_str(), v["warm_frames"].as_u64()),
        (Some("raycast"), Some(3))
    );
    assert_eq!(
        (v["width"].as_u64(), v["rate_unit"].as_str()),
        (Some(32), Some("samples"))
    );
    assert!(v["warm_min_ms"].as_f64() <= v["warm_median_ms"].as_f64());
    assert!(!d.join("out.png").exists() && !d.join("out_0000.png").exists());
    let cases = [
        (
            &["bench", "ml.raw", "--suite", "pt"][..],
            "--suite selects suite cases",
        ),
        (
            &["bench", "ml.raw", "--", "--orbit", "3"][..],
            "--orbit is set by the bench",
        ),
        (
            &["bench", "ml.raw", "--", "--nonsense"][..],
            "the render options after --",
        ),
    ];
    one_line_errors(&cases, d);
}
