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
            r#"{"ColorSpace": "Lab/CIEDE2000", "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "ColorSpace",
            "\"Lab/CIEDE2000\" is not supported (VTK interpolates it along a shortest path",
        ),
        (
            r#"{"ColorSpace": "Prolab", "RGBPoints": [0, 0, 0, 0]}"#.into(),
            "ColorSpace",
            "\"Prolab\" is not supported; supported: \"RGB\", \"HSV\"",
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

// ---------------------------------------------------------------------------------------
// Colour spaces, against vtkColorTransferFunction::GetTable and vtkMath transcribed here.

/// `vtkMath::RGBToHSV`, statement for statement.
fn ref_rgb_to_hsv(r: f64, g: f64, b: f64) -> [f64; 3] {
    let (onethird, onesixth, twothird) = (1.0 / 3.0, 1.0 / 6.0, 2.0 / 3.0);
    let (mut cmax, mut cmin) = (r, r);
    if g > cmax {
        cmax = g;
    } else if g < cmin {
        cmin = g;
    }
    if b > cmax {
        cmax = b;
    } else if b < cmin {
        cmin = b;
    }
    let v = cmax;
    let s = if v > 0.0 { (cmax - cmin) / cmax } else { 0.0 };
    let mut h;
    if s > 0.0 {
        if r == cmax {
            h = onesixth * (g - b) / (cmax - cmin);
        } else if g == cmax {
            h = onethird + onesixth * (b - r) / (cmax - cmin);
        } else {
            h = twothird + onesixth * (r - g) / (cmax - cmin);
        }
        if h < 0.0 {
            h += 1.0;
        }
    } else {
        h = 0.0;
    }
    [h, s, v]
}

/// `vtkMath::HSVToRGB`, statement for statement.
fn ref_hsv_to_rgb(h: f64, s: f64, v: f64) -> [f64; 3] {
    let (onethird, onesixth, twothird, fivesixth) = (1.0 / 3.0, 1.0 / 6.0, 2.0 / 3.0, 5.0 / 6.0);
    let (r, g, b);
    if h > onesixth && h <= onethird {
        (g, r, b) = (1.0, (onethird - h) / onesixth, 0.0);
    } else if h > onethird && h <= 0.5 {
        (g, b, r) = (1.0, (h - onethird) / onesixth, 0.0);
    } else if h > 0.5 && h <= twothird {
        (b, g, r) = (1.0, (twothird - h) / onesixth, 0.0);
    } else if h > twothird && h <= fivesixth {
        (b, r, g) = (1.0, (h - twothird) / onesixth, 0.0);
    } else if h > fivesixth && h <= 1.0 {
        (r, b, g) = (1.0, (1.0 - h) / onesixth, 0.0);
    } else {
        (r, g, b) = (1.0, h / onesixth, 0.0);
    }
    [r, g, b].map(|c| (s * c + (1.0 - s)) * v)
}

/// `vtkMath::RGBToLab` (RGBToXYZ then XYZToLab), statement for statement.
fn ref_rgb_to_lab(rgb: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(|c| {
        if c > 0.04045 {
            ((c + 0.055) / 1.055).powf(2.4)
        } else {
            c / 12.92
        }
    });
    let x = r * 0.4124 + g * 0.3576 + b * 0.1805;
    let y = r * 0.2126 + g * 0.7152 + b * 0.0722;
    let z = r * 0.0193 + g * 0.1192 + b * 0.9505;
    let f = |v: f64| {
        if v > 0.008856 {
            v.powf(1.0 / 3.0)
        } else {
            (7.787 * v) + (16.0 / 116.0)
        }
    };
    let (vx, vy, vz) = (f(x / 0.9505), f(y / 1.000), f(z / 1.089));
    [(116.0 * vy) - 16.0, 500.0 * (vx - vy), 200.0 * (vy - vz)]
}

/// `vtkMath::LabToRGB` (LabToXYZ then XYZToRGB with its gamut clipping).
fn ref_lab_to_rgb(lab: [f64; 3]) -> [f64; 3] {
    let vy = (lab[0] + 16.0) / 116.0;
    let vx = lab[1] / 500.0 + vy;
    let vz = vy - lab[2] / 200.0;
    let f = |v: f64| {
        if v.powf(3.0) > 0.008856 {
            v.powf(3.0)
        } else {
            (v - 16.0 / 116.0) / 7.787
        }
    };
    let (x, y, z) = (0.9505 * f(vx), 1.000 * f(vy), 1.089 * f(vz));
    let mut rgb = [
        x * 3.2406 + y * -1.5372 + z * -0.4986,
        x * -0.9689 + y * 1.8758 + z * 0.0415,
        x * 0.0557 + y * -0.2040 + z * 1.0570,
    ]
    .map(|c| {
        if c > 0.0031308 {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        } else {
            12.92 * c
        }
    });
    let max = rgb[0].max(rgb[1]).max(rgb[2]);
    if max > 1.0 {
        rgb = rgb.map(|c| c / max);
    }
    rgb.map(|c| c.max(0.0))
}

/// `vtkColorTransferFunctionInterpolateDiverging` with its helpers inlined.
fn ref_diverging(mut s: f64, rgb1: [f64; 3], rgb2: [f64; 3]) -> [f64; 3] {
    use std::f64::consts::PI;
    let msh_of = |lab: [f64; 3]| {
        let m = (lab[0] * lab[0] + lab[1] * lab[1] + lab[2] * lab[2]).sqrt();
        let sat = if m > 0.001 {
            (lab[0] / m).min(1.0).acos()
        } else {
            0.0
        };
        let h = if sat > 0.001 {
            lab[2].atan2(lab[1])
        } else {
            0.0
        };
        [m, sat, h]
    };
    let angle = |a1: f64, a2: f64| {
        let mut d = a1 - a2;
        if d >= 0.0 {
            while d >= 2.0 * PI {
                d -= 2.0 * PI;
            }
            if d > PI {
                d = 2.0 * PI - d;
            }
        } else {
            while d <= -2.0 * PI {
                d += 2.0 * PI;
            }
            if d < -PI {
                d += 2.0 * PI;
            }
        }
        d
    };
    let adjust = |msh: [f64; 3], unsat_m: f64| {
        if msh[0] >= unsat_m - 0.1 {
            msh[2]
        } else {
            let spin =
                msh[1] * (unsat_m * unsat_m - msh[0] * msh[0]).sqrt() / (msh[0] * msh[1].sin());
            if msh[2] > -0.3 * PI {
                msh[2] + spin
            } else {
                msh[2] - spin
            }
        }
    };
    let mut msh1 = msh_of(ref_rgb_to_lab(rgb1));
    let mut msh2 = msh_of(ref_rgb_to_lab(rgb2));
    if msh1[1] > 0.05 && msh2[1] > 0.05 && angle(msh1[2], msh2[2]).abs() > 0.33 * PI {
        let mmid = msh1[0].max(msh2[0]).max(88.0);
        if s < 0.5 {
            msh2 = [mmid, 0.0, 0.0];
            s *= 2.0;
        } else {
            msh1 = [mmid, 0.0, 0.0];
            s = 2.0 * s - 1.0;
        }
    }
    if msh1[1] < 0.05 && msh2[1] > 0.05 {
        msh1[2] = adjust(msh2, msh1[0]);
    } else if msh2[1] < 0.05 && msh1[1] > 0.05 {
        msh2[2] = adjust(msh1, msh2[0]);
    }
    let m = (1.0 - s) * msh1[0] + s * msh2[0];
    let sat = (1.0 - s) * msh1[1] + s * msh2[1];
    let h = msh1[2] + s * angle(msh2[2], msh1[2]);
    ref_lab_to_rgb([
        m * sat.cos(),
        m * sat.sin() * h.cos(),
        m * sat.sin() * h.sin(),
    ])
}

/// `vtkColorTransferFunction::GetTable` at one `x` for linear nodes (midpoint 0.5,
/// sharpness 0, as presets hold them), clamping on; nodes `[x, r, g, b]`.
fn vtk_color_reference(nodes: &[[f64; 4]], space: &str, x: f64) -> [f64; 3] {
    let mut idx = 0;
    let (mut x1, mut x2, mut rgb1, mut rgb2) = (0.0, 0.0, [0.0; 3], [0.0; 3]);
    while idx < nodes.len() && x > nodes[idx][0] {
        idx += 1;
        if idx < nodes.len() {
            (x1, x2) = (nodes[idx - 1][0], nodes[idx][0]);
            rgb1 = [nodes[idx - 1][1], nodes[idx - 1][2], nodes[idx - 1][3]];
            rgb2 = [nodes[idx][1], nodes[idx][2], nodes[idx][3]];
        }
    }
    let node = |n: &[f64; 4]| [n[1], n[2], n[3]];
    if idx >= nodes.len() {
        return node(&nodes[nodes.len() - 1]);
    }
    if idx == 0 {
        return node(&nodes[0]);
    }
    let mut s = if x2 != x1 { (x - x1) / (x2 - x1) } else { 0.0 };
    let midpoint = 0.5;
    s = if s < midpoint {
        0.5 * s / midpoint
    } else {
        0.5 + 0.5 * (s - midpoint) / (1.0 - midpoint)
    };
    match space {
        "RGB" => [0, 1, 2].map(|j| (1.0 - s) * rgb1[j] + s * rgb2[j]),
        "Step" => rgb2,
        "HSV" => {
            let mut hsv1 = ref_rgb_to_hsv(rgb1[0], rgb1[1], rgb1[2]);
            let mut hsv2 = ref_rgb_to_hsv(rgb2[0], rgb2[1], rgb2[2]);
            if hsv1[0] - hsv2[0] > 0.5 || hsv2[0] - hsv1[0] > 0.5 {
                if hsv1[0] > hsv2[0] {
                    hsv1[0] -= 1.0;
                } else {
                    hsv2[0] -= 1.0;
                }
            }
            let mut h = (1.0 - s) * hsv1[0] + s * hsv2[0];
            if h < 0.0 {
                h += 1.0;
            }
            ref_hsv_to_rgb(
                h,
                (1.0 - s) * hsv1[1] + s * hsv2[1],
                (1.0 - s) * hsv1[2] + s * hsv2[2],
            )
        }
        "Lab" | "CIELAB" => {
            let (lab1, lab2) = (ref_rgb_to_lab(rgb1), ref_rgb_to_lab(rgb2));
            ref_lab_to_rgb([0, 1, 2].map(|j| (1.0 - s) * lab1[j] + s * lab2[j]))
        }
        "Diverging" => ref_diverging(s, rgb1, rgb2),
        other => panic!("no reference for {other}"),
    }
}

/// The largest difference between the imported colours (re-encoded) and VTK's display
/// colours over many positions, away from the nodes and the positions in `skip`; asserts
/// it is below 1e-4 and returns it. (At a node VTK can jump: its colour-space round trip
/// is not exact, and the first node's own colour is used at it, the round trip right after.)
fn max_colour_error(tf: &TransferFunction, nodes: &[[f64; 4]], space: &str, skip: &[f64]) -> f64 {
    let (lo, hi) = (nodes[0][0], nodes[nodes.len() - 1][0]);
    let mut worst: f64 = 0.0;
    let away = |x: f64| {
        let near = |s: f64| (x - s).abs() <= 1e-9;
        !skip.iter().any(|&s| near(s)) && !nodes.iter().any(|n| near(n[0]))
    };
    for x in probes(lo, hi).filter(|&x| away(x)) {
        let c = tf.color_at(x);
        let want = vtk_color_reference(nodes, space, x);
        for k in 0..3 {
            let e = (srgb_encode(c[k]) - want[k]).abs();
            assert!(
                e < 1e-4,
                "{space}: x {x} channel {k}: got {}, VTK {want:?}",
                srgb_encode(c[k])
            );
            worst = worst.max(e);
        }
    }
    eprintln!(
        "{space}: max colour error {worst:.2e} over {} points",
        tf.color.len()
    );
    worst
}

/// Imports `nodes` as a ParaView preset in `space`, checks it against VTK, and returns the
/// imported TF.
fn check_space(nodes: &[[f64; 4]], space: &str, skip: &[f64]) -> TransferFunction {
    let text = format!(
        r#"{{"ColorSpace": "{space}", "RGBPoints": [{}], "Points": [0, 0.5, 0.5, 0]}}"#,
        flat(nodes)
    );
    let tf = from_paraview_json(&text).unwrap().tf;
    max_colour_error(&tf, nodes, space, skip);
    tf
}

/// Colours that exercise the spaces: a hue wrap (red to magenta), greys, a saturated pair
/// far apart in hue, out-of-gamut Lab mixtures, equal positions (a step).
const MIXED: [[f64; 4]; 8] = [
    [-1.0, 1.0, 0.0, 0.0],
    [-0.5, 1.0, 0.0, 1.0],
    [0.0, 0.2, 0.9, 0.1],
    [0.3, 0.5, 0.5, 0.5],
    [0.6, 0.0, 0.1, 0.9],
    [0.6, 0.95, 0.8, 0.1],
    [0.8, 0.0, 0.0, 0.0],
    [1.0, 0.9, 0.3, 0.05],
];

#[test]
fn rgb_colours_match_vtk() {
    check_space(&MIXED, "RGB", &[0.6]);
}

#[test]
fn hsv_colours_match_vtk_with_hue_wrap() {
    check_space(&MIXED, "HSV", &[0.6]);
    // Red (hue 0) to magenta (hue 5/6) goes through hue 11/12, not through green.
    let tf = check_space(&[[0.0, 1.0, 0.0, 0.0], [1.0, 1.0, 0.0, 1.0]], "HSV", &[]);
    let mid = tf.color_at(0.5).map(srgb_encode);
    assert!((mid[0] - 1.0).abs() < 1e-4 && mid[1] < 1e-4 && (mid[2] - 0.5).abs() < 1e-4);
}

#[test]
fn lab_colours_match_vtk() {
    check_space(&MIXED, "Lab", &[0.6]);
    check_space(&MIXED, "CIELAB", &[0.6]);
}

#[test]
fn diverging_colours_match_vtk() {
    check_space(&MIXED, "Diverging", &[0.6]);
    // Two saturated colours far apart in hue: white (M 88 or more) inserted halfway.
    let tf = check_space(
        &[[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 0.0, 0.0]],
        "Diverging",
        &[],
    );
    let lab = ref_rgb_to_lab(tf.color_at(0.5).map(srgb_encode));
    assert!(
        lab[0] > 87.9 && lab[1].abs() < 0.1 && lab[2].abs() < 0.1,
        "{lab:?}"
    );
}

#[test]
fn step_colours_are_the_right_nodes_as_in_vtk() {
    // VTK's own test (TestColorTransferFunction): red at 0, blue at 1, Step: blue at 0.5.
    let nodes = [[0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0]];
    let tf = check_space(&nodes, "Step", &[0.0]);
    let blue = tf.color_at(0.5).map(srgb_encode);
    assert!((blue[2] - 1.0).abs() < 1e-12 && blue[0] == 0.0 && blue[1] == 0.0);
    // A step is two points at one position: the left node's colour, then the right one's.
    assert_eq!(
        tf.color,
        vec![
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0]
        ]
    );
    tf.validate().unwrap();
    check_space(&MIXED, "Step", &[-1.0, -0.5, 0.0, 0.3, 0.6, 0.8]);
}

