//! End-to-end tests of the `volux` binary: the demo, rendering of the shared datasets, JSON
//! output, and clear one-line errors with no output file on bad input.
use std::path::Path;

mod common;
use common::{coverage, png_pixels, volux};
use volux_testkit::data::shared;

/// Decodes an 8-bit RGB(A) PNG and returns (width, height, fraction of pixels that are not
/// the background colour of the top-left corner, mean luminance of those).
fn png_stats(path: &Path) -> (u32, u32, f64) {
    let (w, h, px) = png_pixels(path);
    (w, h, coverage(&px))
}

#[test]
fn demo_writes_a_non_blank_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = volux(&["demo"], dir.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("demo.png"), "says where it wrote: {stdout}");
    let (w, h, covered) = png_stats(&dir.path().join("demo.png"));
    assert_eq!((w, h), (512, 512));
    assert!(covered > 0.2, "demo covers {covered}");
}

#[test]
fn generate_info_render_round() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = volux(
        &["generate", "shepp-logan", "--size", "48", "-o", "sl.raw"],
        d,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = volux(&["info", "--json", "sl.raw"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["dims"], serde_json::json!([48, 48, 48]));
    assert_eq!(v["dtype"], "float32");
    assert_eq!(v["range"][1].as_f64().unwrap(), 1.0);
    let out = volux(
        &[
            "render",
            "sl.raw",
            "-o",
            "sl.png",
            "--size",
            "96x64",
            "--stats",
            "--json",
            "--tf",
            "grayscale",
        ],
        d,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in ["ms", "rays", "samples", "samples_per_s"] {
        assert!(s[k].as_f64().unwrap() > 0.0, "{k}");
    }
    let (w, h, covered) = png_stats(&d.join("sl.png"));
    assert_eq!((w, h), (96, 64));
    assert!(covered > 0.05, "the phantom shows: {covered}");
    let out = volux(&["generate", "torus", "--size", "24", "-o", "t.vtet"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = volux(&["info", "--json", "t.vtet"], d);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["tets"].as_u64().unwrap() > 1000);
    assert_eq!(v["validation"]["degenerate"], 0);
}

#[test]
fn bad_input_gives_one_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("junk.bin"), b"\x00\x01garbage").unwrap();
    std::fs::write(d.join("t.raw"), [0u8; 10]).unwrap();
    std::fs::write(
        d.join("t.raw.json"),
        r#"{"dims_xyz": [4, 4, 4], "dtype": "uint8", "spacing": [1, 1, 1]}"#,
    )
    .unwrap();
    let cases: [&[&str]; 6] = [
        &["render", "missing.raw", "-o", "o.png"],
        &["render", "junk.bin", "-o", "o.png"],
        &["render", "t.raw", "-o", "o.png"],
        &["info", "t.raw"],
        &["generate", "nonsense", "-o", "o.raw"],
        &["render", "t.raw", "-o", "o.png", "--size", "0x10"],
    ];
    for args in cases {
        let out = volux(args, d);
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            err.trim().lines().count(),
            1,
            "{args:?}: one line, got {err}"
        );
        assert!(err.starts_with("volux: error:"), "{err}");
        assert!(!d.join("o.png").exists() && !d.join("o.raw").exists());
    }
}

