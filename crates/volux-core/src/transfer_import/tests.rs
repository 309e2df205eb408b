//! Tests of the importers against VTK's formulas coded straight here, independently of the
//! module's own evaluation.
use super::*;

/// `vtkPiecewiseFunction::GetTable` at one `x`, transcribed loop for loop (clamping on);
/// nodes as `[x, y, midpoint, sharpness]`.
fn vtk_reference(nodes: &[[f64; 4]], x: f64) -> f64 {
    let mut idx = 0;
    let (mut x1, mut x2, mut y1, mut y2, mut mid, mut sharp) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    while idx < nodes.len() && x > nodes[idx][0] {
        idx += 1;
        if idx < nodes.len() {
            (x1, x2) = (nodes[idx - 1][0], nodes[idx][0]);
            (y1, y2) = (nodes[idx - 1][1], nodes[idx][1]);
            mid = nodes[idx - 1][2].clamp(0.00001, 0.99999);
            sharp = nodes[idx - 1][3];
        }
    }
    if idx >= nodes.len() {
        return nodes[nodes.len() - 1][1];
    }
    if idx == 0 {
        return nodes[0][1];
    }
    let mut s = (x - x1) / (x2 - x1);
    s = if s < mid {
        0.5 * s / mid
    } else {
        0.5 + 0.5 * (s - mid) / (1.0 - mid)
    };
    if sharp > 0.99 {
        return if s < 0.5 { y1 } else { y2 };
    }
    if sharp < 0.01 {
        return (1.0 - s) * y1 + s * y2;
    }
    if s < 0.5 {
        s = 0.5 * (s * 2.0).powf(1.0 + 10.0 * sharp);
    } else if s > 0.5 {
        s = 1.0 - 0.5 * ((1.0 - s) * 2.0).powf(1.0 + 10.0 * sharp);
    }
    let (ss, sss) = (s * s, s * s * s);
    let t = (1.0 - sharp) * (y2 - y1);
    let v = (2.0 * sss - 3.0 * ss + 1.0) * y1
        + (-2.0 * sss + 3.0 * ss) * y2
        + (sss - 2.0 * ss + s) * t
        + (sss - ss) * t;
    v.clamp(y1.min(y2), y1.max(y2))
}

/// Opacity of a slab `len` world units thick in the imported TF (after `resolved`, as the
/// renderer uses it).
fn slab_opacity(tf: &TransferFunction, x: f64, len: f64) -> f64 {
    let r = tf.resolved([0.0, 1.0]);
    1.0 - (-r.tau_per_world(x) * len).exp()
}

/// VTK's opacity of a slab `len` thick for opacity `alpha` per `unit`:
/// `1 - (1 - alpha)^(len / unit)` (the ray casters' opacity correction).
fn vtk_slab(alpha: f64, len: f64, unit: f64) -> f64 {
    1.0 - (1.0 - alpha).powf(len / unit)
}

fn srgb_encode(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(x: f64) -> f64 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Probe positions from `lo` to `hi` in 4001 steps, plus a margin outside.
fn probes(lo: f64, hi: f64) -> impl Iterator<Item = f64> {
    let span = hi - lo;
    (0..=4400).map(move |i| lo - 0.05 * span + span * i as f64 / 4000.0)
}

fn flat(points: &[[f64; 4]]) -> String {
    let v: Vec<String> = points.iter().flatten().map(|x| x.to_string()).collect();
    v.join(", ")
}

fn preset(rgb: &str, points: &[[f64; 4]]) -> String {
    format!(
        r#"[{{"ColorSpace": "RGB", "Name": "test", "NanColor": [1, 1, 0], "Creator": "x",
            "RGBPoints": [{rgb}], "Points": [{}]}}]"#,
        flat(points)
    )
}

const RGB: &str = "0, 0, 0, 0, 40, 1, 0.5, 0, 100, 0.2, 0.9, 1";

