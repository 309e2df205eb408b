//! `--tf` with transfer functions from other programs: the example ParaView preset and
//! Slicer `.vp` of `docs/examples` render like a Volux JSON written here from VTK's formulas
//! (opacity linear per unit distance, display colours linear then decoded from sRGB),
//! sampled densely, within 1/255 per channel.
use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{png_pixels, volux};

/// The examples' nodes: `[x, r, g, b]` display colours and `[x, opacity]`.
const COLOR: [[f64; 4]; 3] = [
    [0.2, 0.1, 0.05, 0.3],
    [0.5, 0.9, 0.4, 0.1],
    [1.0, 1.0, 1.0, 0.8],
];
const OPACITY: [[f64; 2]; 3] = [[0.2, 0.0], [0.6, 0.3], [1.0, 0.9]];

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../docs/examples")
        .join(name)
}

/// Linear interpolation of `[x, v...]` rows at `x` (VTK's, clamped at the ends).
fn lerp<const N: usize>(rows: &[[f64; N]], x: f64) -> [f64; N] {
    let i = rows
        .iter()
        .position(|r| r[0] >= x)
        .unwrap_or(rows.len() - 1);
    if i == 0 || x >= rows[rows.len() - 1][0] {
        return rows[i];
    }
    let (a, b) = (rows[i - 1], rows[i]);
    let t = (x - a[0]) / (b[0] - a[0]);
    std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
}

fn srgb_decode(x: f64) -> f64 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// The native equivalent: VTK's curves sampled at 2001 positions over 0.2..1.
fn native_json() -> String {
    let xs: Vec<f64> = (0..=2000)
        .map(|i| 0.2 + 0.8 * f64::from(i) / 2000.0)
        .collect();
    let color: Vec<String> = xs
        .iter()
        .map(|&x| {
            let c = lerp(&COLOR, x);
            let (r, g, b) = (srgb_decode(c[1]), srgb_decode(c[2]), srgb_decode(c[3]));
            format!("[{x}, {r}, {g}, {b}]")
        })
        .collect();
    let opacity: Vec<String> = xs
        .iter()
        .map(|&x| format!("[{x}, {}]", lerp(&OPACITY, x)[1]))
        .collect();
    format!(
        r#"{{"color": [{}], "opacity": [{}], "opacity_step": 1, "unit_length": 1}}"#,
        color.join(", "),
        opacity.join(", ")
    )
}

fn render(tf: &Path, out: &str, dir: &Path) -> Output {
    let tf = tf.to_str().unwrap();
    let args = [
        "render", "grid.raw", "--tf", tf, "--size", "64x64", "-o", out,
    ];
    let run = volux(&args, dir);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{args:?}: {err}");
    run
}

/// The largest channel difference of two PNGs.
fn max_diff(a: &Path, b: &Path) -> u8 {
    let (pa, pb) = (png_pixels(a).2, png_pixels(b).2);
    assert_eq!(pa.len(), pb.len());
    let lit = pb
        .iter()
        .filter(|p| p.iter().take(3).any(|&c| c > 8))
        .count();
    assert!(
        lit > 100,
        "the reference render shows nothing ({lit} lit pixels)"
    );
    pa.iter()
        .zip(&pb)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| x.abs_diff(*y)))
        .max()
        .unwrap_or(0)
}

#[test]
fn paraview_and_slicer_files_render_like_the_native_equivalent() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gen = volux(
        &["generate", "shepp-logan", "--size", "32", "-o", "grid.raw"],
        d,
    );
    assert!(
        gen.status.success(),
        "{}",
        String::from_utf8_lossy(&gen.stderr)
    );
    std::fs::write(d.join("native.json"), native_json()).unwrap();
    render(&d.join("native.json"), "native.png", d);
    let pv = render(&example("paraview-preset.json"), "paraview.png", d);
    let pv_err = String::from_utf8_lossy(&pv.stderr);
    assert!(
        pv_err.contains("warning: ") && pv_err.contains("NanColor"),
        "{pv_err}"
    );
    let vp = render(&example("slicer-volume-property.vp"), "slicer.png", d);
    assert!(!String::from_utf8_lossy(&vp.stderr).contains("warning"));
    for name in ["paraview.png", "slicer.png"] {
        let diff = max_diff(&d.join(name), &d.join("native.png"));
        assert!(
            diff <= 1,
            "{name}: a channel differs by {diff}/255 from the native render"
        );
    }
}

#[test]
fn tf_show_prints_an_imported_file_as_volux_json() {
    let dir = tempfile::tempdir().unwrap();
    let vp = example("slicer-volume-property.vp");
    let run = volux(&["tf", "show", vp.to_str().unwrap()], dir.path());
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        text.contains("\"opacity\"") && text.contains("[0.6, 0.3]"),
        "{text}"
    );
}

#[test]
fn a_bad_imported_file_is_one_error_line_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("bad.vp"), "1\n0\n1\n0\n0\n1\n4 0 0 1\n").unwrap();
    std::fs::write(
        d.join("bad.json"),
        r#"[{"ColorSpace": "Lab/CIEDE2000", "RGBPoints": [0, 0, 0, 0]}]"#,
    )
    .unwrap();
    for (file, want) in [
        (
            "bad.vp",
            "line 8 (gradient opacity): missing: the file ends after 7 lines of 9",
        ),
        ("bad.json", "ColorSpace: \"Lab/CIEDE2000\" is not supported"),
    ] {
        let run = volux(&["tf", "show", file], d);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{file}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(
            err.starts_with("volux: error: ") && err.contains(want),
            "{err}"
        );
    }
}
