//! The mistakes a new user makes, one test per class, each asserting the message: an option
//! that does not apply to the method or data, negative numbers, a render that comes out
//! empty, a wrong output extension, a JSON file of the wrong shape; and what the CLI says
//! about its outputs. Synthetic data in a temporary folder; no shared data needed.
use std::path::Path;
use std::process::Output;

mod common;
use common::volux;

/// A 32^3 Shepp-Logan phantom (values 0..1) and a small smooth tet mesh in `dir`.
fn data(dir: &Path) {
    for (kind, size, out) in [
        ("shepp-logan", "32", "grid.raw"),
        ("tets-smooth", "3000", "mesh.vtet"),
    ] {
        let run = volux(&["generate", kind, "--size", size, "-o", out], dir);
        assert!(run.status.success(), "{}", stderr(&run));
    }
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `args` in `dir` and returns the error line, asserting a failure with one line on
/// stderr and no output file.
fn refused(args: &[&str], dir: &Path) -> String {
    let strays = ["out.png", "x.png", "x.jpg"];
    let before: Vec<bool> = strays.iter().map(|s| dir.join(s).exists()).collect();
    let out = volux(args, dir);
    let err = stderr(&out);
    assert!(!out.status.success(), "{args:?} should fail: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{args:?}: one line: {err}");
    assert!(err.starts_with("volux: error: "), "{args:?}: {err}");
    for (stray, was) in strays.iter().zip(before) {
        assert!(was || !dir.join(stray).exists(), "{args:?} left {stray}");
    }
    err
}

/// Runs `args` in `dir`, asserting success, and returns stderr.
fn accepted(args: &[&str], dir: &Path) -> String {
    let out = volux(args, dir);
    let err = stderr(&out);
    assert!(out.status.success(), "{args:?}: {err}");
    err
}

#[test]
fn options_that_do_not_apply_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    let cases: &[(&[&str], &str)] = &[
        (&["mesh.vtet", "--mip"], "no maximum intensity projection"),
        (&["mesh.vtet", "--shade"], "does not shade the volume"),
        (
            &["mesh.vtet", "--step", "0.3"],
            "--step does not apply to Projected Tetrahedra",
        ),
        (
            &["mesh.vtet", "--reconstruction", "b-spline"],
            "--reconstruction does not apply",
        ),
        (
            &["mesh.vtet", "--integrator", "simpson"],
            "--integrator does not apply to Projected",
        ),
        (
            &[
                "mesh.vtet",
                "--method",
                "raycast",
                "--integrator",
                "simpson",
            ],
            "exact, psi or adaptive-simpson",
        ),
        (
            &["mesh.vtet", "--method", "raycast", "--sort", "exact"],
            "--sort does not apply",
        ),
        (&["mesh.vtet", "--as-tets"], "tetrahedral mesh already"),
        (
            &["grid.raw", "--sort", "exact"],
            "orders the cells of Projected Tetrahedra",
        ),
        (
            &["grid.raw", "--color", "exact"],
            "--color does not apply to grid ray casting",
        ),
        (
            &["grid.raw", "--tol", "0.1"],
            "--integrator adaptive-simpson",
        ),
        (
            &["grid.raw", "--error-map", "e.png"],
            "--integrator adaptive-simpson",
        ),
        (
            &["grid.raw", "--integrator", "reference", "--step", "1"],
            "chooses its own steps",
        ),
        (
            &["grid.raw", "--as-tets", "--method", "raycast"],
            "--method pt",
        ),
        (&["grid.raw", "--resample", "64"], "--method resample"),
        (&["grid.raw", "--json"], "add --stats"),
        (&["grid.raw", "--ambient", "0.5"], "this render has neither"),
        (
            &["grid.raw", "--camera", "cam.json", "--azimuth", "30"],
            "--camera FILE replaces",
        ),
        (
            &["grid.raw", "--view", "top", "--up", "0,0,1"],
            "lies along the view",
        ),
        (
            &["grid.raw", "--q-variable", "density"],
            "applies to PLOT3D files",
        ),
        (
            &["grid.raw", "--mip", "--shade"],
            "unlit and without isosurfaces",
        ),
        (
            &["grid.raw", "--mip", "--opacity-scale", "2"],
            "with no opacity",
        ),
        (
            &["grid.raw", "--mip", "--iso", "0.5:1,1,1,1"],
            "unlit and without isosurfaces",
        ),
        (
            &["grid.raw", "--clip-plane", "0,0,0,1"],
            "must be finite and non-zero",
        ),
        (
            &["grid.raw", "--clip-plane", "1,2,3"],
            "expected four numbers",
        ),
        (
            &[
                "mesh.vtet",
                "--method",
                "raycast",
                "--mip",
                "--error-map",
                "e.png",
            ],
            "--mip) integrates nothing",
        ),
    ];
    std::fs::write(d.join("cam.json"), r#"{"azimuth": 10}"#).unwrap();
    for (args, message) in cases {
        let mut full = vec!["render"];
        full.extend_from_slice(args);
        let err = refused(&full, d);
        assert!(
            err.contains(message),
            "{args:?}: expected '{message}' in: {err}"
        );
    }
    // The same options where they apply are accepted.
    accepted(
        &[
            "render", "grid.raw", "--mip", "--size", "32x32", "-o", "a.png",
        ],
        d,
    );
    accepted(
        &[
            "render",
            "grid.raw",
            "--clip-plane",
            "-1,0,0,0.5",
            "--size",
            "32x32",
            "-o",
            "c.png",
        ],
        d,
    );
    // PT culls the cells wholly outside a plane, and says so.
    let err = accepted(
        &[
            "render",
            "mesh.vtet",
            "--clip-plane",
            "1,0,0,-0.5",
            "--stats",
            "--size",
            "32x32",
            "-o",
            "m.png",
        ],
        d,
    );
    assert!(err.contains("culled by clip planes"), "{err}");
    // Every mesh method draws clip planes (PT by default).
    for method in ["pt", "raycast", "resample"] {
        accepted(
            &[
                "render",
                "mesh.vtet",
                "--method",
                method,
                "--clip-plane",
                "1,0,0,-0.5",
                "--size",
                "32x32",
                "-o",
                "m.png",
            ],
            d,
        );
    }
    accepted(
        &[
            "render",
            "mesh.vtet",
            "--sort",
            "exact",
            "--size",
            "32x32",
            "-o",
            "b.png",
        ],
        d,
    );
    accepted(
        &[
            "render",
            "grid.raw",
            "--integrator",
            "adaptive-simpson",
            "--tol",
            "0.05",
            "--size",
            "32x32",
            "-o",
            "c.png",
        ],
        d,
    );
}

#[test]
fn bench_options_that_change_nothing_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (args, message) in [
        (
            &["bench", "--quick", "--frames", "5"][..],
            "drop --quick or --frames",
        ),
        (
            &["bench", "--suite", "targets", "--quick"],
            "does not apply to --suite targets",
        ),
        (
            &["bench", "--suite", "pt", "--grid-size", "64"],
            "the mesh suites have none",
        ),
        (
            &["bench", "--suite", "tetray", "--only", "riemann"],
            "--only selects cases",
        ),
        (&["bench", "--frames", "0"], "at least one frame"),
        (
            &["bench", "--suite", "voi", "--quick"],
            "does not apply to --suite voi",
        ),
        // The CI build has no GPU backend: the suite says how to get it.
        (&["bench", "--suite", "gpu", "--quick"], "--features gpu"),
    ] {
        let err = refused(args, d);
        assert!(
            err.contains(message),
            "{args:?}: expected '{message}' in: {err}"
        );
    }
    // (The suite says which shared datasets it skips before the error.)
    let out = volux(
        &[
            "bench",
            "--suite",
            "grid",
            "--only",
            "no such case",
            "--grid-size",
            "8",
        ],
        d,
    );
    assert!(!out.status.success());
    let err = stderr(&out);
    let last = err.trim().lines().last().unwrap_or_default();
    assert!(last.contains("matches no grid case"), "{err}");
}

