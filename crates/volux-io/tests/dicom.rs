//! DICOM reader tests on the shared series and multi-frame file, and on damaged copies of
//! them (uneven gaps, duplicate positions, truncation, differing Rows, several series,
//! compressed transfer syntax, implicit VR and big-endian re-encodings, rescale); then
//! folders as exported, built from the committed fixtures (`fixtures/dicom_compressed`): a
//! truncated slice, a non-DICOM file, junk after a DICM marker, a second series, an RGB
//! secondary capture, localizers in another plane, a gap, a DICOMDIR.
use std::path::{Path, PathBuf};

use dicom_core::VR;
use dicom_dictionary_std::tags;
use volux_core::ScalarType;
use volux_io::{dicom, ErrorKind};
use volux_testkit::data::shared;

/// In `shared/data`: a three-slice MR series and a multi-frame file.
const SERIES: &str = "tcia_cptac_sar_mr_3slice_dicom";
const EMRI: &str = "pydicom_emri_small/emri_small.dcm";
const FILES: [&str; 3] = ["1-1.dcm", "1-2.dcm", "1-3.dcm"];

fn sidecar(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

/// Copies the shared series into a new temp folder.
fn copy_series(series: &Path) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in FILES {
        std::fs::copy(series.join(f), dir.path().join(f)).unwrap();
    }
    dir
}

/// Rewrites `path` (or writes it to `to`) after `edit`.
fn edit(path: &Path, to: &Path, edit: impl FnOnce(&mut dicom_object::DefaultDicomObject)) {
    let mut obj = dicom_object::open_file(path).unwrap();
    edit(&mut obj);
    obj.write_to_file(to).unwrap();
}

fn set_z(obj: &mut dicom_object::DefaultDicomObject, z: f64) {
    obj.put_str(
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        format!("-250\\-250\\{z}"),
    );
}

fn err_kind(r: volux_io::Result<volux_core::Grid>) -> ErrorKind {
    match r {
        Ok(g) => panic!("read a damaged input: dims {:?}", g.dims()),
        Err(e) => {
            eprintln!("expected error: {e}");
            e.kind
        }
    }
}

#[test]
fn shared_series_folder() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let side = sidecar(&series.join("series.json"));
    assert_eq!(side["files"].as_array().unwrap().len(), 3);
    let g = dicom::read(&series, None, Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 3]);
    assert_eq!(g.scalar_type(), ScalarType::U16);
    let s = g.spacing();
    assert!((s.x - 0.9765625).abs() < 1e-9 && (s.y - 0.9765625).abs() < 1e-9);
    assert!((s.z - 12.0).abs() < 1e-9, "{s:?}");
    assert_eq!(g.origin().to_array(), [-250.0, -250.0, -12.0]);
    assert!(g.notes().is_empty(), "{:?}", g.notes());
    // Slice k of the volume is the file at z = -12 + 12 k (1-1 is at z = 12).
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    for (k, f) in FILES.iter().rev().enumerate() {
        let one = dicom::read(&series.join(f), None, Default::default()).unwrap();
        assert_eq!(one.dims(), [512, 512, 1]);
        assert_eq!(one.origin().z, -12.0 + 12.0 * k as f64);
        for i in (0..512 * 512).step_by(97) {
            assert_eq!(
                one.samples().get_f32(i),
                g.samples().get_f32(i + k * 512 * 512)
            );
        }
        range = [range[0].min(one.range()[0]), range[1].max(one.range()[1])];
    }
    assert_eq!(g.range(), range);
    assert!(g.range()[1] > 0.0);
}

