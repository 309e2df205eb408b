//! Raw + sidecar, NRRD, MetaImage and .vtet: round trips, format variants and malformed input.
use std::path::{Path, PathBuf};
use volux_testkit::mutate::{gzip, zlib};

use glam::Vec3;
use proptest::prelude::*;
use volux_core::{Buffer, Grid, Samples, ScalarType, TetMesh};
use volux_io::{load, metaimage, nrrd, raw, vtet, Dataset, ErrorKind, LoadOptions, ReadError};

// ---------- helpers ----------

fn values(g: &Grid) -> Vec<f32> {
    g.to_f32_vec().unwrap()
}

fn assert_kind(r: Result<impl std::fmt::Debug, ReadError>, ok: impl Fn(&ErrorKind) -> bool) {
    match r {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => {
            assert!(ok(&e.kind), "unexpected error kind: {e}");
            // One readable line naming the file.
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }
}

fn is_truncated(k: &ErrorKind) -> bool {
    matches!(k, ErrorKind::Truncated { .. })
}
fn is_mismatch(k: &ErrorKind) -> bool {
    matches!(k, ErrorKind::Header(m) if m.contains("mismatch"))
}
fn is_dims(k: &ErrorKind) -> bool {
    matches!(k, ErrorKind::Data(volux_core::Error::InvalidDims { .. }))
}
fn is_unsupported(k: &ErrorKind) -> bool {
    matches!(k, ErrorKind::Unsupported(_))
}
fn is_header(k: &ErrorKind) -> bool {
    matches!(k, ErrorKind::Header(_))
}

fn le_i16(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}
fn be_i16(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}
fn le_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Equal within one unit in the last place.
fn ulp_close(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() <= x.abs().max(y.abs()) * f64::EPSILON)
}

const I16_VALS: [i16; 12] = [-1024, -1, 0, 1, 2, 3, 300, 3071, -32768, 32767, 7, 8];

// ---------- raw + sidecar ----------

fn samples_strategy() -> impl Strategy<Value = ([usize; 3], Samples)> {
    ([1usize..5, 1usize..5, 1usize..5], 0..4u8).prop_flat_map(|(d, t)| {
        let n = d[0] * d[1] * d[2];
        let s: BoxedStrategy<Samples> = match t {
            0 => prop::collection::vec(any::<u8>(), n)
                .prop_map(|v| Samples::U8(Buffer::owned(v)))
                .boxed(),
            1 => prop::collection::vec(any::<u16>(), n)
                .prop_map(|v| Samples::U16(Buffer::owned(v)))
                .boxed(),
            2 => prop::collection::vec(any::<i16>(), n)
                .prop_map(|v| Samples::I16(Buffer::owned(v)))
                .boxed(),
            _ => prop::collection::vec(-1e6f32..1e6, n)
                .prop_map(|v| Samples::F32(Buffer::owned(v)))
                .boxed(),
        };
        (Just(d), s)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn raw_round_trip(
        (dims, samples) in samples_strategy(),
        spacing in [0.01f64..100.0, 0.01f64..100.0, 0.01f64..100.0],
        origin in [-1e3f64..1e3, -1e3f64..1e3, -1e3f64..1e3],
    ) {
        let g = Grid::new(dims, spacing, origin, samples).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.raw");
        raw::write(&g, &p).unwrap();
        prop_assert_eq!(std::fs::metadata(&p).unwrap().len(), raw::encoded_size(&g));
        let r = raw::read(&p).unwrap();
        prop_assert_eq!(r.dims(), g.dims());
        // serde_json (without its `float_roundtrip` feature) may parse a 17-digit number 1 ulp
        // off; the data itself must be bit-identical.
        prop_assert!(ulp_close(r.spacing().to_array(), g.spacing().to_array()));
        prop_assert!(ulp_close(r.origin().to_array(), g.origin().to_array()));
        prop_assert_eq!(r.scalar_type(), g.scalar_type());
        prop_assert_eq!(r.range(), g.range());
        prop_assert_eq!(values(&r), values(&g));
        prop_assert!(r.samples().is_mapped());
        prop_assert!(r.notes().is_empty(), "{:?}", r.notes());
        // The sidecar path works too.
        let r2 = raw::read(&dir.path().join("v.raw.json")).unwrap();
        prop_assert_eq!(values(&r2), values(&g));
        // A .raw.gz name writes gzip data that reads back the same.
        let gz = dir.path().join("v.raw.gz");
        raw::write(&g, &gz).unwrap();
        let r3 = raw::read(&gz).unwrap();
        prop_assert_eq!(r3.scalar_type(), g.scalar_type());
        prop_assert_eq!(values(&r3), values(&g));
        prop_assert!(r3.notes().is_empty(), "{:?}", r3.notes());
    }

    #[test]
    fn nrrd_round_trip(
        (dims, samples) in samples_strategy(),
        spacing in [0.01f64..100.0, 0.01f64..100.0, 0.01f64..100.0],
        origin in [-1e3f64..1e3, -1e3f64..1e3, -1e3f64..1e3],
    ) {
        let g = Grid::new(dims, spacing, origin, samples).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.nrrd");
        nrrd::write(&g, &p).unwrap();
        let r = nrrd::read(&p, Default::default()).unwrap();
        prop_assert_eq!(r.dims(), g.dims());
        prop_assert_eq!(r.spacing(), g.spacing());
        prop_assert_eq!(r.origin(), g.origin());
        prop_assert_eq!(r.scalar_type(), g.scalar_type());
        prop_assert_eq!(values(&r), values(&g));
    }
}

/// Writes `data` and a sidecar with the given JSON fields; returns the data path.
fn raw_with_sidecar(dir: &Path, name: &str, data: &[u8], car: serde_json::Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    std::fs::write(dir.join(format!("{name}.json")), car.to_string()).unwrap();
    p
}

#[test]
fn raw_gzip_big_endian_and_origin() {
    let dir = tempfile::tempdir().unwrap();
    let car = serde_json::json!({"dims_xyz": [3, 2, 2], "dtype": "int16", "endianness": "big",
        "compression": "gzip", "spacing": [0.5, 1.0, 2.0], "origin": [1.0, 2.0, 3.0]});
    let p = raw_with_sidecar(dir.path(), "v.raw.gz", &gzip(&be_i16(&I16_VALS)), car);
    let g = raw::read(&p).unwrap();
    assert_eq!(g.dims(), [3, 2, 2]);
    assert_eq!(g.scalar_type(), ScalarType::I16);
    assert_eq!(g.spacing().to_array(), [0.5, 1.0, 2.0]);
    assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0]);
    let want: Vec<f32> = I16_VALS.iter().map(|&v| v as f32).collect();
    assert_eq!(values(&g), want);
    assert!(!g.samples().is_mapped());
    // load() picks the raw reader for .raw.gz.
    let (d, f) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(f, volux_io::Format::RawJson);
    assert!(matches!(d, Dataset::Grid(g) if g.dims() == [3, 2, 2]));
}

/// Records the progress reports of a writer.
#[derive(Default)]
struct Reports(std::cell::RefCell<Vec<(u64, u64)>>);