/// Checks the imported opacity per unit distance against VTK at many positions, with unit
/// distance 1 and (set afterwards with `with_unit_length`) 2.5 world units.
fn assert_opacity_matches(nodes: &[[f64; 4]], skip: &[f64]) {
    let imported = from_paraview_json(&preset(RGB, nodes)).unwrap();
    let tf = imported.tf;
    let scaled = tf.clone().with_unit_length(2.5);
    let (lo, hi) = (nodes[0][0], nodes[nodes.len() - 1][0]);
    for x in probes(lo, hi).filter(|x| skip.iter().all(|s| (x - s).abs() > 1e-9)) {
        let alpha = vtk_reference(nodes, x);
        for (t, len, unit) in [(&tf, 1.0, 1.0), (&scaled, 2.5, 2.5)] {
            let (got, want) = (slab_opacity(t, x, len), vtk_slab(alpha, len, unit));
            assert!(
                (got - want).abs() < 1e-4,
                "x {x}, slab {len} unit {unit}: got {got}, VTK {want}"
            );
        }
    }
}

#[test]
fn linear_opacity_matches_vtk_per_unit_length() {
    let nodes = [
        [0.0, 0.0, 0.5, 0.0],
        [20.0, 0.3, 0.5, 0.0],
        [50.0, 0.95, 0.5, 0.0],
        [60.0, 1.0, 0.5, 0.0],
        [100.0, 0.1, 0.5, 0.0],
    ];
    assert_opacity_matches(&nodes, &[]);
}

#[test]
fn midpoint_and_sharpness_match_vtk() {
    let nodes = [
        [0.0, 0.0, 0.3, 0.0],
        [20.0, 0.6, 0.7, 0.5],
        [50.0, 0.1, 0.5, 0.99],
        [60.0, 0.9, 0.2, 0.25],
        [80.0, 0.2, 0.5, 1.0],
        [100.0, 0.7, 0.5, 0.0],
    ];
    // The step of the last-but-one segment is at its midpoint, x = 90.
    assert_opacity_matches(&nodes, &[90.0]);
}

#[test]
fn module_evaluation_agrees_with_the_reference() {
    let nodes = [
        [0.0, 0.0, 0.3, 0.0],
        [20.0, 0.6, 0.7, 0.5],
        [50.0, 0.1, 0.5, 0.99],
        [60.0, 0.9, 0.2, 0.25],
    ];
    let vtk: Vec<VtkNode> = nodes
        .iter()
        .map(|n| VtkNode {
            x: n[0],
            y: n[1],
            midpoint: n[2],
            sharpness: n[3],
        })
        .collect();
    for x in probes(0.0, 60.0) {
        assert_eq!(
            vtk_piecewise_value(&vtk, x),
            vtk_reference(&nodes, x),
            "{x}"
        );
    }
    assert_eq!(vtk_piecewise_value(&[], 1.0), 0.0);
}

#[test]
fn colours_match_vtk_display_values() {
    let tf = from_paraview_json(&preset(RGB, &[[0.0, 0.5, 0.5, 0.0]]))
        .unwrap()
        .tf;
    let nodes = [
        [0.0, 0.0, 0.0, 0.0],
        [40.0, 1.0, 0.5, 0.0],
        [100.0, 0.2, 0.9, 1.0],
    ];
    for x in probes(0.0, 100.0) {
        let c = tf.color_at(x);
        for k in 0..3 {
            let channel: Vec<[f64; 4]> = nodes.iter().map(|n| [n[0], n[k + 1], 0.5, 0.0]).collect();
            let want = vtk_reference(&channel, x);
            assert!((srgb_encode(c[k]) - want).abs() < 1e-4, "x {x} channel {k}");
        }
    }
}