fn render_shared(rel: &str, extra: &[&str], min_cover: f64) {
    let Some(p) = shared(rel) else { return };
    let dir = tempfile::tempdir().unwrap();
    let out_png = dir.path().join("r.png");
    let mut args = vec![
        "render",
        p.to_str().unwrap(),
        "-o",
        out_png.to_str().unwrap(),
        "--size",
        "128x128",
    ];
    args.extend_from_slice(extra);
    let out = volux(&args, dir.path());
    assert!(
        out.status.success(),
        "{rel}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, _, covered) = png_stats(&out_png);
    assert!(
        covered > min_cover,
        "{rel}: only {covered} of the image shows data"
    );
}

#[test]
fn renders_the_shared_ct_head() {
    render_shared(
        "invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz",
        &[],
        0.15,
    );
    render_shared(
        "invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz",
        &["--tf", "ct-bone"],
        0.1,
    );
}

#[test]
fn renders_the_shared_mri_head() {
    render_shared(
        "niivue_chris_t1/chris_t1_188x256x190_uint8.raw.gz",
        &[],
        0.15,
    );
}

#[test]
fn renders_the_blunt_fin_tets() {
    render_shared(
        "nasa_blunt_fin/blunt_fin_tets_density.off.gz",
        &["--elevation", "30", "--azimuth", "40"],
        0.1,
    );
}

#[test]
fn compare_reports_differences_and_rejects_mismatched_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let render = |name: &str, size: &str, extra: &[&str]| {
        let mut args = vec!["render", "t.vtet", "--size", size, "-o", name];
        args.extend_from_slice(extra);
        let out = volux(&args, d);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    assert!(
        volux(&["generate", "torus", "--size", "16", "-o", "t.vtet"], d)
            .status
            .success()
    );
    render("a.png", "48x40", &[]);
    render("b.png", "48x40", &["--opacity-scale", "2"]);
    let same = volux(&["compare", "a.png", "a.png", "--json"], d);
    let v: serde_json::Value = serde_json::from_slice(&same.stdout).unwrap();
    assert_eq!(v["rmse"].as_f64(), Some(0.0));
    assert_eq!(v["pct_over"].as_f64(), Some(0.0));
    let diff = volux(
        &["compare", "a.png", "b.png", "--json", "--diff", "d.png"],
        d,
    );
    assert!(diff.status.success());
    let v: serde_json::Value = serde_json::from_slice(&diff.stdout).unwrap();
    assert!(v["rmse"].as_f64().unwrap() > 0.0);
    assert!(v["max_error"].as_f64().unwrap() > 0.01);
    assert!(v["pct_over"].as_f64().unwrap() > 1.0);
    assert!(d.join("d.png").exists());
    render("c.png", "40x40", &[]);
    let bad = volux(&["compare", "a.png", "c.png"], d);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("differ in size"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one readable line: {err}");
}

/// The VOI suite cuts the box and a polyhedron of at least 578 vertices and renders a grid with
/// and without five planes; its JSON row names every figure.
#[test]
fn bench_voi_suite_reports_cuts_and_clipped_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = volux(
        &[
            "bench",
            "--suite",
            "voi",
            "--frames",
            "3",
            "--grid-size",
            "24",
            "--json",
        ],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let row = &rows[0];
    assert_eq!(row["suite"], "voi");
    assert!(row["many_vertices"].as_u64().unwrap() >= 578);
    for key in ["cut_us_8", "cut_us_many", "ms", "ms_five_planes"] {
        let v = row[key].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v > 0.0, "{key}: {v}");
    }
}

/// A NIfTI-1 `.nii` of int16 `dims` (x, y, z, t) with `pixdim` (x, y, z, t), `xyzt_units`
/// and an sform (`srow` rows), holding `data` (already little-endian).
fn nifti1(dims: [i16; 4], pixdim: [f32; 4], xyzt: u8, srow: [[f32; 4]; 3], data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let mut put = |at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(0, &348i32.to_le_bytes());
    let dim0: i16 = if dims[3] > 1 { 4 } else { 3 };
    for (i, d) in [dim0, dims[0], dims[1], dims[2], dims[3], 1, 1, 1]
        .iter()
        .enumerate()
    {
        put(40 + 2 * i, &d.to_le_bytes());
    }
    put(70, &4i16.to_le_bytes());
    put(72, &16i16.to_le_bytes());
    for (i, p) in [1.0f32, pixdim[0], pixdim[1], pixdim[2], pixdim[3]]
        .iter()
        .enumerate()
    {
        put(76 + 4 * i, &p.to_le_bytes());
    }
    put(108, &352f32.to_le_bytes());
    put(123, &[xyzt]);
    put(254, &1i16.to_le_bytes());
    for (r, row) in srow.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(280 + 16 * r + 4 * c, &v.to_le_bytes());
        }
    }
    put(344, b"n+1\0");
    h.extend_from_slice(data);
    h
}