#[test]
fn shared_multiframe() {
    let Some(emri) = shared(EMRI) else {
        return;
    };
    let side = sidecar(&emri.with_extension("dcm.json"));
    let g = dicom::read(&emri, None, Default::default()).unwrap();
    let (c, r, f) = (
        side["columns"].as_u64().unwrap() as usize,
        side["rows"].as_u64().unwrap() as usize,
        side["frames"].as_u64().unwrap() as usize,
    );
    assert_eq!(g.dims(), [c, r, f]);
    assert_eq!(g.scalar_type(), ScalarType::U16);
    let pr = side["pixel_range"].as_array().unwrap();
    assert_eq!(
        g.range(),
        [pr[0].as_f64().unwrap(), pr[1].as_f64().unwrap()]
    );
    // No PixelSpacing in this file; SpacingBetweenSlices is 1.2.
    assert_eq!(g.spacing().to_array(), [1.0, 1.0, 1.2]);
    assert!(g.notes().iter().any(|n| n.contains("PixelSpacing")));
    assert!(g.notes().iter().any(|n| n.contains("SpacingBetweenSlices")));
    // Through `load` (magic-byte detection).
    let (_, fmt) = volux_io::load(&emri, &Default::default()).unwrap();
    assert_eq!(fmt, volux_io::Format::Dicom);
}

#[test]
fn folder_skips_non_dicom_files() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    std::fs::copy(series.join("series.json"), dir.path().join("series.json")).unwrap();
    std::fs::write(dir.path().join("notes.txt"), "hello").unwrap();
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 3]);
    assert!(
        g.notes().is_empty(),
        "other files pass quietly: {:?}",
        g.notes()
    );
    // Empty files and folders among the slices are said (a damaged copy of a series).
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    std::fs::write(dir.path().join("1-4.dcm"), b"").unwrap();
    std::fs::write(dir.path().join("1-5.dcm"), b"").unwrap();
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 3]);
    assert!(
        g.notes()
            .iter()
            .any(|n| n == "skipped 2 empty files and 1 folder among the series' files"),
        "{:?}",
        g.notes()
    );
}

#[test]
fn frame_counts_that_disagree_with_the_data_are_refused_or_noted() {
    let Some(emri) = shared(EMRI) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for bad in ["0", "-1"] {
        let out = dir.path().join(format!("frames{bad}.dcm"));
        edit(&emri, &out, |o| {
            o.put_str(tags::NUMBER_OF_FRAMES, VR::IS, bad);
        });
        let e = dicom::read(&out, None, Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("NumberOfFrames is {bad}")), "{e}");
    }
    // No NumberOfFrames: one frame is read and the rest of the pixel data is said.
    let out = dir.path().join("missing.dcm");
    edit(&emri, &out, |o| {
        o.remove_element(tags::NUMBER_OF_FRAMES);
    });
    let g = dicom::read(&out, None, Default::default()).unwrap();
    assert_eq!(g.dims()[2], 1);
    assert!(
        g.notes()
            .iter()
            .any(|n| n.contains("more than the") && n.contains("the rest is not read")),
        "{:?}",
        g.notes()
    );
    // A NumberOfFrames smaller than the data: the same note.
    let out = dir.path().join("rows.dcm");
    edit(&emri, &out, |o| {
        o.put_str(tags::NUMBER_OF_FRAMES, VR::IS, "2");
    });
    let g = dicom::read(&out, None, Default::default()).unwrap();
    assert_eq!(g.dims()[2], 2);
    assert!(
        g.notes().iter().any(|n| n.contains("the rest is not read")),
        "{:?}",
        g.notes()
    );
}

#[test]
fn sagittal_series_gets_its_direction_matrix() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    // Rows along +y (P), columns along -z (I), slices at x = 12, 0, -12: the normal is -x.
    for (f, x) in FILES.iter().zip([12.0, 0.0, -12.0]) {
        let p = dir.path().join(f);
        edit(&p, &p, |o| {
            o.put_str(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, "0\\1\\0\\0\\0\\-1");
            o.put_str(
                tags::IMAGE_POSITION_PATIENT,
                VR::DS,
                format!("{x}\\-250\\250"),
            );
        });
    }
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.orientation_code(), "PIR");
    let d = g.direction();
    assert_eq!(
        [d.x_axis, d.y_axis, d.z_axis].map(|c| c.to_array()),
        [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]
    );
    assert_eq!(g.origin().to_array(), [12.0, -250.0, 250.0]);
    assert!((g.spacing().z - 12.0).abs() < 1e-9);
    assert!(g.notes().is_empty(), "{:?}", g.notes());
    // The last sample sits at the far corner in the world: +y rows, -z columns, -x slices.
    let far = g.position(511, 511, 2);
    let s = g.spacing();
    let want = [12.0 - 24.0, -250.0 + 511.0 * s.x, 250.0 - 511.0 * s.y];
    assert!((far - glam::DVec3::from(want)).length() < 1e-9, "{far}");
}