#[test]
fn paraview_nodes_are_kept_exactly() {
    let imported = from_paraview_json(&preset(
        RGB,
        &[[0.0, 0.0, 0.5, 0.0], [100.0, 0.5, 0.5, 0.0]],
    ))
    .unwrap();
    let tf = &imported.tf;
    assert_eq!(imported.format, TfFormat::ParaView);
    assert_eq!(imported.name.as_deref(), Some("test"));
    assert_eq!(
        (tf.space, tf.opacity_step, tf.unit_length, tf.opacity_scale),
        (Space::Value, 1.0, 1.0, 1.0)
    );
    assert!(tf.extinction.is_empty());
    assert_eq!(tf.opacity.first(), Some(&[0.0, 0.0]));
    assert_eq!(tf.opacity.last(), Some(&[100.0, 0.5]));
    for node in [
        [0.0, 0.0, 0.0, 0.0],
        [40.0, 1.0, 0.5, 0.0],
        [100.0, 0.2, 0.9, 1.0],
    ] {
        let want = [
            node[0],
            srgb_decode(node[1]),
            srgb_decode(node[2]),
            srgb_decode(node[3]),
        ];
        assert!(tf.color.contains(&want), "{want:?} in {:?}", tf.color);
    }
    // The sampling stays modest: a 0..0.5 ramp needs few points.
    assert!(tf.opacity.len() < 64, "{}", tf.opacity.len());
    assert!(tf.color.len() < 512, "{}", tf.color.len());
    assert!(imported.notes.iter().any(|n| n.contains("NanColor")));
}

#[test]
fn paraview_single_object_and_default_ramp() {
    let text = r#"{"ColorSpace": "RGB", "RGBPoints": [0, 0, 0, 0, 10, 1, 1, 1]}"#;
    let imported = from_paraview_json(text).unwrap();
    assert_eq!(imported.name, None);
    assert!(imported.notes.iter().any(|n| n.contains("default ramp")));
    let nodes = [[0.0, 0.0, 0.5, 0.0], [10.0, 1.0, 0.5, 0.0]];
    for x in probes(0.0, 10.0) {
        let want = vtk_slab(vtk_reference(&nodes, x), 1.0, 1.0);
        assert!(
            (slab_opacity(&imported.tf, x, 1.0) - want).abs() < 1e-4,
            "{x}"
        );
    }
    let two = format!("[{text}, {text}]");
    let notes = from_paraview_json(&two).unwrap().notes;
    assert!(notes.iter().any(|n| n.contains("2 presets")), "{notes:?}");
}

const VP: &str = "1\n0\n0.9\n0.1\n0.2\n10\n\
                  6 -1000 0 200 0.4 1000 0.8\n\
                  4 0 1 255 1\n\
                  12 -1000 0 0 0 200 1 0.5 0.25 1000 1 1 1\n";

#[test]
fn slicer_vp_reads_exact_values() {
    let imported = from_slicer_vp(VP).unwrap();
    assert_eq!(imported.format, TfFormat::SlicerVp);
    assert!(imported.notes.is_empty(), "{:?}", imported.notes);
    let tf = &imported.tf;
    for node in [[-1000.0, 0.0], [200.0, 0.4], [1000.0, 0.8]] {
        assert!(tf.opacity.contains(&node), "{node:?}");
    }
    assert!(tf
        .color
        .contains(&[200.0, 1.0, srgb_decode(0.5), srgb_decode(0.25)]));
    let nodes = [
        [-1000.0, 0.0, 0.5, 0.0],
        [200.0, 0.4, 0.5, 0.0],
        [1000.0, 0.8, 0.5, 0.0],
    ];
    for x in probes(-1000.0, 1000.0) {
        let want = vtk_slab(vtk_reference(&nodes, x), 1.0, 1.0);
        assert!((slab_opacity(tf, x, 1.0) - want).abs() < 1e-4, "{x}");
    }
    // CRLF line ends, empty settings lines, no final newline.
    let crlf = VP.replace('\n', "\r\n").replacen("0.9", "", 1);
    assert_eq!(from_slicer_vp(crlf.trim_end()).unwrap().tf, imported.tf);
}