#[test]
fn negative_numbers_are_values_not_options() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    let size = ["--size", "32x32"];
    // Each is parsed as a value; the ones out of range get the library's reason, not clap's
    // "unexpected argument", with the library's setting named by its flag.
    let err = refused(&["render", "grid.raw", "--opacity-scale", "-1"], d);
    assert!(err.contains("--opacity-scale -1 must be"), "{err}");
    let err = refused(&["render", "grid.raw", "--step", "-1"], d);
    assert!(err.contains("--step -1 must be"), "{err}");
    let mut args = vec!["render", "grid.raw", "--iso", "-0.5:1,1,1,1", "-o", "n.png"];
    args.extend_from_slice(&size);
    let err = accepted(&args, d);
    assert!(
        err.contains("isosurface at -0.5 lies outside the data range"),
        "{err}"
    );
    let mut args = vec![
        "render",
        "grid.raw",
        "--azimuth",
        "-30",
        "--elevation",
        "-20",
        "--shade",
        "--light",
        "-1,0,0",
        "--up",
        "0,0,-1",
        "-o",
        "m.png",
    ];
    args.extend_from_slice(&size);
    accepted(&args, d);
}

#[test]
fn renders_that_show_nothing_warn_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    std::fs::write(
        d.join("far.json"),
        r#"{"color": [[0, 1, 1, 1]], "extinction": [[100, 0], [200, 1], [300, 0]]}"#,
    )
    .unwrap();
    let err = accepted(
        &["render", "grid.raw", "--tf", "far.json", "--size", "16x16"],
        d,
    );
    assert!(
        err.contains("warning: the image will be empty: the transfer function is transparent")
            && err.contains("(its extinction is non-zero over [100, 300])"),
        "{err}"
    );
    // A constant field.
    let bytes: Vec<u8> = std::iter::repeat_n(2.5f32.to_le_bytes(), 64)
        .flatten()
        .collect();
    std::fs::write(d.join("flat.raw"), bytes).unwrap();
    std::fs::write(
        d.join("flat.raw.json"),
        r#"{"dims_xyz": [4, 4, 4], "dtype": "float32", "endianness": "little"}"#,
    )
    .unwrap();
    let err = accepted(
        &["render", "flat.raw", "--size", "16x16", "-o", "flat.png"],
        d,
    );
    assert!(
        err.contains("every value is 2.5 (a constant field)"),
        "{err}"
    );
}

