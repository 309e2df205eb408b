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
