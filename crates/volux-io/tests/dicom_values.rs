//! DICOM values, geometry, colour and several volumes against what pydicom decodes, on the
//! small fixtures of `tests/fixtures/dicom_values` (made by its `make_fixtures.py` from
//! pydicom's and pydicom-data's test files and from numbers; each with pydicom's values).
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use volux_core::volume_axes::AxisKind;
use volux_core::Grid;
use volux_io::{dicom, ErrorKind, LoadOptions, VolumeChoice};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/dicom_values")
}

fn expected() -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir().join("expected.json")).unwrap()).unwrap()
}

/// pydicom's values of fixture `name`, (z, y, x[, channel]) order.
fn values(name: &str) -> Vec<f64> {
    std::fs::read(dir().join(format!("{name}.expected.f64")))
        .unwrap()
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn read(name: &str) -> Grid {
    dicom::read(
        &dir().join(format!("{name}.dcm")),
        None,
        VolumeChoice::default(),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The grid of fixture `name` holds pydicom's values (rounded once to float32 where Volux
/// stores float32), at its origin and spacing, with a note naming the transform applied.
fn same_as_pydicom(name: &str) -> Grid {
    let e = &expected()[name];
    let g = read(name);
    let dims: Vec<usize> = e["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(g.dims().to_vec(), dims, "{name}");
    let want = values(name);
    let n = g.len();
    if e["channels"] == 3 {
        let rgb = g.color().unwrap_or_else(|| panic!("{name}: no colour"));
        assert_eq!(want.len(), 3 * n, "{name}");
        for i in 0..n {
            for c in 0..3 {
                assert_eq!(
                    rgb.channels()[c].get_f32(i),
                    want[3 * i + c] as f32,
                    "{name}: voxel {i} channel {c}"
                );
            }
        }
    } else {
        assert!(g.color().is_none(), "{name}");
        assert_eq!(want.len(), n, "{name}");
        for (i, w) in want.iter().enumerate() {
            assert_eq!(g.samples().get_f32(i), *w as f32, "{name}: voxel {i}");
        }
    }
    if let Some(o) = e["origin"].as_array() {
        for (a, b) in g.origin().to_array().iter().zip(o) {
            assert!(
                (a - b.as_f64().unwrap()).abs() < 1e-4,
                "{name}: origin {:?}",
                g.origin()
            );
        }
        let s = e["spacing"].as_array().unwrap();
        for (k, (a, b)) in g.spacing().to_array().iter().zip(s).enumerate() {
            if dims[k] > 1 || k < 2 {
                assert!(
                    (a - b.as_f64().unwrap()).abs() < 1e-4,
                    "{name}: spacing {:?}",
                    g.spacing()
                );
            }
        }
    }
    let note = e["note"].as_str().unwrap().to_lowercase();
    assert!(
        note.is_empty() || g.notes().iter().any(|n| n.to_lowercase().contains(&note)),
        "{name}: no note says {note:?}: {:?}",
        g.notes()
    );
    g
}

#[test]
fn un_elements_are_read_by_their_dictionary_vr() {
    // PixelSpacing, positions, orientation, Rows / Columns and rescale stored as UN.
    let g = same_as_pydicom("un_explicit");
    assert_eq!(g.spacing().x, 0.859375);
    assert_eq!(g.origin().z, -121.0);
}

#[test]
fn rt_dose_is_placed_by_grid_frame_offsets_and_scaled_to_gy() {
    for name in ["rtdose", "rtdose_expb"] {
        let g = same_as_pydicom(name);
        let o = g.origin();
        assert!(
            (o.x - 189.43125).abs() < 1e-9
                && (o.y - 199.43125).abs() < 1e-9
                && (o.z + 761.87).abs() < 1e-9,
            "{name}: {o:?}"
        );
        assert_eq!(g.spacing().z, 5.0, "{name}");
        assert_eq!(g.scalar_type(), volux_core::ScalarType::F32);
        assert!(g
            .notes()
            .iter()
            .any(|n| n.contains("GridFrameOffsetVector")));
    }
    // Big endian 32-bit words in order (the halves were swapped: 4.29e9 instead of 0.983).
    same_as_pydicom("rtdose_expb_1frame");
}

#[test]
fn modality_lut_sequence_is_applied() {
    let g = same_as_pydicom("mlut");
    assert_eq!(g.scalar_type(), volux_core::ScalarType::U16);
}

#[test]
fn palette_color_gives_rgb() {
    for name in ["palette8", "palette8_expb", "palette_segmented"] {
        same_as_pydicom(name);
    }
}

#[test]
fn colour_images_planar_ybr_rle_and_bit_depths() {
    for name in [
        "rgb8_planar1_2frame",
        "rgb16_2frame",
        "rgb32_expb",
        "ybr_full",
        "ybr_full_422",
        "ybr_full_rle",
        "ybr_full_j2k",
        "rgb_rle",
    ] {
        let g = same_as_pydicom(name);
        let a = g.extra_axes();
        assert!(
            a.iter()
                .any(|a| a.kind == AxisKind::Color && a.chosen.is_none()),
            "{name}: {a:?}"
        );
    }
}

#[test]
fn one_colour_channel_is_read_with_component() {
    let p = dir().join("rgb16_2frame.dcm");
    let all = read("rgb16_2frame");
    let green = dicom::read(
        &p,
        None,
        VolumeChoice {
            timepoint: 0,
            component: Some(1),
        },
    )
    .unwrap();
    assert!(green.color().is_none());
    for i in 0..all.len() {
        assert_eq!(
            green.samples().get_f32(i),
            all.color().unwrap().channels()[1].get_f32(i)
        );
    }
    let axis = green
        .extra_axes()
        .iter()
        .find(|a| a.kind == AxisKind::Color)
        .unwrap();
    assert_eq!((axis.len, axis.chosen), (3, Some(1)));
    // Through load(), which checks that the component asked for was chosen.
    let opts = LoadOptions {
        component: Some(2),
        ..Default::default()
    };
    volux_io::load(&p, &opts).unwrap();
    let opts = LoadOptions {
        component: Some(3),
        ..Default::default()
    };
    let e = volux_io::load(&p, &opts).unwrap_err();
    assert!(e.to_string().contains("component 3 does not exist"), "{e}");
    // A monochrome image has no component 1.
    let e = dicom::read(
        &dir().join("mlut.dcm"),
        None,
        VolumeChoice {
            timepoint: 0,
            component: Some(1),
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("component 1"), "{e}");
}

#[test]
fn single_bits_and_float_pixel_data() {
    for name in ["bits1_2frame", "bits1_expb", "float32", "float64"] {
        same_as_pydicom(name);
    }
}

/// The grid of volume `t` of `path`.
fn volume(path: &Path, t: usize) -> volux_io::Result<Grid> {
    dicom::read(
        path,
        None,
        VolumeChoice {
            timepoint: t,
            component: None,
        },
    )
}

#[test]
fn b_values_at_the_same_positions_are_volumes() {
    let d = dir().join("dwi");
    for (t, b) in [(0usize, 0.0), (1, 1000.0)] {
        let g = volume(&d, t).unwrap();
        assert_eq!(g.dims(), [4, 4, 3]);
        assert_eq!(g.origin().z, -2.5);
        assert_eq!(g.spacing().z, 2.5);
        // Slice k holds 0..16 + b / 10 + 10 k.
        for k in 0..3 {
            assert_eq!(g.value(1, 0, k), 1.0 + b as f32 / 10.0 + 10.0 * k as f32);
        }
        let a = g
            .extra_axes()
            .iter()
            .find(|a| a.kind == AxisKind::Volume)
            .unwrap();
        assert_eq!((a.len, a.chosen), (2, Some(t)));
        assert_eq!(a.values, vec![0.0, 1000.0]);
        assert!(a.meaning.contains("b-value"));
    }
    let e = volume(&d, 2).unwrap_err();
    assert!(e.to_string().contains("timepoint 2 does not exist"), "{e}");
    // Through load().
    let opts = LoadOptions {
        timepoint: 1,
        ..Default::default()
    };
    let (ds, _) = volux_io::load(&d, &opts).unwrap();
    let volux_io::Dataset::Grid(g) = ds else {
        panic!("a grid")
    };
    assert_eq!(g.value(0, 0, 0), 100.0);
}

#[test]
fn siemens_private_b_values_are_text() {
    // Implicit VR: the private B_value (IS) is kept as bytes by the parser; "1000" is
    // 1000, not its first byte 49.
    let d = dir().join("siemens_dwi");
    for (t, b) in [(0usize, 0.0f32), (1, 1000.0)] {
        let g = volume(&d, t).unwrap();
        assert_eq!(g.dims(), [4, 4, 2]);
        assert_eq!(g.value(0, 0, 1), b / 10.0 + 10.0);
        let a = &g.extra_axes()[0];
        assert_eq!(a.values, vec![0.0, 1000.0]);
    }
}

#[test]
fn temporal_positions_are_a_time_axis() {
    let d = dir().join("temporal");
    for t in 0..3 {
        let g = volume(&d, t).unwrap();
        assert_eq!(g.dims(), [4, 4, 2]);
        // Ordered along z: the slice at z = 1 (k = 1 in the files) first.
        assert_eq!(g.value(0, 0, 0), 1000.0 * (t + 1) as f32 + 1.0);
        let a = &g.extra_axes()[0];
        assert_eq!(
            (a.kind.clone(), a.len, a.chosen),
            (AxisKind::Time, 3, Some(t))
        );
        assert_eq!(a.values, vec![1.0, 2.0, 3.0]);
    }
}

#[test]
fn enhanced_multiframe_diffusion_volumes() {
    let p = dir().join("enhanced_dwi.dcm");
    for (t, b) in [(0usize, 0.0f32), (1, 800.0)] {
        let g = volume(&p, t).unwrap();
        assert_eq!(g.dims(), [4, 4, 3]);
        assert_eq!(g.origin().z, 0.0);
        assert_eq!(g.spacing().z, 2.5);
        // Frames at z 5, 0, 2.5 hold + 0, 10, 20: sorted, z = 0 first.
        assert_eq!(
            [g.value(0, 0, 0), g.value(0, 0, 1), g.value(0, 0, 2)],
            [b + 10.0, b + 20.0, b]
        );
        let a = &g.extra_axes()[0];
        assert_eq!(a.values, vec![0.0, 800.0]);
    }
}

#[test]
fn duplicate_positions_without_a_key_stay_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    for f in ["im1.dcm", "im4.dcm"] {
        let mut obj = dicom_object::open_file(dir().join("dwi").join(f)).unwrap();
        obj.remove_element(dicom_dictionary_std::tags::DIFFUSION_B_VALUE);
        obj.write_to_file(tmp.path().join(f)).unwrap();
    }
    let e = dicom::read(tmp.path(), None, VolumeChoice::default()).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Invalid(_)), "{e}");
    assert!(e.to_string().contains("same position"), "{e}");
}

#[test]
fn un_sequence_is_refused_at_once() {
    // 674 bytes whose UN sequence the parser would read as a 3.5 GB element.
    let t = Instant::now();
    let e = dicom::read(
        &dir().join("UN_sequence.dcm"),
        None,
        VolumeChoice::default(),
    )
    .unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    let msg = e.to_string();
    assert!(
        msg.contains("(4453,100C) has VR UN and an undefined length") && msg.lines().count() == 1,
        "{msg}"
    );
}

#[test]
fn implicit_data_set_under_an_explicit_transfer_syntax_is_named() {
    let e = dicom::read(
        &dir().join("SC_rgb_jpeg.dcm"),
        None,
        VolumeChoice::default(),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("encoded in implicit VR") && msg.contains("(0008,0008)"),
        "{msg}"
    );
}

#[test]
fn a_number_of_frames_that_is_no_number_is_refused() {
    // pydicom's badVR.dcm: NumberOfFrames "1A" was read as one frame without a word.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bad.dcm");
    let mut obj = dicom_object::open_file(dir().join("rtdose.dcm")).unwrap();
    obj.put_str(
        dicom_dictionary_std::tags::NUMBER_OF_FRAMES,
        dicom_core::VR::IS,
        "1A",
    );
    obj.write_to_file(&out).unwrap();
    let e = dicom::read(&out, None, VolumeChoice::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("NumberOfFrames \"1A\" is not a number"),
        "{e}"
    );
}

/// Per-channel sums and a few pixels (index in row order, RGB) of pydicom's decode of `name`.
fn colour_matches(
    name: &str,
    dims: [usize; 3],
    sums: [i64; 3],
    pixels: &[(usize, [u8; 3])],
    tol: i64,
) {
    let g = read(name);
    assert_eq!(g.dims(), dims, "{name}");
    let rgb = g.color().unwrap_or_else(|| panic!("{name}: no colour"));
    let n = g.len();
    for (c, want) in sums.iter().enumerate() {
        let got: i64 = (0..n).map(|i| rgb.channels()[c].get_f32(i) as i64).sum();
        // Lossy frames: at most `tol` a sample apart, on average far less.
        assert!(
            (got - want).abs() <= tol * n as i64 / 100,
            "{name}: channel {c} sums to {got}, pydicom's to {want}"
        );
    }
    for (i, want) in pixels {
        for (c, &w) in want.iter().enumerate() {
            let got = rgb.channels()[c].get_f32(*i) as i64;
            assert!(
                (got - i64::from(w)).abs() <= tol,
                "{name}: pixel {i} channel {c} is {got}, pydicom's {w}"
            );
        }
    }
}

/// An RGB JPEG without an Adobe marker and with component identifiers 0, 1, 2: left to
/// guess, jpeg-decoder converts it from YCbCr (pixels 110 off); decoded as coded, it is
/// pydicom's picture (within the lossy tolerance of 3).
#[test]
fn rgb_jpeg_without_a_colour_marker_is_not_converted() {
    colour_matches(
        "SC_jpeg_no_color_transform",
        [256, 256, 1],
        [15989247, 15989317, 15988450],
        &[
            (7503, [150, 134, 134]),
            (38917, [213, 196, 213]),
            (7247, [182, 165, 169]),
        ],
        3,
    );
}

/// A JPEG 2000 frame wrapped in a JP2 file (GDCM wrote such files): its codestream box is
/// checked and decoded, exactly (lossless).
#[test]
fn jpeg_2000_in_a_jp2_wrapper_is_read() {
    colour_matches(
        "GDCMJ2K_TextGBR",
        [400, 400, 1],
        [19605686, 20227141, 19896396],
        &[(36901, [255, 0, 0]), (16, [128, 128, 128])],
        0,
    );
}