#[test]
fn uneven_gap_is_a_missing_slice() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    let p = dir.path().join("1-1.dcm");
    edit(&p, &p, |o| set_z(o, 40.0));
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("missing")),
        "{k}"
    );
}

#[test]
fn duplicate_position() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    let p = dir.path().join("1-1.dcm");
    edit(&p, &p, |o| set_z(o, 0.0));
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("same position")),
        "{k}"
    );
}

#[test]
fn missing_positions_fall_back_to_instance_number() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    for (i, f) in FILES.iter().enumerate() {
        let p = dir.path().join(f);
        edit(&p, &p, |o| {
            o.remove_element(tags::IMAGE_POSITION_PATIENT);
            o.put_str(tags::INSTANCE_NUMBER, VR::IS, format!("{}", 3 - i));
        });
    }
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 3]);
    assert!(g.notes().iter().any(|n| n.contains("InstanceNumber")));
    assert!(g.notes().iter().any(|n| n.contains("SpacingBetweenSlices")));
    assert_eq!(g.spacing().z, 12.0);
}

#[test]
fn truncated_file() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    let p = dir.path().join("1-2.dcm");
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 200_000]).unwrap();
    let k = err_kind(dicom::read(&p, None, Default::default()));
    assert!(
        matches!(
            k,
            ErrorKind::Truncated {
                expected: 524288,
                ..
            }
        ),
        "{k}"
    );
    // In the folder, the cut slice lies inside the stack: refused, naming it and the two
    // sub-series the series splits into.
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("\"1-2.dcm\" cannot be read: truncated")
            && m.contains("splits into 1 slice of 512 x 512, orientation LPS at -12.0000 mm \
                (1-3.dcm) and 1 slice of 512 x 512, orientation LPS at 12.0000 mm (1-1.dcm)")),
        "{k}"
    );
    // Cut inside the header: a parse error, not a panic.
    std::fs::write(&p, &bytes[..700]).unwrap();
    let k = err_kind(dicom::read(&p, None, Default::default()));
    assert!(
        matches!(k, ErrorKind::Invalid(_) | ErrorKind::Truncated { .. }),
        "{k}"
    );
}

#[test]
fn short_pixel_data_element() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("short.dcm");
    edit(&series.join("1-1.dcm"), &p, |o| {
        o.put(dicom_core::DataElement::new(
            tags::PIXEL_DATA,
            VR::OW,
            dicom_core::PrimitiveValue::U16(vec![7u16; 1000].into()),
        ));
    });
    let k = err_kind(dicom::read(&p, None, Default::default()));
    assert!(
        matches!(
            k,
            ErrorKind::Truncated {
                expected: 524288,
                found: 2000
            }
        ),
        "{k}"
    );
}

#[test]
fn different_rows() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    let p = dir.path().join("1-2.dcm");
    edit(&p, &p, |o| {
        o.put(dicom_core::DataElement::new(
            tags::ROWS,
            VR::US,
            dicom_core::PrimitiveValue::from(256u16),
        ));
    });
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("Rows")),
        "{k}"
    );
}

#[test]
fn no_dicom_files() {
    let dir = tempfile::tempdir().unwrap();
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("no DICOM")),
        "{k}"
    );
    std::fs::write(dir.path().join("a.txt"), "not dicom").unwrap();
    let k = err_kind(dicom::read(dir.path(), None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("no DICOM")),
        "{k}"
    );
    // A lone non-DICOM file, and garbage after a DICM marker.
    let k = err_kind(dicom::read(
        &dir.path().join("a.txt"),
        None,
        Default::default(),
    ));
    assert!(matches!(k, ErrorKind::Invalid(_)), "{k}");
    let mut junk = vec![0u8; 128];
    junk.extend_from_slice(b"DICM");
    junk.extend((0..5000u32).map(|i| (i * 7919 % 251) as u8));
    std::fs::write(dir.path().join("junk.dcm"), &junk).unwrap();
    let k = err_kind(dicom::read(
        &dir.path().join("junk.dcm"),
        None,
        Default::default(),
    ));
    assert!(
        matches!(k, ErrorKind::Invalid(_) | ErrorKind::Truncated { .. }),
        "{k}"
    );
}