impl Reports {
    fn record(&self) -> impl Fn(u64, u64) + '_ {
        |done, total| self.0.borrow_mut().push((done, total))
    }

    /// Checks the reports start at 0, end at `total`, never go back, and number at least `min`.
    fn check(&self, total: u64, min: usize) {
        let r = self.0.borrow();
        assert_eq!(r.first(), Some(&(0, total)), "{r:?}");
        assert_eq!(r.last(), Some(&(total, total)), "{r:?}");
        assert!(
            r.windows(2).all(|w| w[0].0 <= w[1].0 && w[0].1 == w[1].1),
            "{r:?}"
        );
        assert!(r.len() >= min, "{} reports", r.len());
    }
}

/// A 128 x 128 x 200 uint16 grid (6.5 MB of data) with varied values.
fn big_u16_grid() -> Grid {
    let v: Vec<u16> = (0..128 * 128 * 200u32)
        .map(|i| (i * 7 % 4099) as u16)
        .collect();
    Grid::new(
        [128, 128, 200],
        [1.0; 3],
        [0.0; 3],
        Samples::U16(Buffer::owned(v)),
    )
    .unwrap()
}

#[test]
fn raw_gzip_write_round_trip_and_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let g = Grid::new(
        [3, 2, 2],
        [0.5, 1.0, 2.0],
        [1.0, 2.0, 3.0],
        Samples::I16(Buffer::owned(I16_VALS.to_vec())),
    )
    .unwrap();
    let p = dir.path().join("ct.raw.gz");
    raw::write(&g, &p).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(&bytes[..2], &[0x1f, 0x8b]);
    let car: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("ct.raw.gz.json")).unwrap()).unwrap();
    assert_eq!(car["compression"], "gzip");
    let r = raw::read(&p).unwrap();
    assert_eq!((r.dims(), r.scalar_type()), ([3, 2, 2], ScalarType::I16));
    assert_eq!(values(&r), values(&g));
    assert_eq!(r.origin().to_array(), [1.0, 2.0, 3.0]);
    // Only the data and its sidecar are left: no temporary files.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    // Writing through the sidecar's name writes the same pair.
    let q = dir.path().join("b.raw.gz.json");
    raw::write(&g, &q).unwrap();
    assert_eq!(values(&raw::read(&q).unwrap()), values(&g));
}

#[test]
fn raw_write_reports_progress_and_its_size() {
    let g = big_u16_grid();
    let total = raw::encoded_size(&g);
    assert_eq!(total, 128 * 128 * 200 * 2);
    let dir = tempfile::tempdir().unwrap();
    for name in ["big.raw", "big.raw.gz"] {
        let reports = Reports::default();
        let p = dir.path().join(name);
        raw::write_with_progress(&g, &p, &reports.record()).unwrap();
        reports.check(total, 3);
        assert_eq!(values(&raw::read(&p).unwrap()), values(&g), "{name}");
    }
    let plain = std::fs::metadata(dir.path().join("big.raw")).unwrap().len();
    assert_eq!(plain, total);
    let small = Grid::new(
        [2, 1, 1],
        [1.0; 3],
        [0.0; 3],
        Samples::F32(Buffer::owned(vec![1.0, 2.0])),
    )
    .unwrap();
    assert_eq!(raw::encoded_size(&small), 8);
}

#[test]
fn raw_write_errors_name_the_file_and_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("missing").join("v.raw.gz");
    let e = raw::write(&big_u16_grid(), &p).unwrap_err();
    assert_eq!(e.path, p);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn raw_gzip_only_when_the_sidecar_or_name_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Uncompressed data that happens to start with the gzip magic bytes.
    let data = [0x1f, 0x8b, 3, 4];
    let car = serde_json::json!({"dims_xyz": [4, 1, 1], "dtype": "uint8", "spacing": [1, 1, 1]});
    let g = raw::read(&raw_with_sidecar(d, "m.raw", &data, car.clone())).unwrap();
    assert_eq!(values(&g), [31.0, 139.0, 3.0, 4.0]);
    assert!(g.samples().is_mapped());
    // No `compression` key, but a .gz name.
    let g = raw::read(&raw_with_sidecar(d, "m.raw.gz", &gzip(&data), car)).unwrap();
    assert_eq!(values(&g), [31.0, 139.0, 3.0, 4.0]);
}

#[test]
fn raw_wide_types_are_converted_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, Vec<u8>, Vec<f32>); 4] = [
        (
            "int8",
            vec![0x80, 0xff, 0, 127],
            vec![-128.0, -1.0, 0.0, 127.0],
        ),
        (
            "uint32",
            [0u32, 1, 70000, 16_777_216]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
            vec![0.0, 1.0, 70000.0, 16_777_216.0],
        ),
        (
            "int32",
            [-5i32, 1, -70000, 9]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
            vec![-5.0, 1.0, -70000.0, 9.0],
        ),
        (
            "float64",
            [0.5f64, -2.25, 1e10, 3.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
            vec![0.5, -2.25, 1e10, 3.0],
        ),
    ];
    for (dtype, bytes, want) in cases {
        let car = serde_json::json!({"dims_xyz": [2, 2, 1], "dtype": dtype, "spacing": [1, 1, 1]});
        let p = raw_with_sidecar(dir.path(), &format!("{dtype}.raw"), &bytes, car);
        let g = raw::read(&p).unwrap();
        assert_eq!(g.scalar_type(), ScalarType::F32, "{dtype}");
        assert_eq!(values(&g), want, "{dtype}");
        assert!(
            g.notes().iter().any(|n| n.contains(dtype)),
            "{:?}",
            g.notes()
        );
    }
}

#[test]
fn raw_malformed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let car = |dims: serde_json::Value, dtype: &str| serde_json::json!({"dims_xyz": dims, "dtype": dtype, "spacing": [1, 1, 1]});
    let dims = serde_json::json!([2, 2, 3]);
    let data = le_i16(&I16_VALS);
    // Truncated, longer, and the same for gzip.
    let p = raw_with_sidecar(d, "short.raw", &data[..20], car(dims.clone(), "int16"));
    assert_kind(raw::read(&p), is_truncated);
    let mut long = data.clone();
    long.extend_from_slice(&[0, 0]);
    let p = raw_with_sidecar(d, "long.raw", &long, car(dims.clone(), "int16"));
    assert_kind(raw::read(&p), is_mismatch);
    let p = raw_with_sidecar(
        d,
        "short.raw.gz",
        &gzip(&data[..20]),
        car(dims.clone(), "int16"),
    );
    assert_kind(raw::read(&p), is_truncated);
    let p = raw_with_sidecar(d, "long.raw.gz", &gzip(&long), car(dims.clone(), "int16"));
    assert_kind(raw::read(&p), is_mismatch);
    let gz = gzip(&data);
    let p = raw_with_sidecar(
        d,
        "cut.raw.gz",
        &gz[..gz.len() / 2],
        car(dims.clone(), "int16"),
    );
    assert_kind(raw::read(&p), |k| {
        is_truncated(k) || matches!(k, ErrorKind::Io(_))
    });
    // Bad dims.
    for bad in [
        serde_json::json!([i64::MAX, i64::MAX, 4]),
        serde_json::json!([0, 2, 2]),
        serde_json::json!([2, -2, 3]),
    ] {
        let p = raw_with_sidecar(d, "dims.raw", &data, car(bad, "int16"));
        assert_kind(raw::read(&p), is_dims);
    }
    // Unknown dtype, garbage sidecar, missing sidecar, a sidecar for something else.
    let p = raw_with_sidecar(d, "t.raw", &data, car(dims.clone(), "complex128"));
    assert_kind(raw::read(&p), is_unsupported);
    std::fs::write(d.join("t.raw.json"), b"\x00\xffnot json").unwrap();
    assert_kind(raw::read(&p), is_header);
    std::fs::write(d.join("alone.raw"), &data).unwrap();
    assert_kind(raw::read(&d.join("alone.raw")), |k| {
        matches!(k, ErrorKind::Io(_))
    });
    let other = serde_json::json!({"kind": "curvilinear (PLOT3D)", "dims_ijk": [2, 2, 3]});
    let p = raw_with_sidecar(d, "q.bin", &data, other);
    assert_kind(raw::read(&p), is_unsupported);
    // Garbage bytes with a plausible sidecar: the size does not match.
    let p = raw_with_sidecar(d, "g.raw", b"garbage garbage!", car(dims, "float32"));
    assert_kind(raw::read(&p), is_truncated);
}

