//! The tet ray caster on the shared meshes (Blunt Fin, LOx Post, post.vtk): no ray abandoned,
//! re-entries on the non-convex LOx Post, and agreement with PT (exact order, exact colour)
//! within 1/255 mean per channel, measured with `volux compare`. Absent datasets are skipped.
use std::process::Output;

mod common;
use common::volux;
use volux_testkit::data::shared;

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn check(rel: &str, reentries_expected: bool) {
    let Some(input) = shared(rel) else { return };
    let input = input.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let view = [
        "--size",
        "96x72",
        "--azimuth",
        "30",
        "--elevation",
        "25",
        "--no-early-termination",
    ];
    let mut args = vec![
        "render",
        input,
        "--method",
        "raycast",
        "--integrator",
        "exact",
    ];
    args.extend_from_slice(&view);
    args.extend_from_slice(&["-o", "rc.png", "--stats", "--json"]);
    let rc = json(&volux(&args, d));
    assert_eq!(rc["abandoned"].as_u64(), Some(0), "{rel}: abandoned rays");
    assert!(rc["segments"].as_u64().unwrap() > 1000, "{rel}: segments");
    if reentries_expected {
        assert!(rc["reentries"].as_u64().unwrap() > 0, "{rel}: non-convex");
    }
    let mut args = vec![
        "render", input, "--method", "pt", "--sort", "exact", "--color", "exact",
    ];
    args.extend_from_slice(&view);
    args.extend_from_slice(&["-o", "pt.png"]);
    let pt = volux(&args, d);
    assert!(
        pt.status.success(),
        "{}",
        String::from_utf8_lossy(&pt.stderr)
    );
    let cmp = json(&volux(&["compare", "rc.png", "pt.png", "--json"], d));
    let mean = cmp["mean_error"].as_f64().unwrap();
    eprintln!("{rel}: PT vs ray caster {cmp}");
    assert!(mean < 1.0 / 255.0, "{rel}: mean error {mean}");
}

#[test]
fn blunt_fin_ray_cast_loses_no_ray_and_matches_pt() {
    check("nasa_blunt_fin/blunt_fin_tets_density.off.gz", false);
}

#[test]
fn lox_post_ray_cast_reenters_loses_no_ray_and_matches_pt() {
    check("nasa_lox_post/lox_post_tets_velmag.off.gz", true);
}

#[test]
fn post_vtk_ray_cast_loses_no_ray_and_matches_pt() {
    check("vtk_post_tets/post.vtk", false);
}