#[test]
fn two_series() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = copy_series(&series);
    for f in ["1-1.dcm", "1-2.dcm"] {
        let to = dir.path().join(format!("b{f}"));
        edit(&series.join(f), &to, |o| {
            o.put_str(tags::SERIES_INSTANCE_UID, VR::UI, "1.2.3.4");
        });
    }
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 3]);
    assert!(
        g.notes().iter().any(|n| n.contains("2 series")),
        "{:?}",
        g.notes()
    );
    let g = dicom::read(dir.path(), Some("1.2.3.4"), Default::default()).unwrap();
    assert_eq!(g.dims(), [512, 512, 2]);
    assert_eq!(g.origin().z, 0.0);
    let k = err_kind(dicom::read(dir.path(), Some("9.9"), Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("1.2.3.4 (2 files)")),
        "{k}"
    );
}

#[test]
fn compressed_transfer_syntax_with_native_pixel_data_is_invalid() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(series.join("1-1.dcm")).unwrap();
    // Same length: "1.2.840.10008.1.2.1\0" -> "1.2.840.10008.1.2.5\0" (RLE Lossless).
    let at = bytes
        .windows(20)
        .position(|w| w == b"1.2.840.10008.1.2.1\0")
        .unwrap();
    bytes[at + 18] = b'5';
    let p = dir.path().join("rle.dcm");
    std::fs::write(&p, &bytes).unwrap();
    for path in [p.as_path(), dir.path()] {
        let k = err_kind(dicom::read(path, None, Default::default()));
        assert!(
            matches!(&k, ErrorKind::Invalid(m) if m.contains("1.2.840.10008.1.2.5")
                && m.contains("RLE") && m.contains("not encapsulated")),
            "{k}"
        );
    }
}

/// The same slice re-encoded as implicit VR little endian and explicit VR big endian.
#[test]
fn other_uncompressed_transfer_syntaxes() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let src = series.join("1-1.dcm");
    let want = dicom::read(&src, None, Default::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for ts in ["1.2.840.10008.1.2", "1.2.840.10008.1.2.2"] {
        let p: PathBuf = dir.path().join(format!("{ts}.dcm"));
        edit(&src, &p, |o| {
            o.meta_mut().transfer_syntax = ts.to_string();
            o.meta_mut().update_information_group_length();
        });
        let g = dicom::read(&p, None, Default::default()).unwrap_or_else(|e| panic!("{ts}: {e}"));
        assert_eq!(g.dims(), want.dims());
        assert_eq!(g.range(), want.range(), "{ts}");
        for i in (0..g.len()).step_by(101) {
            assert_eq!(g.samples().get_f32(i), want.samples().get_f32(i), "{ts}");
        }
    }
}

#[test]
fn rescale_to_i16_and_f32() {
    let Some(series) = shared(SERIES) else {
        return;
    };
    let src = series.join("1-1.dcm");
    let raw = dicom::read(&src, None, Default::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("1", "-1024", ScalarType::I16),
        ("2", "-1024", ScalarType::F32),
        ("1", "40000", ScalarType::F32),
    ];
    for (slope, inter, ty) in cases {
        let p = dir.path().join(format!("r{slope}_{inter}.dcm"));
        edit(&src, &p, |o| {
            o.put_str(tags::RESCALE_SLOPE, VR::DS, slope);
            o.put_str(tags::RESCALE_INTERCEPT, VR::DS, inter);
        });
        let g = dicom::read(&p, None, Default::default()).unwrap();
        assert_eq!(g.scalar_type(), ty, "{slope} {inter}");
        let (m, b): (f64, f64) = (slope.parse().unwrap(), inter.parse().unwrap());
        for i in (0..g.len()).step_by(89) {
            let v = f64::from(raw.samples().get_f32(i)) * m + b;
            assert_eq!(f64::from(g.samples().get_f32(i)), v);
        }
        assert!(g.notes().iter().any(|n| n.contains("Rescale")));
    }
}