fn example(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../docs/examples")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn cool_to_warm_example_matches_vtk() {
    let imported = from_paraview_json(&example("paraview-cool-to-warm.json")).unwrap();
    assert_eq!(imported.name.as_deref(), Some("Cool to Warm"));
    let nodes = [
        [0.0, 0.23137254902, 0.298039215686, 0.752941176471],
        [0.5, 0.865, 0.865, 0.865],
        [1.0, 0.705882352941, 0.0156862745098, 0.149019607843],
    ];
    max_colour_error(&imported.tf, &nodes, "Diverging", &[]);
    // The grey node is the map's white: VTK gives it after its Lab round trip, about
    // (0.865006, 0.865021, 0.865006); its L* is about 88, Moreland's white magnitude.
    let grey = imported.tf.color_at(0.5).map(srgb_encode);
    let want = vtk_color_reference(&nodes, "Diverging", 0.5);
    assert!(
        (0..3).all(|k| (grey[k] - want[k]).abs() < 1e-4),
        "{grey:?} {want:?}"
    );
    assert!(grey.iter().all(|c| (c - 0.865).abs() < 1e-4), "{grey:?}");
    assert!((ref_rgb_to_lab(grey)[0] - 88.0).abs() < 0.1);
    // Diverging differs from RGB interpolation by more than the tolerance here.
    let rgb = vtk_color_reference(&nodes, "RGB", 0.25);
    let div = imported.tf.color_at(0.25).map(srgb_encode);
    assert!(
        (0..3).any(|k| (rgb[k] - div[k]).abs() > 0.01),
        "{rgb:?} {div:?}"
    );
}