#[test]
fn outputs_must_be_png_and_are_always_said() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    let err = refused(&["render", "grid.raw", "-o", "x.jpg"], d);
    assert!(
        err.contains("Volux writes PNG images; name the file .png, not .jpg"),
        "{err}"
    );
    let err = refused(
        &[
            "render",
            "grid.raw",
            "--integrator",
            "adaptive-simpson",
            "--error-map",
            "e.bmp",
        ],
        d,
    );
    assert!(err.contains("--error-map e.bmp"), "{err}");
    // The default output is named, and replacing it is said.
    let first = accepted(&["render", "grid.raw", "--size", "16x16"], d);
    assert!(first.trim_end().ends_with("wrote out.png"), "{first}");
    let again = accepted(&["render", "grid.raw", "--size", "16x16"], d);
    assert!(
        again.contains("wrote out.png (replaced the file there"),
        "{again}"
    );
    // With --stats --json the JSON names the file too.
    let out = volux(
        &[
            "render", "grid.raw", "--size", "16x16", "--stats", "--json", "-o", "s.png",
        ],
        d,
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["output"], "s.png");
    assert!(stderr(&out).contains("wrote s.png"));
    // compare --diff: a heat map with its legend, its scale said.
    let out = volux(&["compare", "out.png", "s.png", "--diff", "d.png"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("colour scale: black 0 to yellow"),
        "{}",
        stderr(&out)
    );
    let (w, h, _) = common::png_pixels(&d.join("d.png"));
    assert_eq!(w, 16);
    assert!(h > 16, "the legend strip is below the image");
    let err = refused(&["compare", "out.png", "s.png", "--diff", "x.jpg"], d);
    assert!(err.contains("--diff x.jpg"), "{err}");
    // convert writes what the README lists, sizes said.
    let err = accepted(&["convert", "grid.raw", "g.raw.gz"], d);
    assert!(
        err.contains("wrote g.raw.gz (") && err.contains("KiB)"),
        "{err}"
    );
    accepted(&["info", "g.raw.gz"], d);
}

