//! The conformance test of issue 40: Volux against the reference libraries (pydicom,
//! nibabel, pynrrd, tifffile, SimpleITK) on their own test data and on files they write.
//!
//! `.ci/conformance/setup` installs the libraries into a venv under `target/conformance`
//! (this test runs it when the venv is missing, so `cargo test` needs PyPI once), and
//! `.ci/conformance/run.py` converts every file with this build's `volux` and compares values
//! and geometry with what the library decodes. The test fails on any silent difference,
//! crash, unclear refusal, slow or memory-hungry refusal of a small file, or when the share
//! of files read exactly falls below the floor below. The table is written to
//! `target/conformance/conformance.md`; `docs/conformance.md` is a copy of it.
use std::path::PathBuf;
use std::process::Command;

/// Least share of the counted files read exactly. Raise it as readers improve; never lower it.
const MIN_EXACT: f64 = 0.92;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn the_reference_libraries_decode_what_volux_reads() {
    let root = root();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let venv = target.join("conformance/venv");
    let setup = Command::new("bash")
        .arg(root.join(".ci/conformance/setup"))
        .arg(&venv)
        .status()
        .expect("bash runs .ci/conformance/setup");
    assert!(
        setup.success(),
        "installing the reference libraries failed (.ci/conformance/setup needs python3 and PyPI)"
    );
    let work = target.join("conformance/work");
    let _ = std::fs::remove_dir_all(&work);
    let out = Command::new(venv.join("bin/python"))
        .arg(root.join(".ci/conformance/run.py"))
        .args([
            "--volux",
            env!("CARGO_BIN_EXE_volux"),
            "--check",
            "--jobs",
            "2",
        ])
        .arg("--work")
        .arg(&work)
        .arg("--markdown")
        .arg(target.join("conformance/conformance.md"))
        .arg("--json")
        .arg(target.join("conformance/results.json"))
        .args(["--min-exact", &MIN_EXACT.to_string()])
        .output()
        .expect("the venv's python runs run.py");
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{text}");
    assert!(out.status.success(), "conformance failed:\n{err}\n{text}");
}