#[test]
fn paraview_example_still_imports() {
    let imported = from_paraview_json(&example("paraview-preset.json")).unwrap();
    assert_eq!(imported.name.as_deref(), Some("Volux example ramp"));
    let nodes = [
        [0.2, 0.1, 0.05, 0.3],
        [0.5, 0.9, 0.4, 0.1],
        [1.0, 1.0, 1.0, 0.8],
    ];
    max_colour_error(&imported.tf, &nodes, "RGB", &[]);
}

#[test]
fn module_colour_evaluation_agrees_with_the_reference() {
    let vtk: Vec<VtkColorNode> = MIXED
        .iter()
        .map(|n| VtkColorNode {
            x: n[0],
            rgb: [n[1], n[2], n[3]],
            midpoint: 0.5,
            sharpness: 0.0,
        })
        .collect();
    for (name, space) in [
        ("RGB", ColorSpace::Rgb),
        ("HSV", ColorSpace::Hsv),
        ("Lab", ColorSpace::Lab),
        ("Diverging", ColorSpace::Diverging),
        ("Step", ColorSpace::Step),
    ] {
        for x in probes(-1.0, 1.0) {
            let (got, want) = (
                vtk_color_value(&vtk, space, x),
                vtk_color_reference(&MIXED, name, x),
            );
            assert!(
                (0..3).all(|k| (got[k] - want[k]).abs() < 1e-12),
                "{name} {x}: {got:?} {want:?}"
            );
        }
    }
}

/// Files are read within bounds: a device or a huge file is refused before it is read, and
/// a real file imports as its text does.
#[test]
fn files_are_read_within_bounds() {
    let e = import_file(std::path::Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a regular file"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let huge = dir.path().join("huge.json");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(MAX_FILE_BYTES + 1)
        .unwrap();
    let e = import_file(&huge).unwrap_err().to_string();
    assert!(e.contains("a transfer function is at most"), "{e}");
    let good = dir.path().join("tf.json");
    let text = r#"{"color": [[0, 0, 0, 0], [1, 1, 1, 1]], "opacity": [[0, 0], [1, 1]]}"#;
    std::fs::write(&good, text).unwrap();
    assert_eq!(
        import_file(&good).unwrap().tf,
        import("tf.json", text).unwrap().tf
    );
    assert!(import_file(&dir.path().join("missing.json")).is_err());
}