#[test]
fn json_shape_errors_name_the_field_and_the_shape() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    std::fs::write(d.join("five.json"), r#"{"color": [[0, 1, 1, 1, 1]]}"#).unwrap();
    let err = refused(&["render", "grid.raw", "--tf", "five.json"], d);
    assert!(
        err.contains("color[0]: expected [value, r, g, b] (4 numbers), got 5 numbers"),
        "{err}"
    );
    std::fs::write(d.join("eye.json"), r#"{"eye": [1, 2]}"#).unwrap();
    let err = refused(&["render", "grid.raw", "--camera", "eye.json"], d);
    assert!(
        err.contains("eye: expected [x, y, z] (3 numbers), got 2 numbers"),
        "{err}"
    );
}

#[test]
fn formats_are_documented_and_presets_print_as_json_that_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    for (topic, needle) in [("tf", "opacity_step"), ("camera", "fov_y_deg")] {
        let out = volux(&["help", topic], d);
        assert!(out.status.success());
        assert!(
            String::from_utf8_lossy(&out.stdout).contains(needle),
            "help {topic}"
        );
    }
    let out = volux(&["tf", "show", "ct-skin"], d);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::write(d.join("skin.json"), &out.stdout).unwrap();
    let tf: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(tf["color"][0], serde_json::json!([-600, 0.6, 0.35, 0.25]));
    let err = refused(&["tf", "show", "auto"], d);
    assert!(err.contains("--data FILE"), "{err}");
    accepted(&["tf", "show", "auto", "--data", "grid.raw"], d);
    // Layers: a preset under a weighted file.
    accepted(
        &[
            "render",
            "grid.raw",
            "--tf",
            "grayscale",
            "--tf",
            "skin.json:0.5",
            "--size",
            "16x16",
            "-o",
            "l.png",
        ],
        d,
    );
    let err = refused(&["render", "grid.raw", "--tf", "grayscale:-1"], d);
    assert!(err.contains("weight -1 must be >= 0"), "{err}");
}

/// `s.raw`, the 48^3 sphere distance field (a box from 0 to 47 on each axis), and
/// `core.json`, a TF showing only the top fifth of its range: a ball of radius about 8
/// around (23.5, 23.5, 23.5).
fn ball_and_core_tf(d: &Path) {
    let run = volux(&["generate", "sphere", "--size", "48", "-o", "s.raw"], d);
    assert!(run.status.success(), "{}", stderr(&run));
    std::fs::write(
        d.join("core.json"),
        r#"{"space": "normalized", "color": [[0, 1, 1, 1]],
            "extinction": [[0.78, 0], [0.8, 2], [1, 2]]}"#,
    )
    .unwrap();
}

#[test]
fn the_camera_frames_what_the_tf_shows_and_named_views_turn_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ball_and_core_tf(d);
    let covered = |frame: &str, view: &str| {
        let out = format!("{frame}-{view}.png");
        accepted(
            &[
                "render",
                "s.raw",
                "--tf",
                "core.json",
                "--size",
                "48x48",
                "--frame",
                frame,
                "--view",
                view,
                "-o",
                &out,
            ],
            d,
        );
        let (_, _, px) = common::png_pixels(&d.join(&out));
        common::coverage(&px)
    };
    let (visible, all) = (covered("visible", "front"), covered("all", "front"));
    assert!(
        visible > 2.0 * all && visible < 0.95,
        "framed on the ball: {visible} of the image, on the box: {all}"
    );
    // The ball looks alike from every side; framing keeps it the same size.
    for view in ["back", "left", "right", "top", "bottom"] {
        let c = covered("visible", view);
        assert!((c - visible).abs() < 0.05, "{view}: {c} vs front {visible}");
    }
}