#[test]
fn lying_frame_count_is_truncated() {
    let Some(emri) = shared(EMRI) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("frames.dcm");
    edit(&emri, &p, |o| {
        o.put_str(tags::NUMBER_OF_FRAMES, VR::IS, "2000000000");
    });
    let k = err_kind(dicom::read(&p, None, Default::default()));
    assert!(matches!(k, ErrorKind::Truncated { .. }), "{k}");
}

// ---- folders as exported (committed fixtures) ----

/// The committed fixtures of `fixtures/dicom_compressed`.
fn fx(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/dicom_compressed")
        .join(name)
}

/// A temp folder holding the three 32 x 32 MR slices (z = 12, 0, -12 mm) of `mr_native`.
fn mr_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in FILES {
        std::fs::copy(fx("mr_native").join(f), dir.path().join(f)).unwrap();
    }
    dir
}

fn values(g: &volux_core::Grid) -> Vec<f32> {
    (0..g.samples().len())
        .map(|i| g.samples().get_f32(i))
        .collect()
}

fn series_uid(p: &Path) -> String {
    dicom_object::open_file(p)
        .unwrap()
        .element(tags::SERIES_INSTANCE_UID)
        .unwrap()
        .to_str()
        .unwrap()
        .trim_end_matches('\0')
        .to_string()
}

/// A copy of `from` as `to` with `f` applied and a new SOPInstanceUID.
fn variant(from: &Path, to: &Path, f: impl FnOnce(&mut dicom_object::DefaultDicomObject)) {
    let n = to.file_name().unwrap().to_string_lossy().len();
    edit(from, to, |o| {
        o.put_str(tags::SOP_INSTANCE_UID, VR::UI, format!("1.2.826.0.1.9.{n}"));
        f(o);
    });
}

fn truncate(p: &Path, keep: usize) {
    let b = std::fs::read(p).unwrap();
    std::fs::write(p, &b[..b.len() - keep]).unwrap();
}

fn has_note(g: &volux_core::Grid, parts: &[&str]) {
    assert!(
        g.notes()
            .iter()
            .any(|n| parts.iter().all(|p| n.contains(p))),
        "no note with {parts:?}: {:?}",
        g.notes()
    );
}

/// A truncated slice past the end of the stack, junk after a DICM marker, a text file, an
/// RGB secondary capture and a second series: the MR stack is read as on its own, and each
/// file set aside is named in a note (the text file passes quietly).
#[test]
fn folder_sets_aside_damaged_and_foreign_files() {
    let dir = mr_folder();
    let clean = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert!(clean.notes().is_empty(), "{:?}", clean.notes());
    let d = dir.path();
    std::fs::write(d.join("notes.txt"), "not DICOM").unwrap();
    let mut junk = vec![0u8; 128];
    junk.extend_from_slice(b"DICM");
    junk.extend((0..3000u32).map(|i| (i * 7919 % 251) as u8));
    std::fs::write(d.join("junk.dcm"), &junk).unwrap();
    std::fs::copy(fx("rgb_sc.dcm"), d.join("rgb_sc.dcm")).unwrap();
    for f in ["1-1.dcm", "1-2.dcm"] {
        variant(&d.join(f), &d.join(format!("b{f}")), |o| {
            o.put_str(tags::SERIES_INSTANCE_UID, VR::UI, "1.2.3.4");
        });
    }
    variant(&d.join("1-1.dcm"), &d.join("late.dcm"), |o| set_z(o, 24.0));
    truncate(&d.join("late.dcm"), 300);
    let g = dicom::read(d, None, Default::default()).unwrap();
    assert_eq!(g.dims(), [32, 32, 3]);
    assert_eq!(values(&g), values(&clean));
    has_note(
        &g,
        &[
            "3 series in this folder",
            "1.2.3.4 (2 files: b1-1.dcm, b1-2.dcm)",
        ],
    );
    has_note(&g, &["rgb_sc.dcm", "the most readable files"]);
    has_note(
        &g,
        &["skipped 1 file that cannot be read as DICOM: junk.dcm"],
    );
    has_note(&g, &["1 file not loaded: late.dcm", "truncated"]);
    assert!(!g.notes().iter().any(|n| n.contains("notes.txt")));
    // The other series, chosen by UID: read past the damaged files.
    let b = dicom::read(d, Some("1.2.3.4"), Default::default()).unwrap();
    assert_eq!(b.dims(), [32, 32, 2]);
    // The RGB capture's series: read as colour.
    let rgb = dicom::read(d, Some(&series_uid(&fx("rgb_sc.dcm"))), Default::default()).unwrap();
    assert!(rgb.color().is_some(), "{:?}", rgb.notes());
}

