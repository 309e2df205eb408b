//! FreeSurfer MGH / MGZ reader tests: files written byte by byte (big-endian header, frames,
//! footer), placed as nibabel's `MGHHeader.get_affine` places them, and malformed ones.
use std::io::Write;
use std::path::{Path, PathBuf};

use volux_core::{Grid, ScalarType};
use volux_io::{load, mgh, Dataset, ErrorKind, Format, LoadOptions, VolumeChoice};

/// An MGH file: `dims` (x, y, z, frames), type code, `delta`, `Mdc` rows, `c_ras`, the data
/// (already big-endian) and an optional TR footer.
#[allow(clippy::too_many_arguments)]
fn mgh_bytes(
    dims: [i32; 4],
    code: i32,
    good_ras: i16,
    delta: [f32; 3],
    mdc: [[f32; 3]; 3],
    c_ras: [f32; 3],
    data: &[u8],
    tr: Option<f32>,
) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(1i32.to_be_bytes());
    for d in dims {
        b.extend(d.to_be_bytes());
    }
    b.extend(code.to_be_bytes());
    b.extend(0i32.to_be_bytes());
    b.extend(good_ras.to_be_bytes());
    for v in delta.iter().chain(mdc.iter().flatten()).chain(c_ras.iter()) {
        b.extend(v.to_be_bytes());
    }
    b.resize(284, 0);
    b.extend_from_slice(data);
    if let Some(tr) = tr {
        b.extend(tr.to_be_bytes());
        b.extend([0u8; 16]);
    }
    b
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    if name.ends_with(".mgz") {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(bytes).unwrap();
        std::fs::write(&p, e.finish().unwrap()).unwrap();
    } else {
        std::fs::write(&p, bytes).unwrap();
    }
    p
}

fn values(g: &Grid) -> Vec<f32> {
    (0..g.len()).map(|i| g.samples().get_f32(i)).collect()
}

/// Mdc rows of a coronal (LIA) volume, FreeSurfer's conformed orientation.
const LIA: [[f32; 3]; 3] = [[-1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]];

/// Two frames of a 3x2x2 int16 volume, gzip or not: each frame read by `timepoint`, the time
/// axis with the footer's TR, and the placement nibabel computes: columns `Mdc[j] * delta[j]`
/// and translation `c_ras - Σ column_j * dim_j / 2`, here (10, 20, 30) - (-1.5, 3, -2) =
/// (11.5, 17, 32) in RAS, so (-11.5, -17, 32) in LPS.
#[test]
fn frames_and_placement_as_nibabel() {
    let dir = tempfile::tempdir().unwrap();
    let frame = |t: i16| -> Vec<i16> { (0..12).map(|i| 1000 * t - i).collect() };
    let data: Vec<u8> = (0..2)
        .flat_map(|t| frame(t).into_iter().flat_map(i16::to_be_bytes))
        .collect();
    let bytes = mgh_bytes(
        [3, 2, 2, 2],
        4,
        1,
        [1.0, 2.0, 3.0],
        LIA,
        [10.0, 20.0, 30.0],
        &data,
        Some(2000.0),
    );
    for name in ["f.mgh", "f.mgz"] {
        let p = write(dir.path(), name, &bytes);
        assert_eq!(volux_io::detect(&p).unwrap(), Format::Mgh);
        for t in 0..2 {
            let opts = LoadOptions {
                timepoint: t,
                ..Default::default()
            };
            let (Dataset::Grid(g), _) = load(&p, &opts).unwrap() else {
                panic!("a grid")
            };
            assert_eq!(g.scalar_type(), ScalarType::I16);
            let want: Vec<f32> = frame(t as i16).iter().map(|&v| f32::from(v)).collect();
            assert_eq!(values(&g), want, "{name} frame {t}");
            assert_eq!(
                g.extra_axes()[0].describe(),
                format!("time: 2 volumes (timepoint {t} read), TR 2000 ms")
            );
            assert_eq!(g.position(0, 0, 0).to_array(), [-11.5, -17.0, 32.0]);
            assert_eq!(g.position(1, 1, 1).to_array(), [-10.5, -20.0, 30.0]);
            assert_eq!(g.spacing().to_array(), [1.0, 2.0, 3.0]);
        }
        let e = mgh::read(
            &p,
            VolumeChoice {
                timepoint: 2,
                component: None,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("timepoint 2 does not exist"), "{e}");
    }
}

/// uchar, int32 (to float32 with a note), float32 and uint16; one frame has no time axis; a
/// header without `goodRASFlag` gets nibabel's default placement with a note.
#[test]
fn types_and_default_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(i32, Vec<u8>, Vec<f32>, ScalarType); 4] = [
        (
            0,
            vec![1, 2, 250, 7],
            vec![1.0, 2.0, 250.0, 7.0],
            ScalarType::U8,
        ),
        (
            1,
            [-3i32, 1 << 25, 5, 6]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect(),
            vec![-3.0, (1 << 25) as f32, 5.0, 6.0],
            ScalarType::F32,
        ),
        (
            3,
            [0.5f32, -1.25, 3.0, 4.0]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect(),
            vec![0.5, -1.25, 3.0, 4.0],
            ScalarType::F32,
        ),
        (
            10,
            [65535u16, 1, 2, 3]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect(),
            vec![65535.0, 1.0, 2.0, 3.0],
            ScalarType::U16,
        ),
    ];
    for (code, data, want, ty) in cases {
        let bytes = mgh_bytes([2, 2, 1, 1], code, 1, [1.0; 3], LIA, [0.0; 3], &data, None);
        let p = write(dir.path(), &format!("t{code}.mgz"), &bytes);
        let g = mgh::read(&p, Default::default()).unwrap();
        assert_eq!((values(&g), g.scalar_type()), (want, ty), "type {code}");
        assert!(g.extra_axes().is_empty());
        let converted = g
            .notes()
            .iter()
            .any(|n| n.starts_with("converted from int32"));
        assert_eq!(converted, code == 1, "{:?}", g.notes());
    }
    let bytes = mgh_bytes([2, 2, 2, 1], 0, 0, [5.0; 3], LIA, [9.0; 3], &[0; 8], None);
    let g = mgh::read(
        &write(dir.path(), "bad_ras.mgh", &bytes),
        Default::default(),
    )
    .unwrap();
    assert!(g.notes().iter().any(|n| n.contains("goodRASFlag is 0")));
    assert_eq!(g.spacing().to_array(), [1.0; 3]);
    // nibabel's default: Mdc rows (-1,0,0), (0,0,1), (0,-1,0), centre 0 at voxel (1, 1, 1).
    assert_eq!(g.position(1, 1, 1).to_array(), [0.0, 0.0, 0.0]);
    assert_eq!(g.position(1, 2, 1).to_array(), [0.0, 0.0, 1.0]);
    assert_eq!(g.position(1, 1, 2).to_array(), [0.0, 1.0, 0.0]);
}

