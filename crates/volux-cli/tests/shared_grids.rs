//! Every grid dataset of `../shared/data` (raw, SLC, DICOM series and multi-frame), rendered
//! by the `volux` binary with the automatic default transfer function: the picture must show
//! the data (pixels that differ from the background) with structure in it (their luminance
//! varies), not a blank frame or a flat silhouette. The camera frames the whole grid, so a
//! small subject in a wide field of view (the TCIA series: a limb in a 500 mm field) covers
//! only about 2 % of the frame. Skips when the folder is absent.
use std::path::{Path, PathBuf};

mod common;
use common::{png_pixels, volux};
use volux_testkit::data::shared;

/// The fraction of pixels that differ from the top-left corner's colour, and the standard
/// deviation of those pixels' luminance (0-255).
fn coverage_and_contrast(path: &Path) -> (f64, f64) {
    let (_, _, px) = png_pixels(path);
    let bg = &px[0];
    let lum: Vec<f64> = px
        .iter()
        .filter(|p| p.iter().zip(bg).any(|(a, b)| a.abs_diff(*b) > 8))
        .map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]))
        .collect();
    let n = lum.len().max(1) as f64;
    let mean = lum.iter().sum::<f64>() / n;
    let var = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n;
    (lum.len() as f64 / px.len() as f64, var.sqrt())
}

/// What to hand `volux render` for each grid sidecar: the data file, or the DICOM folder.
fn grid_inputs(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for folder in std::fs::read_dir(dir).unwrap().flatten() {
        for f in std::fs::read_dir(folder.path())
            .into_iter()
            .flatten()
            .flatten()
        {
            let p = f.path();
            if p.extension().is_none_or(|e| e != "json") {
                continue;
            }
            let side: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            match side["kind"].as_str().unwrap_or("") {
                "grid" | "grid (DICOM multi-frame)" => {
                    out.push(folder.path().join(side["file"].as_str().unwrap()))
                }
                "grid (DICOM series)" => out.push(folder.path()),
                _ => {}
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

#[test]
fn every_shared_grid_renders_a_picture_with_the_default_tf() {
    let Some(dir) = shared("") else { return };
    let tmp = tempfile::tempdir().unwrap();
    let png = tmp.path().join("r.png");
    let inputs = grid_inputs(&dir);
    let mut failures = Vec::new();
    for input in &inputs {
        let out = volux(
            &[
                "render",
                input.to_str().unwrap(),
                "-q",
                "--size",
                "96x96",
                "-o",
                png.to_str().unwrap(),
            ],
            tmp.path(),
        );
        let name = input.strip_prefix(&dir).unwrap_or(input).display();
        if !out.status.success() {
            failures.push(format!("{name}: {}", String::from_utf8_lossy(&out.stderr)));
            continue;
        }
        let (cover, contrast) = coverage_and_contrast(&png);
        eprintln!("{name}: coverage {cover:.3}, luminance std {contrast:.1}");
        if cover < 0.01 || contrast < 4.0 {
            failures.push(format!(
                "{name}: coverage {cover:.3}, luminance std {contrast:.1}"
            ));
        }
    }
    assert!(inputs.len() >= 15, "only {} grid datasets", inputs.len());
    assert!(failures.is_empty(), "{failures:#?}");
}
