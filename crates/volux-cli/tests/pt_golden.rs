//! Projected Tetrahedra images of the shared tetrahedral meshes (Blunt Fin, LOx Post,
//! post.vtk) compared with small committed baselines in `tests/golden/`.
//!
//! Each case renders through the `volux` binary at 64x64 (automatic TF, centroid order) and
//! compares the 8-bit sRGB PNG with the baseline: mean absolute difference per channel at
//! most 1.0 (of 255) and at most 1 % of the pixels off by more than 16. The tolerance absorbs
//! rounding changes in the rasterizer and the colour models; an ordering error, a crack, a
//! wrong thick vertex or a wrong TF shows far above it. Missing datasets skip their case.
//! Regenerate the baselines with `VOLUX_UPDATE_GOLDEN=1 cargo test -p volux-cli --test
//! pt_golden` after a deliberate change, and look at them.
use std::path::Path;
use std::process::Command;

use volux_testkit::data::shared;

mod common;

fn check(name: &str, rel: &str, extra: &[&str]) {
    let Some(input) = shared(rel) else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pt.png");
    let mut args = vec![
        "render",
        input.to_str().unwrap(),
        "--method",
        "pt",
        "--size",
        "64x64",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let run = Command::new(env!("CARGO_BIN_EXE_volux"))
        .args(&args)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let golden = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{name}.png"));
    if std::env::var_os("VOLUX_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        std::fs::copy(&out, &golden).unwrap();
        eprintln!("updated {}", golden.display());
        return;
    }
    match common::png_close(&out, &golden) {
        Ok(figures) => eprintln!("{name}: {figures}"),
        Err(why) => panic!("{name}: {why}"),
    }
}

#[test]
fn blunt_fin_matches_its_baseline() {
    check(
        "blunt_fin",
        "nasa_blunt_fin/blunt_fin_tets_density.off.gz",
        &["--azimuth", "40", "--elevation", "30"],
    );
}

#[test]
fn blunt_fin_with_isosurfaces_matches_its_baseline() {
    check(
        "blunt_fin_iso",
        "nasa_blunt_fin/blunt_fin_tets_density.off.gz",
        &[
            "--azimuth",
            "40",
            "--elevation",
            "30",
            "--iso",
            "1.2:0.9,0.8,0.3,0.5",
            "--iso",
            "3.0:0.3,0.6,0.9,0.8",
        ],
    );
}

#[test]
fn lox_post_matches_its_baseline() {
    check(
        "lox_post",
        "nasa_lox_post/lox_post_tets_velmag.off.gz",
        &[
            "--azimuth",
            "30",
            "--elevation",
            "40",
            "--opacity-scale",
            "0.05",
        ],
    );
}

#[test]
fn post_vtk_matches_its_baseline() {
    check(
        "post_vtk",
        "vtk_post_tets/post.vtk",
        &["--azimuth", "30", "--elevation", "20", "--sort", "exact"],
    );
}