/// Malformed files are refused in one line, before reading data they cannot hold.
#[test]
fn malformed_mgh_files() {
    let dir = tempfile::tempdir().unwrap();
    let ok = |dims, code, mdc, data: &[u8]| {
        mgh_bytes(dims, code, 1, [1.0; 3], mdc, [0.0; 3], data, None)
    };
    let read =
        |name: &str, bytes: &[u8]| mgh::read(&write(dir.path(), name, bytes), Default::default());
    let kind = |r: volux_io::Result<Grid>| r.unwrap_err().kind;
    assert!(matches!(
        kind(read("short.mgh", &ok([2, 2, 2, 1], 0, LIA, &[0; 7]))),
        ErrorKind::Truncated { .. }
    ));
    assert!(matches!(
        kind(read("short.mgz", &ok([2, 2, 2, 2], 0, LIA, &[0; 9]))),
        ErrorKind::Truncated { .. }
    ));
    assert!(matches!(
        kind(read("head.mgh", &ok([2, 2, 2, 1], 0, LIA, &[])[..100])),
        ErrorKind::Truncated { .. }
    ));
    assert!(matches!(
        kind(read("type.mgh", &ok([2, 2, 2, 1], 2, LIA, &[0; 64]))),
        ErrorKind::Unsupported(_)
    ));
    assert!(matches!(
        kind(read("dims.mgh", &ok([2, -2, 2, 1], 0, LIA, &[0; 8]))),
        ErrorKind::Data(_)
    ));
    assert!(matches!(
        kind(read("frames.mgh", &ok([2, 2, 2, 0], 0, LIA, &[0; 8]))),
        ErrorKind::Header(_)
    ));
    let sheared = [[1.0, 2.0, 3.0], [2.0, 3.0, 1.0], [3.0, 1.0, 2.0]];
    let e = read("sheared.mgh", &ok([2, 2, 2, 1], 0, sheared, &[0; 8])).unwrap_err();
    assert!(e.to_string().contains("not an orthogonal grid"), "{e}");
    let mut v2 = ok([2, 2, 2, 1], 0, LIA, &[0; 8]);
    v2[3] = 2;
    assert!(matches!(
        kind(read("version.mgh", &v2)),
        ErrorKind::Header(_)
    ));
    // 2^40 voxels behind a few compressed bytes: refused before inflating.
    let e = read(
        "huge.mgz",
        &ok([1 << 14, 1 << 14, 1 << 12, 1], 0, LIA, &[0; 8]),
    )
    .unwrap_err();
    assert!(
        matches!(e.kind, ErrorKind::Undeliverable { .. } | ErrorKind::Data(_)),
        "{e}"
    );
}