#[test]
fn raw_nan_values_are_noted_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let vals = [1.0f32, f32::NAN, 3.0, f32::INFINITY];
    let car = serde_json::json!({"dims_xyz": [4, 1, 1], "dtype": "float32", "spacing": [1, 1, 1]});
    let p = raw_with_sidecar(dir.path(), "nan.raw", &le_f32(&vals), car);
    let g = raw::read(&p).unwrap();
    assert_eq!(g.range(), [1.0, 3.0]);
    assert!(g.notes().iter().any(|n| n.contains("non-finite")));
    assert!(values(&g).iter().all(|v| v.is_finite()));
}

// ---------- NRRD ----------

fn nrrd_file(dir: &Path, name: &str, header: &str, data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    let mut bytes = header.as_bytes().to_vec();
    bytes.extend_from_slice(data);
    std::fs::write(&p, bytes).unwrap();
    p
}

const NRRD_I16_HEAD: &str = "NRRD0004\n# a comment\ntype: short\ndimension: 3\nsizes: 3 2 2\n\
     spacings: 0.5 0.25 2\nmodality:=CT\n";

#[test]
fn nrrd_encodings_and_endianness() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let want: Vec<f32> = I16_VALS.iter().map(|&v| v as f32).collect();
    let cases = [
        ("be.nrrd", "endian: big\nencoding: raw\n", be_i16(&I16_VALS)),
        (
            "le.nrrd",
            "endian: little\nencoding: raw\n",
            le_i16(&I16_VALS),
        ),
        (
            "gz.nrrd",
            "endian: big\nencoding: gzip\n",
            gzip(&be_i16(&I16_VALS)),
        ),
        (
            "gz2.nrrd",
            "endian: little\nencoding: gz\n",
            gzip(&le_i16(&I16_VALS)),
        ),
        (
            "txt.nrrd",
            "encoding: ascii\n",
            I16_VALS
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(" ")
                .into_bytes(),
        ),
    ];
    for (name, fields, data) in cases {
        let p = nrrd_file(d, name, &format!("{NRRD_I16_HEAD}{fields}\n"), &data);
        let g = nrrd::read(&p, Default::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.dims(), [3, 2, 2], "{name}");
        assert_eq!(g.spacing().to_array(), [0.5, 0.25, 2.0], "{name}");
        assert_eq!(g.scalar_type(), ScalarType::I16, "{name}");
        assert_eq!(values(&g), want, "{name}");
        let (ds, _) = load(&p, &LoadOptions::default()).unwrap();
        assert!(matches!(ds, Dataset::Grid(_)));
    }
}

#[test]
fn nrrd_detached_with_skips_and_directions() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("data")).unwrap();
    let mut bytes = b"first junk line\nsecond\nXXXX".to_vec();
    bytes.extend_from_slice(&le_i16(&I16_VALS));
    std::fs::write(d.join("data/v.bin"), bytes).unwrap();
    let head = "NRRD0005\ntype: int16\ndimension: 3\nsizes: 3 2 2\n\
        space: left-posterior-superior\n\
        space directions: (0,2,0) (-1.5, 0, 0) (0,0,3)\nspace origin: (10,-20,30.5)\n\
        endian: little\nencoding: raw\ndata file: data/v.bin\nline skip: 2\nbyte skip: 4\n";
    let p = nrrd_file(d, "v.nhdr", head, b"");
    let g = nrrd::read(&p, Default::default()).unwrap();
    assert_eq!(g.spacing().to_array(), [2.0, 1.5, 3.0]);
    assert_eq!(g.origin().to_array(), [10.0, -20.0, 30.5]);
    // i runs along +y (P), j along -x (R), k along +z (S).
    assert_eq!(g.orientation_code(), "PRS");
    let dm = g.direction();
    assert_eq!(
        [dm.x_axis, dm.y_axis, dm.z_axis].map(|c| c.to_array()),
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert!(g.notes().is_empty(), "{:?}", g.notes());
    assert_eq!(values(&g)[0], -1024.0);
    // The same directions in RAS space: x and y negated into LPS.
    let ras = head.replace("left-posterior-superior", "RAS");
    let g = nrrd::read(&nrrd_file(d, "ras.nhdr", &ras, b""), Default::default()).unwrap();
    assert_eq!(g.orientation_code(), "ALS");
    assert_eq!(g.origin().to_array(), [-10.0, 20.0, 30.5]);
    // A sheared frame is noted and read axis-aligned.
    let shear = head.replace("(-1.5, 0, 0)", "(-1.5, 1, 0)");
    let g = nrrd::read(&nrrd_file(d, "shear.nhdr", &shear, b""), Default::default()).unwrap();
    assert!(g.is_axis_aligned());
    assert!(
        g.notes().iter().any(|n| n.contains("not orthogonal")),
        "{:?}",
        g.notes()
    );
    // Written and read back, the placement survives.
    let g = nrrd::read(&p, Default::default()).unwrap();
    let out = d.join("w.nrrd");
    nrrd::write(&g, &out).unwrap();
    let back = nrrd::read(&out, Default::default()).unwrap();
    assert_eq!(back.direction(), g.direction());
    assert_eq!(back.origin(), g.origin());
    assert_eq!(back.spacing(), g.spacing());
    // byte skip -1: the data ends the file.
    let head2 = head.replace("line skip: 2\nbyte skip: 4", "byte skip: -1");
    let p = nrrd_file(d, "v2.nhdr", &head2, b"");
    assert_eq!(
        values(&nrrd::read(&p, Default::default()).unwrap())[11],
        8.0
    );
}