/// `--series` selects a series when another one in the folder is broken (a truncated file
/// whose header reads, and one whose header does not).
#[test]
fn series_option_selects_past_a_broken_series() {
    let dir = mr_folder();
    let d = dir.path();
    for f in FILES {
        variant(&d.join(f), &d.join(format!("b{f}")), |o| {
            o.put_str(tags::SERIES_INSTANCE_UID, VR::UI, "1.2.3.4");
        });
        truncate(&d.join(format!("b{f}")), 100);
    }
    std::fs::write(d.join("bad.dcm"), {
        let mut b = std::fs::read(d.join("1-1.dcm")).unwrap();
        b.truncate(400);
        b
    })
    .unwrap();
    let uid = series_uid(&d.join("1-1.dcm"));
    for choice in [Some(uid.as_str()), None] {
        let g = dicom::read(d, choice, Default::default()).unwrap();
        assert_eq!(g.dims(), [32, 32, 3], "{choice:?}");
        has_note(&g, &["1.2.3.4 (3 files"]);
    }
    // The broken series itself: its first file's error.
    let k = err_kind(dicom::read(d, Some("1.2.3.4"), Default::default()));
    assert!(matches!(k, ErrorKind::Truncated { .. }), "{k}");
}

/// A slice missing from the middle (a gap of twice the spacing): refused, naming the two
/// sub-series by position range and files.
#[test]
fn a_gap_splits_the_series() {
    let dir = mr_folder();
    let d = dir.path();
    variant(&d.join("1-1.dcm"), &d.join("1-5.dcm"), |o| set_z(o, 36.0));
    let k = err_kind(dicom::read(d, None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("a slice is missing")
            && m.contains("the gap of 24.0000 mm between \"1-1.dcm\" and \"1-5.dcm\"")
            && m.contains("splits into 3 slices of 32 x 32, orientation LPS at \
                -12.0000..12.0000 mm (1-3.dcm..1-1.dcm) and 1 slice of 32 x 32, orientation LPS \
                at 36.0000 mm (1-5.dcm)")),
        "{k}"
    );
}

/// Localizers in another plane, a slice of other Rows past the stack, and an RGB capture,
/// all in the same series: the axial stack is loaded, the rest named in notes; a slice of
/// other Rows inside the stack is a hole, refused naming the field that differs.
#[test]
fn a_series_splits_by_orientation_and_size() {
    let dir = mr_folder();
    let d = dir.path();
    let clean = dicom::read(d, None, Default::default()).unwrap();
    let uid = series_uid(&d.join("1-1.dcm"));
    for (i, f) in ["loc1.dcm", "loc2.dcm"].iter().enumerate() {
        variant(&d.join("1-1.dcm"), &d.join(f), |o| {
            o.put_str(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, "0\\1\\0\\0\\0\\-1");
            o.put_str(
                tags::IMAGE_POSITION_PATIENT,
                VR::DS,
                format!("{}\\-250\\250", 5 * i),
            );
        });
    }
    variant(&d.join("1-1.dcm"), &d.join("small.dcm"), |o| {
        set_z(o, 24.0);
        o.put(dicom_core::DataElement::new(
            tags::ROWS,
            VR::US,
            dicom_core::PrimitiveValue::from(16u16),
        ));
    });
    variant(&fx("rgb_sc.dcm"), &d.join("sc.dcm"), |o| {
        o.put_str(tags::SERIES_INSTANCE_UID, VR::UI, uid.clone());
    });
    let g = dicom::read(d, None, Default::default()).unwrap();
    assert_eq!(g.dims(), [32, 32, 3]);
    assert_eq!(values(&g), values(&clean));
    has_note(
        &g,
        &[
            "also holds 3 stacks of another orientation or size, not loaded: 2 slices of \
             32 x 32, orientation PIR at -5.0000..0.0000 mm (loc2.dcm..loc1.dcm); 1 slice of \
             16 x 16, no orientation (sc.dcm); 1 slice of 32 x 16, orientation LPS at \
             24.0000 mm (small.dcm)",
        ],
    );
    // The smaller slice moved inside the stack.
    variant(&d.join("small.dcm"), &d.join("small.dcm"), |o| {
        set_z(o, 6.0)
    });
    let k = err_kind(dicom::read(d, None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("\"small.dcm\" has Rows 16 Columns 32")
            && m.contains("where the stack's slices have Rows 32 Columns 32")
            && m.contains("lies inside the stack at 6.0000 mm") && m.contains("splits into")),
        "{k}"
    );
}

