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
    let bytes =
        volux_testkit::nifti::nifti1([4, 3, 2, 4], [2.0, 2.0, 3.0, 2.5], 2 | 8, srow, &data);
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
    let nii = volux_testkit::nifti::nifti1([4, 3, 2, 1], [0.9, 1.1, 2.5, 0.0], 2, srow, &data);
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

/// A head as nibabel writes it (RAS sform, i towards the patient's right) with a red marker
/// on the patient's left: `--view left` shows it, `--view right` hides it behind the head,
/// and the radiological `--view inferior` puts it on the image's right (patient's left on
/// the viewer's right, anterior up); `--up` turns a view about its direction.
#[test]
fn named_views_show_the_patients_named_side() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    volux_testkit::nifti::write_head_with_left_marker(&d.join("head.nii"));
    std::fs::write(d.join("marker.json"), volux_testkit::nifti::MARKER_TF).unwrap();
    // The head (0.1 of the range) is opaque grey, the marker (1.0) opaque red, and the
    // values between them, where the marker meets the air, clear.
    // Red pixels of a view: (count, mean column / width).
    let red = |view: &[&str]| {
        let name: String = view
            .concat()
            .chars()
            .filter(char::is_ascii_alphanumeric)
            .collect();
        let out = format!("v{name}.png");
        let mut args = vec![
            "render",
            "head.nii",
            "--tf",
            "marker.json",
            "--size",
            "64x64",
        ];
        args.extend_from_slice(view);
        args.extend_from_slice(&["-o", &out]);
        let run = volux(&args, d);
        assert!(run.status.success(), "{view:?}: {}", stderr(&run));
        let (w, _, px) = png_pixels(&d.join(&out));
        let cols: Vec<f64> = px
            .iter()
            .enumerate()
            .filter(|(_, p)| p[0] > 150 && p[1] < 80)
            .map(|(i, _)| (i as u32 % w) as f64 / w as f64)
            .collect();
        (
            cols.len(),
            cols.iter().sum::<f64>() / cols.len().max(1) as f64,
        )
    };
    let (left, _) = red(&["--view", "left"]);
    let (right, _) = red(&["--view", "right"]);
    assert!(
        left > 20 && right == 0,
        "red pixels: left {left}, right {right}"
    );
    let (count, column) = red(&["--view", "inferior"]);
    assert!(
        count > 5 && column > 0.6,
        "inferior: {count} red at column {column}"
    );
    let (count, column) = red(&["--view", "superior"]);
    assert!(
        count > 5 && column < 0.4,
        "superior: {count} red at column {column}"
    );
    // Anterior with the patient's left as up: the marker moves to the top.
    let (count, _) = red(&["--view", "anterior", "--up", "1,0,0"]);
    assert!(count > 5, "anterior, up left: {count}");
    let run = volux(
        &["render", "head.nii", "--view", "superior", "--up", "0,0,1"],
        d,
    );
    assert!(!run.status.success());
    assert!(
        stderr(&run).contains("lies along the view"),
        "{}",
        stderr(&run)
    );
    // The axis names stay for data without a patient: -x is the right view's side.
    assert_eq!(red(&["--view=-x"]).0, 0);
    assert!(red(&["--view", "+x"]).0 > 20);
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every command that prints ends quietly when its reader has gone (`| head -1`): exit 0
/// and nothing on stderr, as Unix tools do (it was a panic with exit 101).
#[test]
fn a_closed_pipe_ends_every_command_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = volux(&["generate", "sphere", "--size", "24", "-o", "s.raw"], d);
    assert!(run.status.success(), "{}", stderr(&run));
    let commands: [&[&str]; 8] = [
        &["info", "s.raw"],
        &["info", "--json", "s.raw"],
        &["tf", "show", "ct-bone"],
        &["help", "tf"],
        &["help", "camera"],
        &["help"],
        &[
            "render", "s.raw", "--size", "24x24", "--stats", "--json", "-o", "s.png",
        ],
        &[
            "measure", "s.raw", "--size", "48x48", "--point", "20,24", "--point", "28,24",
        ],
    ];
    for args in commands {
        // The reading end is closed before the command writes its first byte.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_volux"))
            .args(args)
            .current_dir(d)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .unwrap();
        assert!(
            out.status.success() && out.stderr.is_empty(),
            "{args:?}: {:?} {}",
            out.status,
            stderr(&out)
        );
    }
}