#[test]
fn nrrd_2d_4d_and_wide_types() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h2 = "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 2 3\nencoding: raw\n\n";
    let g = nrrd::read(
        &nrrd_file(d, "a.nrrd", h2, &[1, 2, 3, 4, 5, 6]),
        Default::default(),
    )
    .unwrap();
    assert_eq!(g.dims(), [2, 3, 1]);
    let h4 = "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 1 2 3 1\n\
        space directions: none (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\n";
    let g = nrrd::read(
        &nrrd_file(d, "b.nrrd", h4, &[1, 2, 3, 4, 5, 6]),
        Default::default(),
    )
    .unwrap();
    assert_eq!(g.dims(), [2, 3, 1]);
    let h4bad = h4
        .replace("sizes: 1 2 3 1", "sizes: 2 2 3 1")
        .replace("none ", "");
    let r = nrrd::read(
        &nrrd_file(d, "c.nrrd", &h4bad, &[0; 12]),
        Default::default(),
    );
    assert!(r.is_ok(), "a trailing size-1 axis is fine too: {r:?}");
    let h4multi = "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 3 2 3 2\nencoding: raw\n\n";
    assert_kind(
        nrrd::read(
            &nrrd_file(d, "m.nrrd", h4multi, &[0; 36]),
            Default::default(),
        ),
        is_unsupported,
    );
    let wide: [(&str, Vec<u8>); 4] = [
        ("signed char", vec![0xfe, 1]),
        (
            "uint",
            [7u32, 3].iter().flat_map(|v| v.to_be_bytes()).collect(),
        ),
        (
            "int32_t",
            [-7i32, 3].iter().flat_map(|v| v.to_be_bytes()).collect(),
        ),
        (
            "double",
            [-7.5f64, 3.0]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect(),
        ),
    ];
    for (ty, bytes) in wide {
        let h =
            format!("NRRD0004\ntype: {ty}\ndimension: 1\nsizes: 2\nendian: big\nencoding: raw\n\n");
        let g = nrrd::read(&nrrd_file(d, "w.nrrd", &h, &bytes), Default::default()).unwrap();
        assert_eq!(g.scalar_type(), ScalarType::F32);
        assert!(!g.notes().is_empty(), "{ty}");
        let v = values(&g);
        assert!(
            v == [-2.0, 1.0] || v == [7.0, 3.0] || v == [-7.0, 3.0] || v == [-7.5, 3.0],
            "{ty}: {v:?}"
        );
    }
}

#[test]
fn nrrd_malformed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let head = |sizes: &str, ty: &str| {
        format!(
            "NRRD0004\ntype: {ty}\ndimension: 3\nsizes: {sizes}\nendian: little\nencoding: raw\n\n"
        )
    };
    let data = le_i16(&I16_VALS);
    let f = |name: &str, h: &str, data: &[u8]| {
        nrrd::read(&nrrd_file(d, name, h, data), Default::default())
    };
    assert_kind(
        f("t.nrrd", &head("3 2 2", "short"), &data[..23]),
        is_truncated,
    );
    assert_kind(
        f(
            "l.nrrd",
            &head("3 2 2", "short"),
            &[&data[..], &[1]].concat(),
        ),
        is_mismatch,
    );
    let gz = head("3 2 2", "short").replace("raw", "gzip");
    assert_kind(f("g.nrrd", &gz, &gzip(&data[..20])), is_truncated);
    assert_kind(
        f("g2.nrrd", &gz, &gzip(&[&data[..], &[0, 0]].concat())),
        is_mismatch,
    );
    let huge = "9223372036854775807 9223372036854775807 2";
    assert_kind(f("o.nrrd", &head(huge, "short"), &data), is_dims);
    assert_kind(f("z.nrrd", &head("3 0 2", "short"), &data), is_dims);
    assert_kind(f("n.nrrd", &head("3 -2 2", "short"), &data), is_dims);
    assert_kind(
        f("u.nrrd", &head("3 2 2", "quaternion"), &data),
        is_unsupported,
    );
    assert_kind(f("s.nrrd", &head("3 2", "short"), &data), is_header);
    assert_kind(f("x.nrrd", "garbage\x00\x01\x02\n\nmore", &data), is_header);
    assert_kind(
        f("b.nrrd", "\u{0}\u{1}NRRD0004\ntype: short\n\n", &data),
        is_header,
    );
    // Data that is not bzip2 where the header says bzip2: refused.
    let bz = head("3 2 2", "short").replace("raw", "bzip2");
    assert!(f("bz.nrrd", &bz, &data).is_err());
    let lz = head("3 2 2", "short").replace("raw", "lzma");
    assert_kind(f("lz.nrrd", &lz, &data), is_unsupported);
    let ascii = head("3 2 2", "short").replace("raw", "ascii");
    assert_kind(f("a.nrrd", &ascii, b"1 2 3"), is_truncated);
    assert_kind(f("a2.nrrd", &ascii, b"1 2 3 4 5 6 7 8 9 10 11 x"), |k| {
        matches!(k, ErrorKind::Invalid(_))
    });
    // Binary garbage (not UTF-8) in the header.
    let mut bin = b"NRRD0004\ntype: short\n".to_vec();
    bin.extend_from_slice(&[0xff, 0xfe, b'\n', b'\n']);
    std::fs::write(d.join("bin.nrrd"), bin).unwrap();
    assert_kind(
        nrrd::read(&d.join("bin.nrrd"), Default::default()),
        is_header,
    );
    // NaN floats are noted and replaced by volux-core.
    let nan = le_f32(&[1.0, f32::NAN, 2.0, 5.0]);
    let g = f("nan.nrrd", &head("2 2 1", "float"), &nan).unwrap();
    assert_eq!(g.range(), [1.0, 5.0]);
    assert!(g.notes().iter().any(|n| n.contains("non-finite")));
}

// ---------- MetaImage ----------

fn mha(dir: &Path, name: &str, fields: &str, data_file: &str, data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    let mut bytes = format!("{fields}ElementDataFile = {data_file}\n").into_bytes();
    bytes.extend_from_slice(data);
    std::fs::write(&p, bytes).unwrap();
    p
}

const MHA_I16: &str = "ObjectType = Image\nNDims = 3\nDimSize = 3 2 2\nElementType = MET_SHORT\n\
    ElementSpacing = 0.5 0.25 2\nOffset = 1 2 3\n";

#[test]
fn metaimage_variants() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let want: Vec<f32> = I16_VALS.iter().map(|&v| v as f32).collect();
    let le = le_i16(&I16_VALS);
    let be = be_i16(&I16_VALS);
    let z = zlib(&le);
    let cases: Vec<(&str, String, Vec<u8>)> = vec![
        (
            "le.mha",
            "BinaryDataByteOrderMSB = False\n".into(),
            le.clone(),
        ),
        ("be.mha", "ElementByteOrderMSB = True\n".into(), be.clone()),
        ("z.mha", "CompressedData = True\n".into(), z.clone()),
        (
            "zs.mha",
            format!("CompressedData = True\nCompressedDataSize = {}\n", z.len()),
            z,
        ),
        (
            "txt.mha",
            "BinaryData = False\n".into(),
            want.iter()
                .map(|v| format!("{v}\n"))
                .collect::<String>()
                .into_bytes(),
        ),
        (
            "hs.mha",
            "HeaderSize = 5\n".into(),
            [&b"12345"[..], &le].concat(),
        ),
        ("hsm.mha", "HeaderSize = -1\n".into(), le.clone()),
    ];
    for (name, extra, data) in cases {
        let p = mha(d, name, &format!("{MHA_I16}{extra}"), "LOCAL", &data);
        let g = metaimage::read(&p, Default::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.dims(), [3, 2, 2], "{name}");
        assert_eq!(g.spacing().to_array(), [0.5, 0.25, 2.0], "{name}");
        assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0], "{name}");
        assert_eq!(values(&g), want, "{name}");
        let (ds, _) = load(&p, &LoadOptions::default()).unwrap();
        assert!(matches!(ds, Dataset::Grid(_)));
    }
    // .mhd with a separate file, HeaderSize -1 skipping a preamble in the data file.
    std::fs::write(d.join("v.raw"), [&b"preamble"[..], &be].concat()).unwrap();
    let p = mha(
        d,
        "v.mhd",
        &format!("{MHA_I16}ElementByteOrderMSB = True\nHeaderSize = -1\n"),
        "v.raw",
        b"",
    );
    assert_eq!(
        values(&metaimage::read(&p, Default::default()).unwrap()),
        want
    );
}

