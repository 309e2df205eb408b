//! `mpirun -np N volux render STORE --distributed` on 2 and 3 ranks equals the
//! single-process render (`--lod 0 --no-early-termination`; MIP refuses the flag, having no
//! opacity) within 1e-6 per channel of the raw linear image: composited (Riemann, and with
//! shaded isosurfaces) and by maximum intensity projection; adaptive Simpson (its state
//! pipeline, early termination on and off) exactly; a missing store is one error line and
//! no output. Needs the `mpi` feature and `mpirun` (OpenMPI):
//! `cargo test -p volux-cli --features mpi --test distributed`.
#![cfg(feature = "mpi")]
use std::path::Path;
use std::process::Command;

const VOLUX: &str = env!("CARGO_BIN_EXE_volux");

fn volux(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(VOLUX)
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn mpirun(dir: &Path, n: usize, args: &[&str]) -> std::process::Output {
    let mut c = Command::new("mpirun");
    c.current_dir(dir).arg("--oversubscribe");
    if std::env::var("USER").map(|u| u == "root").unwrap_or(false)
        || std::env::var("HOME").map(|h| h == "/root").unwrap_or(false)
    {
        c.arg("--allow-run-as-root");
    }
    c.args(["-np", &n.to_string(), VOLUX])
        .args(args)
        .output()
        .unwrap()
}

fn raw(path: &Path) -> Vec<f32> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// The single-process render of `s.ome.zarr` with `extra` options against the distributed
/// one on 2 and 3 ranks: the largest difference of the raw images.
fn check(d: &Path, name: &str, extra: &[&str]) -> f32 {
    let view = ["--size", "64x56", "--azimuth", "35", "--elevation", "25"];
    let (single_png, single_raw) = (format!("{name}.png"), format!("{name}.f32"));
    let mut single = vec![
        "render",
        "s.ome.zarr",
        "--lod",
        "0",
        "-o",
        &single_png,
        "--raw-out",
        &single_raw,
    ];
    // MIP has no opacity to stop at (the flag is refused with it); adaptive Simpson's state
    // pipeline keeps early termination (its cases say when to turn it off).
    if !extra.contains(&"--mip") && !extra.contains(&"adaptive-simpson") {
        single.push("--no-early-termination");
    }
    single.extend(view);
    single.extend(extra);
    let out = volux(d, &single);
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let want = raw(&d.join(&single_raw));
    assert!(
        want.iter().any(|&v| v > 0.1),
        "{name}: the picture shows something"
    );
    let mut worst = 0.0f32;
    for n in [2, 3] {
        let (png, f32_) = (format!("{name}-d{n}.png"), format!("{name}-d{n}.f32"));
        let mut args = vec![
            "render",
            "s.ome.zarr",
            "--distributed",
            "-o",
            &png,
            "--raw-out",
            &f32_,
            "--stats",
            "--json",
        ];
        args.extend(view);
        args.extend(extra);
        let out = mpirun(d, n, &args);
        assert!(
            out.status.success(),
            "{name}, {n} ranks: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stats: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(stats["ranks"], n);
        for r in stats["per_rank"].as_array().unwrap() {
            assert_eq!(r["reads"]["other"], 0, "{name}: {r}");
        }
        let got = raw(&d.join(&f32_));
        assert_eq!(got.len(), want.len());
        let diff = got
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(diff <= 1e-6, "{name}, {n} ranks: largest difference {diff}");
        assert!(d.join(&png).exists());
        worst = worst.max(diff);
    }
    eprintln!("{name}: largest difference {worst:e}");
    worst
}

#[test]
fn two_and_three_ranks_equal_the_single_process_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = volux(
        d,
        &[
            "generate",
            "marschner-lobb",
            "--size",
            "40",
            "--chunk",
            "12",
            "-o",
            "s.ome.zarr",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    check(d, "riemann", &[]);
    check(d, "mip", &["--mip"]);
    check(
        d,
        "iso",
        &[
            "--iso",
            "0.3:1,0.5,0.2,0.4",
            "--iso",
            "0.55:0.2,0.6,1,0.6",
            "--shade",
        ],
    );
    // Adaptive Simpson through the state pipeline: bit for bit, the f32 lanes with early
    // termination, the f64 decoupled control without.
    let adaptive = [
        "--integrator",
        "adaptive-simpson",
        "--tol",
        "0.002",
        "--hmax",
        "2",
    ];
    assert_eq!(check(d, "adaptive", &adaptive), 0.0);
    let decoupled = [&adaptive[..], &["--decoupled", "--no-early-termination"]].concat();
    assert_eq!(check(d, "adaptive-decoupled", &decoupled), 0.0);
    // An error on the ranks: one line from rank 0, a failed run, no image.
    let out = mpirun(
        d,
        2,
        &[
            "render",
            "missing.ome.zarr",
            "--distributed",
            "-o",
            "none.png",
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("volux: error:").count(), 1, "{err}");
    assert!(!d.join("none.png").exists());
}