/// A build without the `gpu` feature refuses `--backend gpu` and `info --gpu` with how to
/// build it, and renders `--backend auto` and `cpu` on the CPU without a word about the GPU.
#[cfg(not(feature = "gpu"))]
#[test]
fn the_gpu_backend_of_a_build_without_it_is_refused_with_how_to_build_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    let err = refused(
        &[
            "render",
            "grid.raw",
            "--backend",
            "gpu",
            "--size",
            "32x32",
            "-o",
            "x.png",
        ],
        d,
    );
    assert!(err.contains("--features gpu"), "{err}");
    let out = volux(&["info", "--gpu"], d);
    assert!(!out.status.success() && stderr(&out).contains("--features gpu"));
    for backend in ["auto", "cpu"] {
        let err = accepted(
            &[
                "render",
                "grid.raw",
                "--backend",
                backend,
                "--size",
                "32x32",
                "-o",
                "x.png",
            ],
            d,
        );
        assert!(!err.contains("GPU"), "{backend}: {err}");
        assert!(d.join("x.png").exists());
    }
}

/// `--method slicing` is a GPU method: the CPU backend refuses it in one line saying to use
/// `--backend gpu`, and options it has no use for are refused.
#[test]
fn slicing_on_the_cpu_is_refused_with_the_backend_to_use() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    data(d);
    let base = [
        "render", "grid.raw", "--method", "slicing", "--size", "32x32",
    ];
    let err = refused(
        &[&base[..], &["--backend", "cpu", "-o", "x.png"]].concat(),
        d,
    );
    assert!(
        err.contains("GPU method") && err.contains("--backend gpu"),
        "{err}"
    );
    let err = refused(&[&base[..], &["--jitter", "-o", "x.png"]].concat(), d);
    assert!(err.contains("--jitter does not apply to slicing"), "{err}");
    // On `auto` only the GPU is asked: no CPU render is announced and then failed.
    for extra in [&["-o", "x.png"][..], &["--mip", "-o", "x.png"]] {
        let out = volux(&[&base[..], extra].concat(), d);
        let err = stderr(&out);
        assert!(!out.status.success(), "{extra:?}");
        assert!(
            err.lines().count() == 1 && !err.contains("on the CPU"),
            "{extra:?}: {err}"
        );
    }
}

/// A grid too large to split into tetrahedra is refused from its header, before gigabytes
/// are read: the sidecar claims 2048^3 samples and the data file holds 8 bytes, so loading
/// first would report a truncated file instead.
#[test]
fn as_tets_is_refused_from_the_header_before_the_grid_is_loaded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("huge.raw"), [0u8; 8]).unwrap();
    std::fs::write(
        d.join("huge.raw.json"),
        r#"{"dims_xyz": [2048, 2048, 2048], "dtype": "uint8", "spacing": [1, 1, 1]}"#,
    )
    .unwrap();
    let err = refused(&["render", "huge.raw", "--as-tets"], d);
    assert!(
        err.contains("the tetrahedral mesh of the grid needs"),
        "{err}"
    );
    assert!(!err.contains("truncated"), "{err}");
}

/// The centre of the box of what a PNG shows (column, row, as fractions of the image) and
/// the fraction of the image it covers.
fn shown(path: &Path) -> ([f64; 2], f64) {
    let (w, h, px) = common::png_pixels(path);
    let bg = px[0].clone();
    let (mut n, mut lo, mut hi) = (0usize, [u32::MAX; 2], [0u32; 2]);
    for (i, p) in px.iter().enumerate() {
        if p.iter().zip(&bg).any(|(a, b)| a.abs_diff(*b) > 8) {
            n += 1;
            let xy = [i as u32 % w, i as u32 / w];
            for a in 0..2 {
                lo[a] = lo[a].min(xy[a]);
                hi[a] = hi[a].max(xy[a] + 1);
            }
        }
    }
    let centre = |a: usize, size: u32| f64::from(lo[a] + hi[a]) / 2.0 / f64::from(size);
    ([centre(0, w), centre(1, h)], n as f64 / f64::from(w * h))
}