#[test]
fn metaimage_2d_wide_types_and_aliases() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let h =
        "NDims = 2\nDimSize = 2 2\nElementType = MET_UCHAR\nElementSize = 3 4\nPosition = 5 6\n";
    let g = metaimage::read(
        &mha(d, "a.mha", h, "LOCAL", &[1, 2, 3, 4]),
        Default::default(),
    )
    .unwrap();
    assert_eq!(g.dims(), [2, 2, 1]);
    assert_eq!(g.spacing().to_array(), [3.0, 4.0, 1.0]);
    assert_eq!(g.origin().to_array(), [5.0, 6.0, 0.0]);
    let wide: [(&str, Vec<u8>, [f32; 2]); 4] = [
        ("MET_CHAR", vec![0xfe, 1], [-2.0, 1.0]),
        (
            "MET_UINT",
            [7u32, 3].iter().flat_map(|v| v.to_le_bytes()).collect(),
            [7.0, 3.0],
        ),
        (
            "MET_INT",
            [-7i32, 3].iter().flat_map(|v| v.to_le_bytes()).collect(),
            [-7.0, 3.0],
        ),
        (
            "MET_DOUBLE",
            [-7.5f64, 3.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
            [-7.5, 3.0],
        ),
    ];
    for (ty, bytes, want) in wide {
        let h = format!("NDims = 1\nDimSize = 2\nElementType = {ty}\n");
        let g = metaimage::read(&mha(d, "w.mha", &h, "LOCAL", &bytes), Default::default()).unwrap();
        assert_eq!(values(&g), want, "{ty}");
        assert!(g.notes().iter().any(|n| n.contains("converted")), "{ty}");
    }
    // Axis by axis, as ITK writes it: i along +y (P), j along +x (L), k along +z (S).
    let rot = format!("{MHA_I16}TransformMatrix = 0 1 0 1 0 0 0 0 1\n");
    let g = metaimage::read(
        &mha(d, "r.mha", &rot, "LOCAL", &le_i16(&I16_VALS)),
        Default::default(),
    )
    .unwrap();
    assert_eq!(g.orientation_code(), "PLS");
    assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0]);
    assert!(g.notes().is_empty(), "{:?}", g.notes());
    // Oblique: 30 degrees about z.
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let obl = format!("{MHA_I16}TransformMatrix = {c} {s} 0 {} {c} 0 0 0 1\n", -s);
    let g = metaimage::read(
        &mha(d, "o.mha", &obl, "LOCAL", &le_i16(&I16_VALS)),
        Default::default(),
    )
    .unwrap();
    let m = g.direction();
    assert!((m.x_axis - glam::DVec3::new(c, s, 0.0)).length() < 1e-12);
    assert!((m.y_axis - glam::DVec3::new(-s, c, 0.0)).length() < 1e-12);
    // Sheared: noted, read axis-aligned.
    let bad = format!("{MHA_I16}TransformMatrix = 1 0 0 0.5 1 0 0 0 1\n");
    let g = metaimage::read(
        &mha(d, "b.mha", &bad, "LOCAL", &le_i16(&I16_VALS)),
        Default::default(),
    )
    .unwrap();
    assert!(g.is_axis_aligned());
    assert!(g
        .notes()
        .iter()
        .any(|n| n.contains("TransformMatrix is not usable")));
    let id = format!("{MHA_I16}TransformMatrix = 1 0 0 0 1 0 0 0 1\n");
    let g = metaimage::read(
        &mha(d, "i.mha", &id, "LOCAL", &le_i16(&I16_VALS)),
        Default::default(),
    )
    .unwrap();
    assert!(g.notes().is_empty());
}

#[test]
fn metaimage_malformed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = le_i16(&I16_VALS);
    let f = |name: &str, fields: &str, data: &[u8]| {
        metaimage::read(&mha(d, name, fields, "LOCAL", data), Default::default())
    };
    let head = |dims: &str, ty: &str| format!("NDims = 3\nDimSize = {dims}\nElementType = {ty}\n");
    assert_kind(
        f("t.mha", &head("3 2 2", "MET_SHORT"), &data[..22]),
        is_truncated,
    );
    assert_kind(
        f(
            "l.mha",
            &head("3 2 2", "MET_SHORT"),
            &[&data[..], &[0]].concat(),
        ),
        is_mismatch,
    );
    let zh = format!("{}CompressedData = True\n", head("3 2 2", "MET_SHORT"));
    assert_kind(f("z.mha", &zh, &zlib(&data[..20])), is_truncated);
    assert_kind(
        f("z2.mha", &zh, &zlib(&[&data[..], &[0, 0]].concat())),
        is_mismatch,
    );
    let zs = format!("{zh}CompressedDataSize = 100000\n");
    assert_kind(f("z3.mha", &zs, &zlib(&data)), is_truncated);
    let huge = "9223372036854775807 9223372036854775807 2";
    assert_kind(f("o.mha", &head(huge, "MET_SHORT"), &data), is_dims);
    assert_kind(f("0.mha", &head("3 0 2", "MET_SHORT"), &data), is_dims);
    assert_kind(f("n.mha", &head("3 2 -2", "MET_SHORT"), &data), is_dims);
    assert_kind(
        f("u.mha", &head("3 2 2", "MET_FANCY"), &data),
        is_unsupported,
    );
    assert_kind(f("d.mha", &head("3 2", "MET_SHORT"), &data), is_header);
    let ch = format!(
        "{}ElementNumberOfChannels = 3\n",
        head("3 2 2", "MET_SHORT")
    );
    // Three channels need three times the data.
    assert_kind(f("c.mha", &ch, &data), is_truncated);
    let ch0 = ch.replace("= 3\n", "= 0\n");
    assert_kind(f("c0.mha", &ch0, &data), is_header);
    let ob = format!("ObjectType = Mesh\n{}", head("3 2 2", "MET_SHORT"));
    assert_kind(f("ob.mha", &ob, &data), is_unsupported);
    let list = metaimage::read(
        &mha(d, "list.mhd", &head("3 2 2", "MET_SHORT"), "LIST", b""),
        Default::default(),
    );
    assert_kind(list, is_unsupported);
    let missing = metaimage::read(
        &mha(d, "m.mhd", &head("3 2 2", "MET_SHORT"), "nope.raw", b""),
        Default::default(),
    );
    assert_kind(missing, |k| matches!(k, ErrorKind::Io(_)));
    std::fs::write(d.join("garbage.mha"), b"\x00\x01\xff\xfe garbage \n\x00").unwrap();
    assert_kind(
        metaimage::read(&d.join("garbage.mha"), Default::default()),
        is_header,
    );
    std::fs::write(d.join("noend.mha"), b"NDims = 3\nDimSize = 1 1 1\n").unwrap();
    assert_kind(
        metaimage::read(&d.join("noend.mha"), Default::default()),
        is_header,
    );
    let g = f(
        "nan.mha",
        &head("2 2 1", "MET_FLOAT"),
        &le_f32(&[f32::NAN, 1.0, 2.0, 3.0]),
    )
    .unwrap();
    assert_eq!(g.range(), [1.0, 3.0]);
    assert!(g.notes().iter().any(|n| n.contains("non-finite")));
}