/// A DICOMDIR (pydicom's FileSet over the MR slices, files in PT000000/ST000000/SE000000):
/// opening the DICOMDIR or its folder reads the series it references; a referenced file
/// that is missing is noted; a ReferencedFileID leaving the folder is refused.
#[test]
fn dicomdir_is_followed() {
    let clean = dicom::read(&fx("mr_native"), None, Default::default()).unwrap();
    for p in [fx("mr_dicomdir/DICOMDIR"), fx("mr_dicomdir")] {
        let g = dicom::read(&p, None, Default::default()).unwrap();
        assert_eq!(g.dims(), [32, 32, 3]);
        assert_eq!(values(&g), values(&clean));
        assert_eq!(g.origin(), clean.origin());
        has_note(
            &g,
            &["read through the DICOMDIR \"DICOMDIR\" (3 files referenced)"],
        );
    }
    let k = err_kind(dicom::read(
        &fx("mr_dicomdir"),
        Some("9.9"),
        Default::default(),
    ));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("series 9.9 is not in this folder")),
        "{k}"
    );
    // A copy with one referenced file gone (the last slice), then with a hostile path.
    let dir = tempfile::tempdir().unwrap();
    let se = dir.path().join("PT000000/ST000000/SE000000");
    std::fs::create_dir_all(&se).unwrap();
    std::fs::copy(fx("mr_dicomdir/DICOMDIR"), dir.path().join("DICOMDIR")).unwrap();
    for f in ["IM000000", "IM000001", "IM000002"] {
        std::fs::copy(
            fx("mr_dicomdir/PT000000/ST000000/SE000000").join(f),
            se.join(f),
        )
        .unwrap();
    }
    let last = std::fs::read_dir(&se)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            let o = dicom_object::open_file(p).unwrap();
            o.element(tags::IMAGE_POSITION_PATIENT)
                .unwrap()
                .to_multi_float64()
                .unwrap()[2]
                == 12.0
        })
        .unwrap();
    std::fs::remove_file(&last).unwrap();
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [32, 32, 2]);
    has_note(
        &g,
        &["skipped 1 file the DICOMDIR references but the folder lacks"],
    );
    let dd = dir.path().join("DICOMDIR");
    edit(&dd, &dd, |o| {
        let mut seq = o
            .element(tags::DIRECTORY_RECORD_SEQUENCE)
            .unwrap()
            .items()
            .unwrap()
            .to_vec();
        for item in &mut seq {
            if item
                .element_opt(tags::REFERENCED_FILE_ID)
                .ok()
                .flatten()
                .is_some()
            {
                item.put_str(tags::REFERENCED_FILE_ID, VR::CS, "..\\etc\\passwd");
            }
        }
        o.put(dicom_core::DataElement::new(
            tags::DIRECTORY_RECORD_SEQUENCE,
            VR::SQ,
            dicom_core::value::DataSetSequence::from(seq),
        ));
    });
    let k = err_kind(dicom::read(&dd, None, Default::default()));
    assert!(
        matches!(&k, ErrorKind::Invalid(m) if m.contains("not a plain name")),
        "{k}"
    );
    // Its folder: the DICOMDIR is set aside with a note, and the folder's own files are
    // scanned (here none at the top: the slices are in subfolders).
    std::fs::copy(fx("mr_native/1-1.dcm"), dir.path().join("flat.dcm")).unwrap();
    let g = dicom::read(dir.path(), None, Default::default()).unwrap();
    assert_eq!(g.dims(), [32, 32, 1]);
    has_note(&g, &["the DICOMDIR cannot be followed", "not a plain name"]);
}