#[test]
fn slicer_notes_what_is_not_applied() {
    let vp = VP
        .replacen("\n0\n", "\n1\n", 1)
        .replace("4 0 1 255 1", "4 0 0 100 1");
    let notes = from_slicer_vp(&vp.replacen("1\n", "0\n", 1)).unwrap().notes;
    for want in ["gradient opacity", "shading", "nearest"] {
        assert!(notes.iter().any(|n| n.contains(want)), "{want}: {notes:?}");
    }
}

#[test]
fn formats_are_detected() {
    assert_eq!(detect_format("a.vp", "{}"), TfFormat::SlicerVp);
    assert_eq!(detect_format("a.VP", VP), TfFormat::SlicerVp);
    assert_eq!(detect_format("preset", VP), TfFormat::SlicerVp);
    assert_eq!(detect_format("a.json", "[]"), TfFormat::ParaView);
    assert_eq!(
        detect_format("a.json", r#"{"RGBPoints": []}"#),
        TfFormat::ParaView
    );
    assert_eq!(detect_format("a.json", r#"{"color": []}"#), TfFormat::Volux);
    assert_eq!(detect_format("a.json", "1"), TfFormat::Volux);
    let native = r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1]]}"#;
    assert_eq!(import("tf.json", native).unwrap().format, TfFormat::Volux);
    assert_eq!(import("x.vp", VP).unwrap().format, TfFormat::SlicerVp);
}

/// The error of `text` read as a ParaView preset: (field, reason).
fn pv_error(text: &str) -> (String, String) {
    match from_paraview_json(text).unwrap_err() {
        Error::TfImport {
            format,
            field,
            reason,
        } => {
            assert_eq!(format, "ParaView preset");
            (field, reason)
        }
        other => panic!("{text}: not a TfImport error: {other}"),
    }
}