// ---------- .vtet ----------

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A .vtet file written by hand (with a correct checksum unless `bad_sum`).
fn vtet_bytes(pos: &[[f32; 3]], sca: &[f32], tets: &[[u32; 4]], counts: (u64, u64)) -> Vec<u8> {
    let mut out = b"VOLUXTET".to_vec();
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&counts.0.to_le_bytes());
    out.extend_from_slice(&counts.1.to_le_bytes());
    let mut payload: Vec<u8> = pos.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    payload.extend(sca.iter().flat_map(|v| v.to_le_bytes()));
    payload.extend(tets.iter().flatten().flat_map(|v| v.to_le_bytes()));
    out.extend_from_slice(&payload);
    out.extend_from_slice(&fnv1a(&payload).to_le_bytes());
    out
}

fn mesh_strategy() -> impl Strategy<Value = TetMesh> {
    (4usize..24).prop_flat_map(|nv| {
        let pos = prop::collection::vec([-10f32..10.0, -10f32..10.0, -10f32..10.0], nv);
        let sca = prop::collection::vec(-1e3f32..1e3, nv);
        let tet = prop::sample::subsequence((0..nv as u32).collect::<Vec<_>>(), 4)
            .prop_shuffle()
            .prop_map(|v| [v[0], v[1], v[2], v[3]]);
        let tets = prop::collection::vec(tet, 1..32);
        (pos, sca, tets).prop_map(|(p, s, t)| {
            let p = p.into_iter().map(Vec3::from_array).collect();
            TetMesh::new(p, s, t).unwrap()
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn vtet_round_trip(mesh in mesh_strategy()) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.vtet");
        vtet::write(&mesh, &p).unwrap();
        prop_assert_eq!(std::fs::metadata(&p).unwrap().len(), vtet::encoded_size(&mesh));
        let r = vtet::read(&p).unwrap();
        prop_assert_eq!(r.positions(), mesh.positions());
        prop_assert_eq!(r.scalars(), mesh.scalars());
        prop_assert_eq!(r.tets(), mesh.tets());
        prop_assert_eq!(r.report().inverted_reoriented, 0);
        prop_assert_eq!(r.report().degenerate, mesh.report().degenerate);
        prop_assert_eq!(r.range(), mesh.range());
    }
}

#[test]
fn vtet_write_reports_progress_and_its_size() {
    // A 60 x 60 x 60 grid of points split into 5 tets per cube: over 1 million tets.
    let n = 60u32;
    let id = |i: u32, j: u32, k: u32| i + n * (j + n * k);
    let mut pos = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                pos.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    let mut tets = Vec::new();
    for k in 0..n - 1 {
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let c = |a, b, d| id(i + a, j + b, k + d);
                tets.push([c(0, 0, 0), c(1, 0, 0), c(0, 1, 0), c(0, 0, 1)]);
                tets.push([c(1, 1, 0), c(1, 0, 0), c(0, 1, 0), c(1, 1, 1)]);
            }
        }
    }
    let scalars = (0..pos.len()).map(|i| i as f32).collect();
    let mesh = TetMesh::new(pos, scalars, tets).unwrap();
    let total = vtet::encoded_size(&mesh);
    let (nv, nt) = (mesh.positions().len() as u64, mesh.tets().len() as u64);
    assert_eq!(total, 28 + 16 * nv + 16 * nt + 8);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.vtet");
    let reports = Reports::default();
    vtet::write_with_progress(&mesh, &p, &reports.record()).unwrap();
    reports.check(total, 3);
    assert_eq!(std::fs::metadata(&p).unwrap().len(), total);
    let r = vtet::read(&p).unwrap();
    assert_eq!((r.positions(), r.tets()), (mesh.positions(), mesh.tets()));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    let bad = dir.path().join("missing").join("m.vtet");
    assert_eq!(vtet::write(&mesh, &bad).unwrap_err().path, bad);
}

#[test]
fn vtet_load_and_nan_scalars() {
    let dir = tempfile::tempdir().unwrap();
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let p = dir.path().join("nan.vtet");
    // Inverted tet (swapped last two) and a NaN scalar: both repaired and reported.
    std::fs::write(
        &p,
        vtet_bytes(&pos, &[1.0, f32::NAN, 2.0, 3.0], &[[0, 1, 3, 2]], (4, 1)),
    )
    .unwrap();
    let (ds, f) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(f, volux_io::Format::Vtet);
    let Dataset::Mesh(m) = ds else {
        panic!("not a mesh")
    };
    assert_eq!(m.report().nonfinite_scalars, 1);
    assert_eq!(m.report().inverted_reoriented, 1);
    assert_eq!(m.range(), [1.0, 3.0]);
}

#[test]
fn vtet_malformed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let sca = [0.0, 1.0, 2.0, 3.0];
    let good = vtet_bytes(&pos, &sca, &[[0, 1, 2, 3]], (4, 1));
    let f = |name: &str, bytes: &[u8]| {
        let p = d.join(name);
        std::fs::write(&p, bytes).unwrap();
        vtet::read(&p)
    };
    assert!(f("good.vtet", &good).is_ok());
    assert_kind(f("t.vtet", &good[..good.len() - 9]), is_truncated);
    assert_kind(f("h.vtet", &good[..20]), is_truncated);
    assert_kind(f("l.vtet", &[&good[..], &[0]].concat()), is_mismatch);
    // Counts that overflow, or ask for far more than the file holds (no allocation happens).
    assert_kind(
        f(
            "o.vtet",
            &vtet_bytes(&pos, &sca, &[[0, 1, 2, 3]], (u64::MAX / 8, 1)),
        ),
        is_header,
    );
    assert_kind(
        f(
            "big.vtet",
            &vtet_bytes(&pos, &sca, &[[0, 1, 2, 3]], (1 << 40, 1 << 40)),
        ),
        is_truncated,
    );
    // Out-of-range index, empty mesh: rejected by TetMesh::new.
    let is_mesh = |k: &ErrorKind| matches!(k, ErrorKind::Data(volux_core::Error::InvalidMesh(_)));
    assert_kind(
        f("r.vtet", &vtet_bytes(&pos, &sca, &[[0, 1, 2, 4]], (4, 1))),
        is_mesh,
    );
    assert_kind(f("e.vtet", &vtet_bytes(&[], &[], &[], (0, 0))), is_mesh);
    let nanpos = [[f32::NAN, 0.0, 0.0], pos[1], pos[2], pos[3]];
    assert_kind(
        f(
            "np.vtet",
            &vtet_bytes(&nanpos, &sca, &[[0, 1, 2, 3]], (4, 1)),
        ),
        is_mesh,
    );
    // Corruption, wrong version, garbage.
    let mut bad = good.clone();
    bad[40] ^= 0x55;
    assert_kind(
        f("c.vtet", &bad),
        |k| matches!(k, ErrorKind::Invalid(m) if m.contains("checksum")),
    );
    let mut v2 = good.clone();
    v2[8] = 2;
    assert_kind(f("v.vtet", &v2), is_unsupported);
    assert_kind(
        f("g.vtet", b"this is not a tet mesh at all, just garbage"),
        is_header,
    );
    assert_kind(f("s.vtet", b"VOLU"), is_header);
}