/// `volux info` lists a 4-D NIfTI's time axis as the header gives it (4 volumes, TR 2.5 s in
/// `xyzt_units`), and `volux convert --timepoint 2` writes the third volume; a timepoint past
/// the series is one line and no output.
#[test]
fn info_and_convert_a_nifti_time_series() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let volume = |t: i16| -> Vec<i16> { (0..24).map(|i| 100 * t - i).collect() };
    let data: Vec<u8> = (0..4)
        .flat_map(|t| volume(t).into_iter().flat_map(i16::to_le_bytes))
        .collect();
    let srow = [
        [2.0, 0.0, 0.0, -3.0],
        [0.0, 2.0, 0.0, 4.0],
        [0.0, 0.0, 3.0, 5.0],
    ];
    let bytes = nifti1([4, 3, 2, 4], [2.0, 2.0, 3.0, 2.5], 2 | 8, srow, &data);
    std::fs::write(d.join("fmri.nii"), bytes).unwrap();
    let out = volux(&["info", "fmri.nii"], d);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("volumes         time: 4 volumes (timepoint 0 read), step 2.5 s"),
        "{text}"
    );
    let out = volux(&["info", "--json", "--timepoint", "3", "fmri.nii"], d);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v["volumes"][0]["text"],
        "time: 4 volumes (timepoint 3 read), step 2.5 s"
    );
    let out = volux(&["convert", "--timepoint", "2", "fmri.nii", "t2.nrrd"], d);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = volux_io::nrrd::read(&d.join("t2.nrrd"), Default::default()).unwrap();
    let got: Vec<f32> = (0..g.len()).map(|i| g.samples().get_f32(i)).collect();
    let want: Vec<f32> = volume(2).iter().map(|&v| f32::from(v)).collect();
    assert_eq!(got, want);
    assert_eq!(g.dims(), [4, 3, 2]);
    let out = volux(&["convert", "--timepoint", "4", "fmri.nii", "t4.nrrd"], d);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("timepoint 4 does not exist: the file holds 4 (0 to 3)"),
        "{err}"
    );
    assert_eq!(
        err.lines().filter(|l| !l.starts_with("note:")).count(),
        1,
        "{err}"
    );
    assert!(!d.join("t4.nrrd").exists());
}

/// An oblique NIfTI (an sform rotated about two axes, anisotropic voxels) converted to raw +
/// JSON and to NRRD keeps its geometry: the same spacing, origin and direction when read back.
#[test]
fn oblique_nifti_keeps_its_geometry_through_raw_and_nrrd() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b) = (30f32.to_radians(), 20f32.to_radians());
    // R = Rz(a) Rx(b), columns scaled by the spacing (0.9, 1.1, 2.5).
    let r = [
        [a.cos(), -a.sin() * b.cos(), a.sin() * b.sin()],
        [a.sin(), a.cos() * b.cos(), -a.cos() * b.sin()],
        [0.0, b.sin(), b.cos()],
    ];
    let sp = [0.9f32, 1.1, 2.5];
    let t = [10.5f32, -20.0, 30.25];
    let srow: [[f32; 4]; 3] =
        std::array::from_fn(|i| [r[i][0] * sp[0], r[i][1] * sp[1], r[i][2] * sp[2], t[i]]);
    let data: Vec<u8> = (0..24i16).flat_map(i16::to_le_bytes).collect();
    let nii = nifti1([4, 3, 2, 1], [0.9, 1.1, 2.5, 0.0], 2, srow, &data);
    std::fs::write(d.join("obl.nii.gz"), volux_testkit::mutate::gzip(&nii)).unwrap();
    let load = |name: &str| match volux_io::load(&d.join(name), &Default::default()).unwrap() {
        (volux_io::Dataset::Grid(g), _) => g,
        _ => panic!("a grid"),
    };
    let src = load("obl.nii.gz");
    assert!(!src.is_axis_aligned());
    for out_name in ["obl.raw", "obl.nrrd"] {
        let out = volux(&["convert", "obl.nii.gz", out_name], d);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let back = load(out_name);
        assert_eq!(back.dims(), src.dims());
        let close = |x: glam::DVec3, y: glam::DVec3| (x - y).abs().max_element() < 1e-9;
        assert!(close(back.spacing(), src.spacing()), "{out_name} spacing");
        assert!(close(back.origin(), src.origin()), "{out_name} origin");
        for c in 0..3 {
            assert!(
                close(back.direction().col(c), src.direction().col(c)),
                "{out_name} direction {:?} vs {:?}",
                back.direction(),
                src.direction()
            );
        }
        assert_eq!(back.position(3, 2, 1), src.position(3, 2, 1));
    }
}
