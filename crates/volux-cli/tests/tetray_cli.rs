//! End-to-end tests of `volux render MESH --method raycast` (issue 5): each integrator
//! (exact, ψ, adaptive Simpson with its error map), isosurfaces, MIP and the `--stats --json`
//! figures, on a generated torus (a non-convex mesh: rays re-enter it).
use std::path::Path;
use std::process::Output;

mod common;
use common::{coverage, png_pixels, volux};

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Renders the torus with `extra` options and `--stats --json`; returns the figures and the
/// image's pixels.
fn render(dir: &Path, name: &str, extra: &[&str]) -> (serde_json::Value, Vec<Vec<u8>>) {
    let png = format!("{name}.png");
    let mut args = vec![
        "render", "t.vtet", "--method", "raycast", "--size", "48x40", "--stats", "--json", "-o",
        &png,
    ];
    args.extend_from_slice(extra);
    let out = volux(&args, dir);
    ok(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{name}: {e}: {}", String::from_utf8_lossy(&out.stdout)));
    let (w, h, px) = png_pixels(&dir.join(&png));
    assert_eq!((w, h), (48, 40), "{name}");
    (v, px)
}

#[test]
fn raycast_renders_a_torus_with_every_integrator_isosurfaces_and_mip() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    ok(&volux(
        &["generate", "torus", "--size", "16", "-o", "t.vtet"],
        d,
    ));
    let mut images = Vec::new();
    for integrator in ["exact", "psi", "adaptive-simpson"] {
        let (v, px) = render(d, integrator, &["--integrator", integrator]);
        assert_eq!(v["method"], "raycast");
        assert_eq!(v["integrator"], integrator);
        assert_eq!(v["rays"], 48 * 40);
        assert!(v["segments"].as_u64().unwrap() > 0, "{v}");
        assert!(v["reentries"].as_u64().unwrap() > 0, "a torus: {v}");
        assert_eq!(v["abandoned"], 0);
        assert_eq!(v["rays_over_tolerance"], 0, "{v}");
        if integrator == "adaptive-simpson" {
            assert!(v["samples"].as_u64().unwrap() > v["segments"].as_u64().unwrap());
            assert!(v["max_error"].as_f64().unwrap() > 0.0, "{v}");
            assert!(v["max_error"].as_f64().unwrap() < 0.01, "{v}");
        } else {
            assert_eq!(v["samples"], 2 * v["segments"].as_u64().unwrap(), "{v}");
            assert_eq!(v["max_error"].as_f64().unwrap(), 0.0, "{v}");
        }
        let cov = coverage(&px);
        assert!(cov > 0.1, "{integrator}: coverage {cov}");
        images.push(px);
    }
    // The three integrators agree to a few levels of 8 bits.
    for (i, img) in images.iter().enumerate().skip(1) {
        let worst = img
            .iter()
            .zip(&images[0])
            .flat_map(|(p, q)| p.iter().zip(q).map(|(a, b)| a.abs_diff(*b)))
            .max()
            .unwrap();
        assert!(worst <= 12, "integrator {i} differs from exact by {worst}");
    }

    // Adaptive with a tight tolerance, decoupled control and an error map.
    let (v, _) = render(
        d,
        "tight",
        &[
            "--integrator",
            "adaptive-simpson",
            "--tol",
            "1e-4",
            "--h0",
            "1",
            "--hmin",
            "0.01",
            "--hmax",
            "2",
            "--decoupled",
            "--error-map",
            "err.png",
        ],
    );
    assert!(v["max_error"].as_f64().unwrap() < 1e-4, "{v}");
    // The heat map is the image's size plus its legend strip; no ray is over the tolerance
    // (magenta), though the legend shows magenta in its "over" block.
    let (w, h, err) = png_pixels(&d.join("err.png"));
    assert_eq!(w, 48);
    assert!(h > 40, "a legend strip below the map");
    assert!(err[..48 * 40]
        .iter()
        .all(|p| !(p[0] == 255 && p[1] == 0 && p[2] == 255)));
    assert!(err[48 * 40..]
        .iter()
        .any(|p| p[0] == 255 && p[1] == 0 && p[2] == 255));

    // Isosurfaces (lit) change the image; several are counted.
    let (v, iso) = render(
        d,
        "iso",
        &[
            "--integrator",
            "exact",
            "--iso",
            "0.3:1,0.5,0.2,0.8",
            "--iso",
            "0.5:0.2,0.5,1,0.5",
            "--specular",
            "0.5",
        ],
    );
    assert_eq!(v["isosurfaces"], 2);
    let changed = iso
        .iter()
        .zip(&images[0])
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(a, b)| a.abs_diff(*b) > 8))
        .count();
    assert!(changed > 48 * 40 / 20, "isosurfaces show: {changed} pixels");
    let (v, _) = render(
        d,
        "iso_adaptive",
        &[
            "--integrator",
            "adaptive-simpson",
            "--iso",
            "0.3:1,0.5,0.2,0.8",
        ],
    );
    assert_eq!(v["isosurfaces"], 1);

    // MIP: opaque where the mesh is.
    let (v, mip) = render(d, "mip", &["--mip"]);
    assert_eq!(v["integrator"], "mip");
    assert_eq!(v["mip"], true);
    assert!(coverage(&mip) > 0.1);

    // Bad options give an error and no image.
    let out = volux(
        &[
            "render",
            "t.vtet",
            "--method",
            "raycast",
            "--integrator",
            "adaptive-simpson",
            "--tol",
            "-1",
            "-o",
            "bad.png",
        ],
        d,
    );
    assert!(!out.status.success());
    assert!(!d.join("bad.png").exists());
}