// ---------- several volumes, colour, bzip2 and 64-bit types (NRRD, MetaImage) ----------

fn choice(timepoint: usize, component: Option<usize>) -> volux_io::VolumeChoice {
    volux_io::VolumeChoice {
        timepoint,
        component,
    }
}

fn describe(g: &Grid) -> Vec<String> {
    g.extra_axes().iter().map(|a| a.describe()).collect()
}

/// bzip2-encoded data (pynrrd's `encoding: bzip2`) reads as the raw data does; int64 and
/// uint64 become float32 in one rounding with a note.
#[test]
fn nrrd_bzip2_and_64_bit_types() {
    use std::io::Write as _;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let head = |ty: &str, enc: &str| {
        format!(
            "NRRD0004\ntype: {ty}\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: {enc}\n\n"
        )
    };
    let bz = |data: &[u8]| {
        let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::fast());
        e.write_all(data).unwrap();
        e.finish().unwrap()
    };
    let v = [-7i16, 300, 12, -32768];
    let g = nrrd::read(
        &nrrd_file(d, "b.nrrd", &head("short", "bzip2"), &bz(&le_i16(&v))),
        Default::default(),
    )
    .unwrap();
    assert_eq!(values(&g), v.map(f32::from).to_vec());
    assert_eq!(g.scalar_type(), ScalarType::I16);
    // A stream holding more than the header declares is a mismatch, as for gzip.
    let long = bz(&le_i16(&[1, 2, 3, 4, 5]));
    assert_kind(
        nrrd::read(
            &nrrd_file(d, "b2.nrrd", &head("short", "bz2"), &long),
            Default::default(),
        ),
        is_mismatch,
    );
    let big = (1i64 << 40) + 1;
    let i64s: Vec<u8> = [big, -3, i64::MAX, 0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    for ty in ["int64", "longlong", "signed long long int"] {
        let g = nrrd::read(
            &nrrd_file(d, "i.nrrd", &head(ty, "raw"), &i64s),
            Default::default(),
        )
        .unwrap();
        assert_eq!(
            values(&g),
            vec![big as f32, -3.0, i64::MAX as f32, 0.0],
            "{ty}"
        );
        assert!(g
            .notes()
            .iter()
            .any(|n| n.starts_with("converted from int64 to float32")));
    }
    let u64s: Vec<u8> = [u64::MAX, 1, 2, 3]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let g = nrrd::read(
        &nrrd_file(d, "u.nrrd", &head("uint64", "gzip"), &gzip(&u64s)),
        Default::default(),
    )
    .unwrap();
    assert_eq!(values(&g), vec![u64::MAX as f32, 1.0, 2.0, 3.0]);
    assert!(g.notes().iter().any(|n| n.contains("uint64 to float32")));
    let g = nrrd::read(
        &nrrd_file(
            d,
            "a.nrrd",
            &head("int64", "ascii"),
            b"1099511627777 -3 4 5",
        ),
        Default::default(),
    )
    .unwrap();
    assert_eq!(values(&g)[0], big as f32);
}

/// A 4-D NRRD as pynrrd writes one: the non-spatial axis found by its kind (or its `none`
/// space direction), time chosen by `timepoint` (its step from `spacings`), vector components
/// by `component`, a list on the first axis as components and elsewhere as volumes; the
/// geometry of the spatial axes is kept.
#[test]
fn nrrd_4d_time_vector_and_list_axes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // value = 1000 a + flat index of the spatial voxel, with `a` the entry on the extra axis.
    let vol = |a: i16| -> Vec<i16> { (0..12).map(|i| 1000 * a + i).collect() };
    let time: Vec<i16> = (0..3).flat_map(vol).collect();
    let h =
        "NRRD0004\ntype: short\ndimension: 4\nsizes: 3 2 2 3\nkinds: domain domain domain time\n\
        spacings: NaN NaN NaN 2.5\nspace: left-posterior-superior\n\
        space directions: (0.5,0,0) (0,0.25,0) (0,0,2) none\nspace origin: (1,2,3)\n\
        endian: little\nencoding: raw\n\n";
    let p = nrrd_file(d, "t.nrrd", h, &le_i16(&time));
    for t in 0..3 {
        let g = nrrd::read(&p, choice(t, None)).unwrap();
        assert_eq!(
            values(&g),
            vol(t as i16)
                .iter()
                .map(|&v| f32::from(v))
                .collect::<Vec<_>>()
        );
        assert_eq!(
            describe(&g),
            vec![format!("time: 3 volumes (timepoint {t} read), step 2.5")]
        );
        assert_eq!(g.dims(), [3, 2, 2]);
        assert_eq!(g.spacing().to_array(), [0.5, 0.25, 2.0]);
        assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0]);
    }
    assert!(nrrd::read(&p, choice(3, None))
        .unwrap_err()
        .to_string()
        .contains("timepoint 3 does not exist"));
    // Vector components first (interleaved), found by a `none` direction when kinds are absent.
    let inter: Vec<i16> = (0..12)
        .flat_map(|i| (0..3).map(move |c| 1000 * c + i))
        .collect();
    let hv = "NRRD0004\ntype: short\ndimension: 4\nsizes: 3 3 2 2\n\
        space directions: none (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n";
    let p = nrrd_file(d, "v.nrrd", hv, &le_i16(&inter));
    let g = nrrd::read(&p, Default::default()).unwrap();
    assert_eq!(
        values(&g),
        vol(0).iter().map(|&v| f32::from(v)).collect::<Vec<_>>()
    );
    assert_eq!(
        describe(&g),
        vec!["components: 3 components (component 0 read)".to_string()]
    );
    let hv = hv.replace(
        "sizes:",
        "kinds: covariant-vector domain domain domain\nsizes:",
    );
    let g = nrrd::read(
        &nrrd_file(d, "cv.nrrd", &hv, &le_i16(&inter)),
        choice(0, Some(2)),
    )
    .unwrap();
    assert_eq!(
        values(&g),
        vol(2).iter().map(|&v| f32::from(v)).collect::<Vec<_>>()
    );
    assert_eq!(
        describe(&g),
        vec!["components: 3 components (component 2 read), kind covariant-vector".to_string()]
    );
    // list: first axis = components, last axis = volumes.
    let hl = hv.replace("covariant-vector", "list");
    let g = nrrd::read(
        &nrrd_file(d, "l0.nrrd", &hl, &le_i16(&inter)),
        choice(0, Some(1)),
    )
    .unwrap();
    assert_eq!(values(&g)[1], 1001.0);
    let hl3 = h.replace(" time\n", " list\n");
    let g = nrrd::read(
        &nrrd_file(d, "l3.nrrd", &hl3, &le_i16(&time)),
        choice(2, None),
    )
    .unwrap();
    assert_eq!(
        describe(&g),
        vec!["volumes: 3 volumes (timepoint 2 read), kind list".to_string()]
    );
    assert_eq!(values(&g)[0], 2000.0);
    // Through `load`: a component asked of a time series is refused, not ignored.
    let opts = LoadOptions {
        component: Some(1),
        ..Default::default()
    };
    let e = load(&d.join("t.nrrd"), &opts).unwrap_err().to_string();
    assert!(e.contains("component 1 does not exist"), "{e}");
}