/// `--frame visible` frames what the clip planes and the mask leave: the cap of a ball that
/// is kept fills the middle of the image (it sat at one side of the ball's frame).
#[test]
fn the_camera_frames_what_the_cuts_leave() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ball_and_core_tf(d);
    let base = ["render", "s.raw", "--tf", "core.json", "--size", "64x64"];
    // Keep x >= 26: a cap of the ball, on the image's right seen from the front.
    let cut = [&base[..], &["--clip-plane", "1,0,0,-26"]].concat();
    accepted(
        &[&cut[..], &["--frame", "all", "-o", "all.png"]].concat(),
        d,
    );
    accepted(&[&cut[..], &["-o", "cut.png"]].concat(), d);
    let ([ax, _], all) = shown(&d.join("all.png"));
    let ([cx, cy], framed) = shown(&d.join("cut.png"));
    assert!(
        ax > 0.55,
        "the box's frame shows the cap right of centre: {ax}"
    );
    assert!(
        (cx - 0.5).abs() < 0.05 && (cy - 0.5).abs() < 0.05,
        "the framed cap's centre at ({cx}, {cy})"
    );
    assert!(
        framed > 1.5 * all,
        "the cap fills {framed} framed, {all} in the box"
    );
    // A mask that removes x < 26 frames the same.
    let (volux_io::Dataset::Grid(g), _) =
        volux_io::load(&d.join("s.raw"), &Default::default()).unwrap()
    else {
        panic!("a grid")
    };
    let [nx, ny, nz] = g.dims();
    let mut kept = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = g.index_to_world(glam::DVec3::new(i as f64, j as f64, k as f64));
                kept.push(u8::from(p.x >= 26.0));
            }
        }
    }
    let mask = volux_core::Grid::new(
        g.dims(),
        g.spacing().to_array(),
        g.origin().to_array(),
        volux_core::Samples::U8(volux_core::Buffer::owned(kept)),
    )
    .unwrap();
    volux_io::nrrd::write(&mask, &d.join("mask.nrrd")).unwrap();
    accepted(
        &[&base[..], &["--mask", "mask.nrrd", "-o", "masked.png"]].concat(),
        d,
    );
    let ([mx, my], masked) = shown(&d.join("masked.png"));
    assert!(
        (mx - 0.5).abs() < 0.05 && (my - 0.5).abs() < 0.05,
        "the masked cap's centre at ({mx}, {my})"
    );
    assert!(masked > 1.5 * all, "{masked} vs {all}");
}

/// `--stats` on Projected Tetrahedra times the frame without the sort-order diagnostic,
/// which costs about a third more; `--sort-violations` asks for it; it needs --stats and PT.
#[test]
fn the_pt_sort_diagnostic_is_asked_for_not_part_of_stats() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = volux(
        &["generate", "tets-smooth", "--size", "300", "-o", "m.vtet"],
        d,
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let json = |extra: &[&str]| -> serde_json::Value {
        let args = [
            &[
                "render", "m.vtet", "--size", "32x32", "--stats", "--json", "-o", "m.png",
            ][..],
            extra,
        ]
        .concat();
        let out = volux(&args, d);
        assert!(out.status.success(), "{extra:?}: {}", stderr(&out));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = json(&[]);
    assert!(plain["sort_violations"].is_null(), "{plain}");
    let counted = json(&["--sort-violations"]);
    assert!(counted["sort_violations"].is_u64(), "{counted}");
    let err = refused(&["render", "m.vtet", "--sort-violations", "-o", "x.png"], d);
    assert!(err.contains("add --stats"), "{err}");
    data(d);
    let err = refused(
        &[
            "render",
            "grid.raw",
            "--stats",
            "--sort-violations",
            "-o",
            "x.png",
        ],
        d,
    );
    assert!(err.contains("--sort-violations"), "{err}");
}