#[test]
fn bad_paraview_presets_name_the_field() {
    let ok = |rgb: &str, pts: &str| {
        format!(r#"{{"ColorSpace": "RGB", "RGBPoints": [{rgb}], "Points": [{pts}]}}"#)
    };
    let rgb = "0, 0, 0, 0, 1, 1, 1, 1";
    let pts = "0, 0, 0.5, 0, 1, 1, 0.5, 0";
    let cases = [
        ("[]".to_string(), "presets", "empty"),
        (
            "[3]".to_string(),
            "presets",
            "expected a preset object, got 3",
        ),
        (ok("", pts), "RGBPoints", "no points"),
        (
            ok("0, 0, 0", pts),
            "RGBPoints",
            "3 numbers, not a multiple of 4",
        ),
        (
            ok("1, 0, 0, 0, 0, 1, 1, 1", pts),
            "RGBPoints[4]",
            "below the previous",
        ),
        (
            ok("0, 0, 2, 0", pts),
            "RGBPoints[2]",
            "colour component 2 is outside 0..1",
        ),
        (
            ok("0, 0, \"a\", 0", pts),
            "RGBPoints[2]",
            "expected a number, got \"a\"",
        ),
        (ok(rgb, "0, 1.5, 0.5, 0"), "Points[1]", "opacity 1.5"),
        (ok(rgb, "0, 1, 2, 0"), "Points[2]", "midpoint 2"),
        (ok(rgb, "0, 1, 0.5, -1"), "Points[3]", "sharpness -1"),
        (ok(rgb, "0, 1, 0.5"), "Points", "not a multiple of 4"),
        (ok(rgb, "5, 1, 0.5, 0, 4, 1, 0.5, 0"), "Points[4]", "sorted"),
        (
            r#"{"IndexedColors": [1, 0, 0]}"#.into(),
            "RGBPoints",
            "categorical",
        ),
        (r#"{"ColorSpace": "RGB"}"#.into(), "RGBPoints", "missing"),
        (
            r#"{"ColorSpace": "Diverging", "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "ColorSpace",
            "\"Diverging\" is not supported",
        ),
        (
            r#"{"ColorSpace": 3, "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "ColorSpace",
            "expected a string",
        ),
        (
            r#"{"ColorSpace": "RGB", "UseLogScale": true, "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "UseLogScale",
            "not supported",
        ),
        (
            r#"{"ColorSpace": "RGB", "NanColor": [1, 0], "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "NanColor",
            "expected [r, g, b]",
        ),
        (
            r#"{"ColorSpace": "RGB", "RGBPoints": 7}"#.into(),
            "RGBPoints",
            "expected a flat list",
        ),
        (
            r#"{"Name": 7, "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "Name",
            "expected a string",
        ),
    ];
    for (text, field, reason) in cases {
        let (f, r) = pv_error(&text);
        assert_eq!(f, field, "{text}: {r}");
        assert!(r.contains(reason), "{text}: {r}, want {reason}");
    }
    assert!(matches!(from_paraview_json("[1,,]"), Err(Error::Json(_))));
}

#[test]
fn oversized_inputs_are_refused() {
    let big: Vec<String> = (0..=MAX_POINTS)
        .flat_map(|i| [i.to_string(), "0".into()])
        .collect();
    let vp = format!(
        "1\n0\n1\n0\n0\n1\n{} {}\n\n4 0 0 0 0\n",
        big.len(),
        big.join(" ")
    );
    let e = from_slicer_vp(&vp).unwrap_err().to_string();
    assert!(
        e.contains("line 7 (scalar opacity)") && e.contains("up to 131072"),
        "{e}"
    );
}

/// The error message of `text` read as a .vp file.
fn vp_error(text: &str) -> String {
    let e = from_slicer_vp(text).unwrap_err();
    assert!(
        matches!(
            e,
            Error::TfImport {
                format: "Slicer .vp",
                ..
            }
        ),
        "{e}"
    );
    e.to_string()
}

#[test]
fn bad_vp_files_name_the_line() {
    let lines: Vec<&str> = VP.lines().collect();
    let with = |i: usize, s: &str| {
        let mut l = lines.clone();
        l[i] = s;
        l.join("\n")
    };
    let cases = [
        (
            lines[..7].join("\n"),
            "line 8 (gradient opacity): missing: the file ends after 7 lines",
        ),
        (String::new(), "line 1 (interpolation type): missing"),
        (
            with(0, "linear"),
            "line 1 (interpolation type): expected a number, got \"linear\"",
        ),
        (with(1, "3"), "line 2 (shade): 3 is not a valid value"),
        (
            with(5, "inf"),
            "line 6 (specular power): inf is not a valid value",
        ),
        (with(6, ""), "line 7 (scalar opacity): empty"),
        (with(6, "0"), "line 7 (scalar opacity): empty"),
        (
            with(6, "4 0 0 1"),
            "line 7 (scalar opacity): declares 4 numbers, holds 3",
        ),
        (with(6, "3 0 0 1"), "count 3 is not a multiple of 2"),
        (
            with(6, "x 0 0"),
            "expected the count of numbers first, got \"x\"",
        ),
        (
            with(6, "4 0 0 1 abc"),
            "number 3: expected a number, got \"abc\"",
        ),
        (
            with(6, "4 5 0 1 0"),
            "line 7 (scalar opacity): number [2]: position 1 is below",
        ),
        (
            with(6, "4 0 NaN 1 0"),
            "number [1]: NaN is not a finite number",
        ),
        (with(6, "4 0 0 1 1.5"), "opacity 1.5 is outside 0..1"),
        (
            with(7, "4 0 1 255"),
            "line 8 (gradient opacity): declares 4 numbers",
        ),
        (
            with(8, "4 0 0 0 2"),
            "line 9 (colour transfer): number [3]: colour component 2",
        ),
        (with(8, "") + "\n", "line 9 (colour transfer): empty"),
        (with(8, ""), "line 9 (colour transfer): missing"),
    ];
    for (text, want) in cases {
        let e = vp_error(&text);
        assert!(e.starts_with("Slicer .vp transfer function: "), "{e}");
        assert!(e.contains(want), "{text:?}: {e}, want {want}");
    }
}