/// RGB-color and RGBA-color axes are colour (written back as colour by the NRRD writer); a
/// channel can be read as a scalar; alpha is dropped with a note.
#[test]
fn nrrd_colour_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let px: [[u8; 4]; 2] = [[255, 0, 10, 128], [0, 200, 30, 255]];
    for (kind, n) in [("RGB-color", 3), ("RGBA-color", 4)] {
        let data: Vec<u8> = px.iter().flat_map(|p| p[..n].to_vec()).collect();
        let h = format!(
            "NRRD0004\ntype: uchar\ndimension: 4\nsizes: {n} 2 1 1\nkinds: {kind} domain domain domain\n\
             encoding: raw\n\n"
        );
        let p = nrrd_file(d, &format!("{kind}.nrrd"), &h, &data);
        let g = nrrd::read(&p, Default::default()).unwrap();
        let c = g.color().expect("colour");
        assert_eq!(c.channels()[1].get_f32(1), 200.0);
        assert_eq!(
            describe(&g),
            vec!["colour: 3 channels (all kept)".to_string()]
        );
        assert_eq!(
            g.notes()
                .iter()
                .any(|n| n.contains("alpha channel was dropped")),
            n == 4
        );
        let out = d.join(format!("{kind}-out.nrrd"));
        nrrd::write(&g, &out).unwrap();
        let back = nrrd::read(&out, Default::default()).unwrap();
        let b = back.color().expect("colour written back");
        for (channel, &want) in b.channels().iter().zip(&px[0]) {
            assert_eq!(channel.get_f32(0), f32::from(want));
        }
        let blue = nrrd::read(&p, choice(0, Some(2))).unwrap();
        assert!(blue.color().is_none());
        assert_eq!(values(&blue), vec![10.0, 30.0]);
    }
}

/// MetaImage: three uchar channels (SimpleITK's RGB) are colour, other channel counts or
/// types are components, NDims 4 is a time series (step from the 4th spacing), and
/// MET_LONG (4 bytes), MET_LONG_LONG and MET_ULONG_LONG are converted with notes.
#[test]
fn metaimage_channels_4d_and_long_types() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rgb = "ObjectType = Image\nNDims = 3\nDimSize = 2 1 1\nElementNumberOfChannels = 3\n\
        ElementType = MET_UCHAR\n";
    let g = metaimage::read(
        &mha(d, "rgb.mha", rgb, "LOCAL", &[255, 0, 10, 0, 200, 30]),
        Default::default(),
    )
    .unwrap();
    assert_eq!(g.color().expect("colour").channels()[2].get_f32(1), 30.0);
    let g = metaimage::read(&d.join("rgb.mha"), choice(0, Some(1))).unwrap();
    assert_eq!(values(&g), vec![0.0, 200.0]);
    let vec2 = "ObjectType = Image\nNDims = 3\nDimSize = 2 1 1\nElementNumberOfChannels = 2\n\
        ElementType = MET_FLOAT\n";
    let g = metaimage::read(
        &mha(d, "v.mha", vec2, "LOCAL", &le_f32(&[1.0, -1.0, 2.0, -2.0])),
        choice(0, Some(1)),
    )
    .unwrap();
    assert_eq!(values(&g), vec![-1.0, -2.0]);
    assert_eq!(
        describe(&g),
        vec!["components: 2 components (component 1 read)".to_string()]
    );
    let four = "ObjectType = Image\nNDims = 4\nDimSize = 2 1 1 3\nElementType = MET_SHORT\n\
        ElementSpacing = 0.5 0.5 2 1.5\nOffset = 1 2 3 0\n\
        TransformMatrix = 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n";
    let p = mha(d, "4d.mha", four, "LOCAL", &le_i16(&[1, 2, 3, 4, 5, 6]));
    let g = metaimage::read(&p, choice(2, None)).unwrap();
    assert_eq!(values(&g), vec![5.0, 6.0]);
    assert_eq!(
        describe(&g),
        vec!["time: 3 volumes (timepoint 2 read), step 1.5".to_string()]
    );
    assert_eq!(g.spacing().to_array(), [0.5, 0.5, 2.0]);
    assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0]);
    let long = |ty: &str, bytes: Vec<u8>| {
        let h = format!("ObjectType = Image\nNDims = 3\nDimSize = 2 1 1\nElementType = {ty}\n");
        metaimage::read(&mha(d, "l.mha", &h, "LOCAL", &bytes), Default::default()).unwrap()
    };
    let g = long(
        "MET_LONG",
        [-4i32, 1 << 30]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    assert_eq!(values(&g), vec![-4.0, (1 << 30) as f32]);
    assert!(g
        .notes()
        .iter()
        .any(|n| n.starts_with("converted from int32")));
    let big = (1i64 << 40) + 1;
    let g = long(
        "MET_LONG_LONG",
        [big, -1].iter().flat_map(|v| v.to_le_bytes()).collect(),
    );
    assert_eq!(values(&g), vec![big as f32, -1.0]);
    assert!(g
        .notes()
        .iter()
        .any(|n| n.starts_with("converted from int64")));
    let g = long(
        "MET_ULONG_LONG",
        [u64::MAX, 9].iter().flat_map(|v| v.to_le_bytes()).collect(),
    );
    assert_eq!(values(&g), vec![u64::MAX as f32, 9.0]);
    assert!(g
        .notes()
        .iter()
        .any(|n| n.starts_with("converted from uint64")));
}

/// A grid in micrometres (a microscope stack) keeps its unit through the raw sidecar and the
/// NRRD `space units`; an NRRD whose axes mix units is refused rather than read as mm.
#[test]
fn the_unit_of_length_survives_raw_and_nrrd() {
    let dir = tempfile::tempdir().unwrap();
    let g = Grid::new(
        [3, 2, 2],
        [0.2, 0.2, 1.5],
        [0.0; 3],
        Samples::U8(Buffer::owned((0..12).collect())),
    )
    .unwrap()
    .with_unit("µm");
    assert_eq!(g.unit(), "µm");
    let r = dir.path().join("cells.raw");
    raw::write(&g, &r).unwrap();
    assert_eq!(raw::read(&r).unwrap().unit(), "µm");
    let n = dir.path().join("cells.nrrd");
    nrrd::write(&g, &n).unwrap();
    let back = nrrd::read(&n, Default::default()).unwrap();
    assert_eq!(back.unit(), "µm");
    assert_eq!(values(&back), values(&g));
    // Millimetres are the default and need no field.
    let mm = Grid::new(
        [1, 1, 1],
        [1.0; 3],
        [0.0; 3],
        Samples::U8(Buffer::owned(vec![1])),
    )
    .unwrap();
    nrrd::write(&mm, &n).unwrap();
    assert!(!std::fs::read_to_string(&n).unwrap().contains("space units"));
    assert_eq!(nrrd::read(&n, Default::default()).unwrap().unit(), "mm");
    let mixed = "NRRD0004\ntype: uint8\ndimension: 3\nspace: left-posterior-superior\n\
                 sizes: 1 1 1\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n\
                 space units: \"mm\" \"mm\" \"um\"\nencoding: raw\n\n\x01";
    std::fs::write(&n, mixed).unwrap();
    let e = nrrd::read(&n, Default::default()).unwrap_err().to_string();
    assert!(e.contains("space units"), "{e}");
}
