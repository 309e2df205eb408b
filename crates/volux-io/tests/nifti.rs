//! NIfTI-1 and NIfTI-2 reader tests: files written byte by byte (both byte orders, gzip or
//! not, every datatype, scaling, geometry), malformed headers and data, and a shared dataset
//! converted to `.nii.gz`. NIfTI-2 files are written as nibabel writes them (540-byte header,
//! magic `n+2\0\r\n\x1a\n`, `vox_offset` 544) from the same fields as a NIfTI-1 case,
//! and must read the same.
use std::io::Write;
use std::path::{Path, PathBuf};

use volux_core::{Samples, ScalarType};
use volux_io::{nifti, ErrorKind};
use volux_testkit::data::shared;

/// Header fields a test sets.
#[derive(Clone)]
struct Spec {
    le: bool,
    sizeof_hdr: i32,
    dim: [i16; 8],
    datatype: i16,
    bitpix: i16,
    pixdim: [f32; 8],
    vox_offset: f32,
    slope: f32,
    inter: f32,
    qform: i16,
    sform: i16,
    qoffset: [f32; 3],
    quatern: [f32; 3],
    srow: [[f32; 4]; 3],
    magic: [u8; 4],
    intent: i16,
    xyzt: u8,
}

impl Spec {
    fn new(le: bool, dims: [i16; 3], datatype: i16, bitpix: i16) -> Self {
        Spec {
            le,
            sizeof_hdr: 348,
            dim: [3, dims[0], dims[1], dims[2], 1, 1, 1, 1],
            datatype,
            bitpix,
            pixdim: [1.0, 0.5, 0.75, 2.0, 0.0, 0.0, 0.0, 0.0],
            vox_offset: 352.0,
            slope: 0.0,
            inter: 0.0,
            qform: 0,
            sform: 0,
            qoffset: [0.0; 3],
            quatern: [0.0; 3],
            srow: [[0.0; 4]; 3],
            magic: *b"n+1\0",
            intent: 0,
            xyzt: 0,
        }
    }

    fn header(&self) -> Vec<u8> {
        let mut h = vec![0u8; 348];
        let le = self.le;
        let mut put = |at: usize, b: &[u8]| {
            let mut b = b.to_vec();
            if !le {
                b.reverse();
            }
            h[at..at + b.len()].copy_from_slice(&b);
        };
        put(0, &self.sizeof_hdr.to_le_bytes());
        for (i, d) in self.dim.iter().enumerate() {
            put(40 + 2 * i, &d.to_le_bytes());
        }
        put(68, &self.intent.to_le_bytes());
        put(70, &self.datatype.to_le_bytes());
        put(72, &self.bitpix.to_le_bytes());
        put(123, &[self.xyzt]);
        for (i, p) in self.pixdim.iter().enumerate() {
            put(76 + 4 * i, &p.to_le_bytes());
        }
        put(108, &self.vox_offset.to_le_bytes());
        put(112, &self.slope.to_le_bytes());
        put(116, &self.inter.to_le_bytes());
        put(252, &self.qform.to_le_bytes());
        put(254, &self.sform.to_le_bytes());
        for (i, q) in self.quatern.iter().enumerate() {
            put(256 + 4 * i, &q.to_le_bytes());
        }
        for (i, q) in self.qoffset.iter().enumerate() {
            put(268 + 4 * i, &q.to_le_bytes());
        }
        for (r, row) in self.srow.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                put(280 + 16 * r + 4 * c, &v.to_le_bytes());
            }
        }
        h[344..348].copy_from_slice(&self.magic);
        h
    }

    /// The same fields as a 540-byte NIfTI-2 header (`nifti2.h`): dims as int64, the
    /// floats as float64 (widened exactly), the form codes as int32, magic `n+2` / `ni2` at
    /// byte 4 followed by `\r\n\x1a\n`. A NIfTI-1 `vox_offset` of 352 becomes 544.
    fn header2(&self) -> Vec<u8> {
        let mut h = vec![0u8; 540];
        let le = self.le;
        let mut put = |at: usize, b: &[u8]| {
            let mut b = b.to_vec();
            if !le {
                b.reverse();
            }
            h[at..at + b.len()].copy_from_slice(&b);
        };
        let size: i32 = if self.sizeof_hdr == 348 {
            540
        } else {
            self.sizeof_hdr
        };
        put(0, &size.to_le_bytes());
        put(12, &self.datatype.to_le_bytes());
        put(14, &self.bitpix.to_le_bytes());
        for (i, d) in self.dim.iter().enumerate() {
            put(16 + 8 * i, &i64::from(*d).to_le_bytes());
        }
        for (i, p) in self.pixdim.iter().enumerate() {
            put(104 + 8 * i, &f64::from(*p).to_le_bytes());
        }
        put(168, &(self.vox_offset2() as i64).to_le_bytes());
        put(176, &f64::from(self.slope).to_le_bytes());
        put(184, &f64::from(self.inter).to_le_bytes());
        put(500, &i32::from(self.xyzt).to_le_bytes());
        put(504, &i32::from(self.intent).to_le_bytes());
        put(344, &i32::from(self.qform).to_le_bytes());
        put(348, &i32::from(self.sform).to_le_bytes());
        for (i, q) in self.quatern.iter().enumerate() {
            put(352 + 8 * i, &f64::from(*q).to_le_bytes());
        }
        for (i, q) in self.qoffset.iter().enumerate() {
            put(376 + 8 * i, &f64::from(*q).to_le_bytes());
        }
        for (r, row) in self.srow.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                put(400 + 32 * r + 8 * c, &f64::from(*v).to_le_bytes());
            }
        }
        let magic2 = match &self.magic {
            b"n+1\0" => *b"n+2\0",
            b"ni1\0" => *b"ni2\0",
            m => *m,
        };
        h[4..8].copy_from_slice(&magic2);
        h[8..12].copy_from_slice(b"\r\n\x1a\n");
        h
    }

    /// The NIfTI-2 `vox_offset` of this case: 352 (NIfTI-1's least) moves to 544.
    fn vox_offset2(&self) -> f32 {
        if self.vox_offset == 352.0 {
            544.0
        } else {
            self.vox_offset
        }
    }

    /// The NIfTI-2 file: header, 4 extension bytes, padding up to vox_offset, data.
    fn file2(&self, data: &[u8]) -> Vec<u8> {
        let mut f = self.header2();
        f.extend_from_slice(&[0; 4]);
        f.resize(self.vox_offset2().max(544.0) as usize, 0);
        f.extend_from_slice(data);
        f
    }

    /// Header, 4 extension bytes, padding up to vox_offset, data.
    fn file(&self, data: &[u8]) -> Vec<u8> {
        let mut f = self.header();
        f.extend_from_slice(&[0; 4]);
        let off = self.vox_offset.max(352.0) as usize;
        f.resize(off, 0);
        f.extend_from_slice(data);
        f
    }
}

/// Encodes values with the given byte order.
fn enc<const N: usize>(vals: impl IntoIterator<Item = [u8; N]>, le: bool) -> Vec<u8> {
    vals.into_iter()
        .flat_map(|mut b| {
            if !le {
                b.reverse();
            }
            b
        })
        .collect()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    if name.ends_with(".gz") {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(bytes).unwrap();
        std::fs::write(&p, e.finish().unwrap()).unwrap();
    } else {
        std::fs::write(&p, bytes).unwrap();
    }
    p
}

fn values(s: &Samples) -> Vec<f32> {
    (0..s.len()).map(|i| s.get_f32(i)).collect()
}

/// 2 x 3 x 2 values 0..12 (negated for signed types to exercise the sign).
fn expected(signed: bool) -> Vec<f32> {
    (0..12)
        .map(|i| {
            if signed && i % 2 == 1 {
                -(i as f32)
            } else {
                i as f32
            }
        })
        .collect()
}

/// Every datatype x byte order x gzip.
#[test]
fn datatypes_endianness_gzip() {
    let dir = tempfile::tempdir().unwrap();
    type Enc = fn(f32, bool) -> Vec<u8>;
    let cases: [(i16, i16, Option<ScalarType>, bool, Enc); 8] = [
        (2, 8, Some(ScalarType::U8), false, |v, _| vec![v as u8]),
        (256, 8, None, true, |v, _| vec![v as i8 as u8]),
        (4, 16, Some(ScalarType::I16), true, |v, le| {
            enc([(v as i16).to_le_bytes()], le)
        }),
        (512, 16, Some(ScalarType::U16), false, |v, le| {
            enc([(v as u16).to_le_bytes()], le)
        }),
        (8, 32, None, true, |v, le| {
            enc([(v as i32).to_le_bytes()], le)
        }),
        (768, 32, None, false, |v, le| {
            enc([(v as u32).to_le_bytes()], le)
        }),
        (16, 32, Some(ScalarType::F32), true, |v, le| {
            enc([v.to_le_bytes()], le)
        }),
        (64, 64, None, true, |v, le| {
            enc([(v as f64).to_le_bytes()], le)
        }),
    ];
    for (code, bitpix, native, signed, f) in cases {
        for le in [true, false] {
            for gz in [false, true] {
                let want = expected(signed);
                let data: Vec<u8> = want.iter().flat_map(|&v| f(v, le)).collect();
                let spec = Spec::new(le, [2, 3, 2], code, bitpix);
                let name = format!("t{code}_{le}.nii{}", if gz { ".gz" } else { "" });
                let p = write(dir.path(), &name, &spec.file(&data));
                let g =
                    nifti::read(&p, Default::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_eq!(g.dims(), [2, 3, 2], "{name}");
                assert_eq!(values(g.samples()), want, "{name}");
                assert_eq!(g.spacing().to_array(), [0.5, 0.75, 2.0], "{name}");
                match native {
                    Some(t) => {
                        assert_eq!(g.scalar_type(), t, "{name}");
                        assert!(g.notes().is_empty(), "{name}: {:?}", g.notes());
                        // Uncompressed little-endian native data is memory-mapped.
                        assert_eq!(g.samples().is_mapped(), le && !gz, "{name}");
                    }
                    None => {
                        assert_eq!(g.scalar_type(), ScalarType::F32, "{name}");
                        assert!(g.notes().iter().any(|n| n.contains("converted from")));
                    }
                }
            }
        }
    }
}

#[test]
fn scl_slope_applied_as_f32() {
    let dir = tempfile::tempdir().unwrap();
    for le in [true, false] {
        let mut spec = Spec::new(le, [2, 2, 1], 4, 16);
        spec.slope = 2.0;
        spec.inter = -10.0;
        let data = enc((0..4i16).map(|v| v.to_le_bytes()), le);
        let p = write(dir.path(), "s.nii.gz", &spec.file(&data));
        let g = nifti::read(&p, Default::default()).unwrap();
        assert_eq!(g.scalar_type(), ScalarType::F32);
        assert_eq!(values(g.samples()), vec![-10.0, -8.0, -6.0, -4.0]);
        assert!(g.notes().iter().any(|n| n.contains("scl_slope")));
    }
    // Slope (1, 0) and slope 0 leave the data native.
    for (slope, inter) in [(1.0, 0.0), (0.0, 5.0)] {
        let mut spec = Spec::new(true, [2, 2, 1], 4, 16);
        (spec.slope, spec.inter) = (slope, inter);
        let data = enc((0..4i16).map(|v| v.to_le_bytes()), true);
        let p = write(dir.path(), "n.nii", &spec.file(&data));
        let g = nifti::read(&p, Default::default()).unwrap();
        assert_eq!(g.scalar_type(), ScalarType::I16);
        assert_eq!(values(g.samples()), vec![0.0, 1.0, 2.0, 3.0]);
    }
}

/// The direction matrix of `g` as its columns.
fn columns(g: &volux_core::Grid) -> [[f64; 3]; 3] {
    let d = g.direction();
    [d.x_axis, d.y_axis, d.z_axis].map(|c| c.to_array())
}

fn close(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> bool {
    (0..3).all(|c| (0..3).all(|r| (a[c][r] - b[c][r]).abs() < 1e-6))
}

#[test]
fn geometry_sform_qform_pixdim() {
    let dir = tempfile::tempdir().unwrap();
    let data = [0u8; 8];
    let mut spec = Spec::new(true, [2, 2, 2], 2, 8);
    spec.pixdim = [1.0, -1.5, 0.0, 3.0, 0.0, 0.0, 0.0, 0.0];
    spec.qform = 1;
    spec.qoffset = [7.0, 8.0, 9.0];
    let p = write(dir.path(), "q.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.spacing().to_array(), [1.5, 1.0, 3.0]);
    // RAS (7, 8, 9) is LPS (-7, -8, 9); the identity quaternion is RAS+ storage.
    assert_eq!(g.origin().to_array(), [-7.0, -8.0, 9.0]);
    assert_eq!(g.orientation_code(), "RAS");
    assert!(g.notes().iter().any(|n| n.contains("pixdim[2]")));
    // The sform wins over the qform.
    spec.sform = 2;
    spec.srow = [
        [1.5, 0.0, 0.0, -10.0],
        [0.0, 1.0, 0.0, -20.0],
        [0.0, 0.0, 3.0, -30.0],
    ];
    let p = write(dir.path(), "s.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.origin().to_array(), [10.0, 20.0, -30.0]);
    assert_eq!(g.spacing().to_array(), [1.5, 1.0, 3.0]);
    let ras = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
    assert_eq!(columns(&g), ras);
    assert!(!g.notes().iter().any(|n| n.contains("sform")));
    // A flipped sform is applied: i now runs to the left.
    spec.srow[0][0] = -1.5;
    let p = write(dir.path(), "f.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.orientation_code(), "LAS");
    assert_eq!(g.spacing().to_array(), [1.5, 1.0, 3.0]);
    // Neither: origin 0, identity.
    spec.sform = 0;
    spec.qform = 0;
    let p = write(dir.path(), "o.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.origin().to_array(), [0.0; 3]);
    assert!(g.is_axis_aligned());
}

#[test]
fn qform_quaternion_and_qfac_and_oblique_sform() {
    let dir = tempfile::tempdir().unwrap();
    let data = [0u8; 8];
    let mut spec = Spec::new(true, [2, 2, 2], 2, 8);
    // 90 degrees about z (b = c = 0, d = sin 45), qfac -1: RAS columns (0,1,0), (-1,0,0),
    // (0,0,-1); in LPS (0,-1,0) A, (1,0,0) L, (0,0,-1) I.
    spec.qform = 1;
    spec.quatern = [0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    spec.pixdim[0] = -1.0;
    let p = write(dir.path(), "q.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.orientation_code(), "ALI");
    let want = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];
    assert!(close(columns(&g), want), "{:?}", columns(&g));
    // An oblique sform, 30 degrees about x (RAS), spacing 2 along j.
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    spec.sform = 1;
    spec.srow = [
        [1.0, 0.0, 0.0, 5.0],
        [0.0, 2.0 * c, -s, 6.0],
        [0.0, 2.0 * s, c, 7.0],
    ];
    let p = write(dir.path(), "s.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    let (c, s) = (f64::from(c), f64::from(s));
    let want = [[-1.0, 0.0, 0.0], [0.0, -c, s], [0.0, s, c]];
    assert!(close(columns(&g), want), "{:?}", columns(&g));
    assert!((g.spacing().y - 2.0).abs() < 1e-6);
    assert_eq!(g.origin().to_array(), [-5.0, -6.0, 7.0]);
    // A sheared sform is noted and the qform used instead.
    spec.srow[0][1] = 0.5;
    let p = write(dir.path(), "shear.nii", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.orientation_code(), "ALI");
    assert!(
        g.notes()
            .iter()
            .any(|n| n.contains("sform is not usable") && n.contains("not orthogonal")),
        "{:?}",
        g.notes()
    );
}

#[test]
fn dims_2d_and_4d() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = Spec::new(true, [3, 2, 7], 2, 8);
    spec.dim[0] = 2;
    let p = write(dir.path(), "2d.nii", &spec.file(&[1; 6]));
    assert_eq!(
        nifti::read(&p, Default::default()).unwrap().dims(),
        [3, 2, 1]
    );
    let mut spec = Spec::new(true, [2, 2, 2], 2, 8);
    spec.dim[0] = 4;
    let p = write(dir.path(), "4d.nii", &spec.file(&[1; 8]));
    assert_eq!(
        nifti::read(&p, Default::default()).unwrap().dims(),
        [2, 2, 2]
    );
    spec.dim[4] = 3;
    let p = write(dir.path(), "4dt.nii", &spec.file(&[1; 24]));
    assert_eq!(
        nifti::read(&p, Default::default()).unwrap().dims(),
        [2, 2, 2]
    );
    spec.dim[0] = 7;
    spec.dim[6] = 2;
    let p = write(dir.path(), "7d.nii", &spec.file(&[1; 48]));
    let e = nifti::read(&p, Default::default()).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    assert!(e.to_string().contains("dim[6] is 2"), "{e}");
}

#[test]
fn hdr_img_pair() {
    let dir = tempfile::tempdir().unwrap();
    for gz in [false, true] {
        let mut spec = Spec::new(false, [2, 2, 1], 512, 16);
        spec.magic = *b"ni1\0";
        spec.vox_offset = 0.0;
        let stem = format!("pair{gz}");
        write(dir.path(), &format!("{stem}.hdr"), &spec.header());
        let data = enc((1..5u16).map(|v| v.to_le_bytes()), false);
        let img = format!("{stem}.img{}", if gz { ".gz" } else { "" });
        write(dir.path(), &img, &data);
        let g = nifti::read(&dir.path().join(format!("{stem}.hdr")), Default::default()).unwrap();
        assert_eq!(values(g.samples()), vec![1.0, 2.0, 3.0, 4.0]);
    }
    let mut spec = Spec::new(true, [2, 2, 1], 2, 8);
    spec.magic = *b"ni1\0";
    let p = write(dir.path(), "lonely.hdr", &spec.header());
    let e = nifti::read(&p, Default::default()).unwrap_err();
    assert!(e.to_string().contains("lonely.img"), "{e}");
}

#[test]
fn nan_values_are_noted() {
    let dir = tempfile::tempdir().unwrap();
    let spec = Spec::new(true, [2, 2, 1], 16, 32);
    let vals = [1.0f32, f32::NAN, 3.0, 4.0];
    let p = write(
        dir.path(),
        "nan.nii.gz",
        &spec.file(&enc(vals.map(f32::to_le_bytes), true)),
    );
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(g.range(), [1.0, 4.0]);
    assert!(g.notes().iter().any(|n| n.contains("non-finite")));
}

/// Writes `bytes` as both `.nii` and `.nii.gz` and checks that each read fails as `check` says.
fn fails(name: &str, bytes: &[u8], check: impl Fn(&ErrorKind) -> bool) {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["nii", "nii.gz"] {
        let p = write(dir.path(), &format!("{name}.{ext}"), bytes);
        match nifti::read(&p, Default::default()) {
            Ok(_) => panic!("{name}.{ext}: read a malformed file"),
            Err(e) => assert!(check(&e.kind), "{name}.{ext}: unexpected error {e}"),
        }
    }
}

#[test]
fn malformed_files() {
    let good = Spec::new(true, [4, 4, 4], 4, 16);
    let data = vec![0u8; 128];
    let header = |k: &ErrorKind| matches!(k, ErrorKind::Header(_));
    let unsupported = |k: &ErrorKind| matches!(k, ErrorKind::Unsupported(_));
    let truncated = |k: &ErrorKind| matches!(k, ErrorKind::Truncated { .. });
    let data_err = |k: &ErrorKind| matches!(k, ErrorKind::Data(_));

    fails("short_data", &good.file(&data[..100]), truncated);
    fails("short_header", &good.header()[..200], truncated);
    fails("empty", &[], truncated);
    fails("garbage", &[0xAB; 400], header);
    let mut s = good.clone();
    s.sizeof_hdr = 349;
    fails("sizeof_hdr", &s.file(&data), header);
    // A NIfTI-1 header claiming to be NIfTI-2 lacks NIfTI-2's magic.
    s.sizeof_hdr = 540;
    fails("nifti2", &s.file(&data), |k| unsupported(k) || truncated(k));
    for d0 in [0, 8, -1] {
        let mut s = good.clone();
        s.dim[0] = d0;
        fails("dim0", &s.file(&data), header);
    }
    let mut s = good.clone();
    s.dim[0] = 1;
    fails("dim0_1", &s.file(&data), unsupported);
    for bad in [[4, -4, 4], [0, 4, 4], [4, 4, 0]] {
        let mut s = good.clone();
        s.dim[1..4].copy_from_slice(&bad);
        fails("dims", &s.file(&data), data_err);
    }
    // The largest dims a NIfTI-1 header can hold: rejected before any allocation.
    let mut s = good.clone();
    s.dim[1..4].copy_from_slice(&[i16::MAX; 3]);
    s.datatype = 64;
    s.bitpix = 64;
    fails("huge", &s.file(&data), |k| {
        truncated(k) || data_err(k) || matches!(k, ErrorKind::Undeliverable { .. })
    });
    for code in [0, 3, 32, 1536, 9999] {
        let mut s = good.clone();
        s.datatype = code;
        fails("dtype", &s.file(&data), unsupported);
    }
    // Colour and 64-bit codes are read, but their bitpix must agree.
    for code in [128, 1024, 2304] {
        let mut s = good.clone();
        s.datatype = code;
        fails("dtype_bitpix", &s.file(&data), header);
    }
    let mut s = good.clone();
    s.magic = *b"abc\0";
    fails("magic", &s.file(&data), unsupported);
    for off in [f32::NAN, -352.0, 352.5] {
        let mut s = good.clone();
        s.vox_offset = off;
        fails("vox_offset", &s.file(&data), header);
    }
    let bytes = {
        let mut b = good.file(&data);
        b[108..112].copy_from_slice(&1e9f32.to_le_bytes());
        b
    };
    fails("vox_offset_past_end", &bytes, |k| {
        header(k) || truncated(k) || matches!(k, ErrorKind::Undeliverable { .. })
    });
}

/// A `bitpix` that disagrees with the datatype is refused, naming both.
#[test]
fn bitpix_mismatch_is_an_error() {
    for (code, bitpix) in [(2, 16), (16, 8), (64, 32), (4, 0), (512, -16)] {
        let spec = Spec::new(true, [2, 1, 1], code, bitpix);
        let data = vec![0u8; 16];
        let name = format!("bitpix_{code}_{bitpix}");
        fails(&name, &spec.file(&data), |k| {
            let m = k.to_string();
            matches!(k, ErrorKind::Header(_))
                && m.contains(&format!("bitpix {bitpix}"))
                && m.contains(&format!("datatype {code}"))
                && m.lines().count() == 1
        });
    }
}

/// Data longer than the dims declare is read up to the declared size, with a note giving the
/// surplus (plain files), or saying there is more (gzip); a matching file has no such note.
#[test]
fn data_longer_than_dims_is_noted() {
    let dir = tempfile::tempdir().unwrap();
    let spec = Spec::new(true, [2, 2, 1], 2, 8);
    let surplus = |p: &Path| {
        let g = nifti::read(p, Default::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(values(g.samples()), vec![1.0, 2.0, 3.0, 4.0]);
        g.notes()
            .iter()
            .find(|n| n.contains("dims 2x2x1 of uint8 declare"))
            .cloned()
    };
    let exact = write(dir.path(), "exact.nii", &spec.file(&[1, 2, 3, 4]));
    assert_eq!(surplus(&exact), None);
    let exact_gz = write(dir.path(), "exact.nii.gz", &spec.file(&[1, 2, 3, 4]));
    assert_eq!(surplus(&exact_gz), None);
    let long = spec.file(&[1, 2, 3, 4, 5, 6, 7]);
    let n = surplus(&write(dir.path(), "long.nii", &long)).unwrap();
    assert!(n.contains("holds 3 bytes more than the 4"), "{n}");
    let n = surplus(&write(dir.path(), "long.nii.gz", &long)).unwrap();
    assert!(n.contains("continues past the 4 bytes"), "{n}");
    // A time series declared as one volume: the unused dim is named.
    let mut series = spec.clone();
    series.dim[4] = 2;
    let n = surplus(&write(
        dir.path(),
        "t.nii",
        &series.file(&[1, 2, 3, 4, 1, 2, 3, 4]),
    ))
    .unwrap();
    assert!(n.contains("dim[0] is 3 but dim[4] is 2"), "{n}");
    // The same checks for a .hdr + .img pair.
    let mut pair = spec.clone();
    pair.magic = *b"ni1\0";
    pair.vox_offset = 0.0;
    let hdr = write(dir.path(), "pair.hdr", &pair.header());
    write(dir.path(), "pair.img", &[1, 2, 3, 4, 9, 9]);
    let n = surplus(&hdr).unwrap();
    assert!(n.contains("holds 2 bytes more"), "{n}");
}

/// A FIFO as the `.img` of a pair is refused by its type, without opening it.
#[cfg(unix)]
#[test]
fn fifo_image_file_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("pipe.img");
    let made = std::process::Command::new("mkfifo").arg(&img).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo unavailable: skipped");
        return;
    }
    let mut spec = Spec::new(true, [2, 2, 1], 2, 8);
    spec.magic = *b"ni1\0";
    spec.vox_offset = 0.0;
    let hdr = write(dir.path(), "pipe.hdr", &spec.header());
    let e = nifti::read(&hdr, Default::default()).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::NotRegular(_)), "{e}");
    assert!(e.path.ends_with("pipe.img"), "{e}");
}

/// The shared VTK head MR (raw + JSON sidecar) written as `.nii.gz` reads back identically.
#[test]
fn shared_head_mr_as_nii_gz() {
    let Some(raw) = shared("vtk_head_mr/HeadMRVolume_48x62x42_uint8.raw") else {
        return;
    };
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(raw.with_extension("raw.json")).unwrap()).unwrap();
    let dims: Vec<i16> = side["dims_xyz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_i64().unwrap() as i16)
        .collect();
    let spacing: Vec<f64> = side["spacing"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(side["dtype"], "uint8");
    let data = std::fs::read(raw).unwrap();
    let mut spec = Spec::new(true, [dims[0], dims[1], dims[2]], 2, 8);
    spec.pixdim[1..4].copy_from_slice(&spacing.iter().map(|&s| s as f32).collect::<Vec<_>>());
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "head.nii.gz", &spec.file(&data));
    let g = nifti::read(&p, Default::default()).unwrap();
    assert_eq!(
        g.dims(),
        [dims[0] as usize, dims[1] as usize, dims[2] as usize]
    );
    assert_eq!(g.spacing().to_array().to_vec(), spacing);
    assert_eq!(g.scalar_type(), ScalarType::U8);
    let range = side["value_range"].as_array().unwrap();
    assert_eq!(g.range()[0], range[0].as_f64().unwrap());
    assert_eq!(g.range()[1], range[1].as_f64().unwrap());
    match g.samples() {
        Samples::U8(b) => assert_eq!(&b[..], &data[..]),
        _ => unreachable!(),
    }
    // Through the format detection and `load` as well.
    let (ds, fmt) = volux_io::load(&p, &Default::default()).unwrap();
    assert_eq!(fmt, volux_io::Format::Nifti);
    assert!(matches!(ds, volux_io::Dataset::Grid(_)));
}

/// Everything a reader gives of a grid, for comparing two reads.
fn summary(g: &volux_core::Grid) -> String {
    format!(
        "{:?} {:?} {:?} {:?} {:?} {:?}",
        g.dims(),
        g.scalar_type(),
        g.spacing(),
        g.origin(),
        columns(g),
        values(g.samples())
    )
}

/// A NIfTI-2 file written from the same fields as a NIfTI-1 case (nibabel's layout) reads the
/// same grid, value for value and with the same placement: every datatype, both byte orders,
/// gzip, scaling, sform, qform with `qfac`, 2-D and 4-D dims, and `.hdr` + `.img` pairs. Its
/// notes are NIfTI-1's plus one naming the NIfTI-2 header.
#[test]
fn nifti2_reads_as_nifti1() {
    let dir = tempfile::tempdir().unwrap();
    let mut cases: Vec<(String, Spec, Vec<u8>)> = Vec::new();
    for (code, bitpix, size) in [(2, 8, 1), (256, 8, 1), (4, 16, 2), (512, 16, 2)] {
        for le in [true, false] {
            let spec = Spec::new(le, [2, 3, 2], code, bitpix);
            let data: Vec<u8> = (0..12 * size).map(|i| (i * 7 % 251) as u8).collect();
            cases.push((format!("t{code}_{le}"), spec, data));
        }
    }
    for (code, bitpix) in [(8, 32), (768, 32), (16, 32), (64, 64)] {
        let spec = Spec::new(false, [2, 3, 2], code, bitpix);
        let size = bitpix as usize / 8;
        let data: Vec<u8> = (0..12 * size).map(|i| (i % 3) as u8).collect();
        cases.push((format!("t{code}"), spec, data));
    }
    let mut scaled = Spec::new(true, [2, 2, 1], 4, 16);
    scaled.slope = 0.1;
    scaled.inter = -3.0;
    cases.push((
        "scaled".into(),
        scaled,
        enc((0..4i16).map(i16::to_le_bytes), true),
    ));
    let mut sform = Spec::new(true, [2, 2, 2], 2, 8);
    let (c, s) = (0.6f32, 0.8f32);
    sform.sform = 1;
    sform.srow = [
        [1.0, 0.0, 0.0, 5.25],
        [0.0, 2.0 * c, -s, -6.0],
        [0.0, 2.0 * s, c, 7.5],
    ];
    cases.push(("sform".into(), sform, (0..8).collect()));
    let mut qform = Spec::new(false, [2, 2, 2], 2, 8);
    qform.qform = 1;
    qform.quatern = [0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    qform.pixdim[0] = -1.0;
    qform.qoffset = [1.5, -2.0, 3.0];
    cases.push(("qform".into(), qform, (0..8).collect()));
    let mut flat = Spec::new(true, [3, 2, 9], 2, 8);
    flat.dim[0] = 2;
    cases.push(("2d".into(), flat, (0..6).collect()));
    let mut four = Spec::new(true, [2, 2, 1], 2, 8);
    four.dim[0] = 4;
    cases.push(("4d".into(), four, (0..4).collect()));
    for (name, spec, data) in &cases {
        for gz in ["", ".gz"] {
            let one = nifti::read(
                &write(dir.path(), &format!("{name}1.nii{gz}"), &spec.file(data)),
                Default::default(),
            )
            .unwrap_or_else(|e| panic!("{name} NIfTI-1: {e}"));
            let two = write(dir.path(), &format!("{name}2.nii{gz}"), &spec.file2(data));
            assert_eq!(volux_io::detect(&two).unwrap(), volux_io::Format::Nifti);
            let two = nifti::read(&two, Default::default())
                .unwrap_or_else(|e| panic!("{name} NIfTI-2: {e}"));
            assert_eq!(summary(&two), summary(&one), "{name}{gz}");
            let mut notes = one.notes().to_vec();
            notes.insert(0, "NIfTI-2 header (540 bytes, 64-bit dims)".into());
            assert_eq!(two.notes(), notes, "{name}{gz}");
        }
    }
    // A pair: 540-byte `.hdr` (magic `ni2`) and `.img`.
    let mut pair = Spec::new(false, [2, 2, 1], 4, 16);
    pair.magic = *b"ni1\0";
    pair.vox_offset = 0.0;
    let data = enc([-5i16, 6, -7, 8].map(i16::to_le_bytes), false);
    let hdr = write(dir.path(), "pair.hdr", &pair.header2());
    write(dir.path(), "pair.img", &data);
    let g = nifti::read(&hdr, Default::default()).unwrap();
    assert_eq!(values(g.samples()), vec![-5.0, 6.0, -7.0, 8.0]);
    assert_eq!(g.scalar_type(), ScalarType::I16);
}

/// NIfTI-2's 64-bit dims hold sizes NIfTI-1's int16 cannot (here 40000 voxels along x).
#[test]
fn nifti2_dims_past_int16() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = Spec::new(true, [1, 1, 1], 2, 8).header2();
    f[24..32].copy_from_slice(&40_000i64.to_le_bytes());
    f.resize(544, 0);
    f.extend((0..40_000u32).map(|i| (i % 256) as u8));
    let g = nifti::read(&write(dir.path(), "wide.nii", &f), Default::default()).unwrap();
    assert_eq!(g.dims(), [40_000, 1, 1]);
    assert_eq!(g.samples().get_f32(39_999), (39_999 % 256) as f32);
}

/// Malformed NIfTI-2 files get the same errors as NIfTI-1's, and NIfTI-2's own checks: the
/// magic's line-end signature, a NIfTI-1 magic in a 540-byte header, a header cut short, and
/// 64-bit dims far past memory, refused before any allocation.
#[test]
fn malformed_nifti2_files() {
    let good = Spec::new(true, [4, 4, 4], 4, 16);
    let data = vec![0u8; 128];
    let header = |k: &ErrorKind| matches!(k, ErrorKind::Header(_));
    let unsupported = |k: &ErrorKind| matches!(k, ErrorKind::Unsupported(_));
    let truncated = |k: &ErrorKind| matches!(k, ErrorKind::Truncated { .. });
    let data_err = |k: &ErrorKind| matches!(k, ErrorKind::Data(_));
    fails("short_data2", &good.file2(&data[..100]), truncated);
    fails("short_header2", &good.header2()[..400], truncated);
    let mut text_mode = good.file2(&data);
    text_mode[8..12].copy_from_slice(b"\n\n\x1a\n");
    fails("signature", &text_mode, |k| {
        header(k) && k.to_string().contains("text-mode")
    });
    let mut wrong_magic = good.file2(&data);
    wrong_magic[4..8].copy_from_slice(b"n+1\0");
    fails("magic2", &wrong_magic, unsupported);
    let put_dim = |i: usize, v: i64| {
        let mut f = good.file2(&data);
        f[16 + 8 * i..24 + 8 * i].copy_from_slice(&v.to_le_bytes());
        f
    };
    for (i, v) in [(0, 0), (0, 8), (0, -1), (0, i64::MAX)] {
        fails("dim0_2", &put_dim(i, v), header);
    }
    for (i, v) in [(1, -4), (2, 0), (3, i64::MIN), (1, i64::MAX), (2, 1 << 40)] {
        fails("dims2", &put_dim(i, v), |k| {
            data_err(k) || truncated(k) || matches!(k, ErrorKind::Undeliverable { .. })
        });
    }
    let mut bitpix = good.clone();
    bitpix.bitpix = 8;
    fails("bitpix2", &bitpix.file2(&data), header);
    let mut dtype = good.clone();
    dtype.datatype = 1792;
    fails("dtype2", &dtype.file2(&data), unsupported);
    let mut off = good.file2(&data);
    off[168..176].copy_from_slice(&(-544i64).to_le_bytes());
    fails("vox_offset2", &off, header);
}

// ---------- several volumes: 4-D and 5-D, colour, 64-bit integers ----------

/// The volume `t` of a 2x2x1 int16 series: `100 t + i` (negated at odd `i`).
fn series_volume(t: i16) -> Vec<i16> {
    (0..4i16)
        .map(|i| {
            if i % 2 == 1 {
                -(100 * t + i)
            } else {
                100 * t + i
            }
        })
        .collect()
}

fn as_f32(v: &[i16]) -> Vec<f32> {
    v.iter().map(|&x| f32::from(x)).collect()
}

fn choice(timepoint: usize, component: Option<usize>) -> volux_io::VolumeChoice {
    volux_io::VolumeChoice {
        timepoint,
        component,
    }
}

/// An fMRI-like series (dim[0] 4, dim[4] 3, TR 2.5 s in `xyzt_units`) is read one volume at a
/// time, in NIfTI-1 and NIfTI-2, both byte orders, gzip or not; the grid records the time
/// axis and its step; an uncompressed little-endian volume past the first is still
/// memory-mapped (at its own offset); a timepoint past the series is `NoSuchVolume`.
#[test]
fn time_series_reads_one_volume_at_a_time() {
    let dir = tempfile::tempdir().unwrap();
    for le in [true, false] {
        let mut spec = Spec::new(le, [2, 2, 1], 4, 16);
        spec.dim[0] = 4;
        spec.dim[4] = 3;
        spec.pixdim[4] = 2.5;
        spec.xyzt = 2 | 8; // mm, s
        let data: Vec<u8> = (0..3)
            .flat_map(|t| enc(series_volume(t).iter().map(|v| v.to_le_bytes()), le))
            .collect();
        for (version, bytes) in [(1, spec.file(&data)), (2, spec.file2(&data))] {
            for gz in ["", ".gz"] {
                let name = format!("fmri{le}{version}.nii{gz}");
                let p = write(dir.path(), &name, &bytes);
                for t in 0..3 {
                    let g = nifti::read(&p, choice(t, None)).unwrap_or_else(|e| panic!("{e}"));
                    assert_eq!(
                        values(g.samples()),
                        as_f32(&series_volume(t as i16)),
                        "{name}"
                    );
                    assert_eq!(g.scalar_type(), ScalarType::I16);
                    let axes = g.extra_axes();
                    assert_eq!(axes.len(), 1, "{name}");
                    assert_eq!(
                        axes[0].describe(),
                        format!("time: 3 volumes (timepoint {t} read), step 2.5 s")
                    );
                    let mapped = le && gz.is_empty();
                    assert_eq!(g.samples().is_mapped(), mapped, "{name} t={t}");
                }
                let e = nifti::read(&p, choice(3, None)).unwrap_err();
                assert!(
                    e.to_string()
                        .contains("timepoint 3 does not exist: the file holds 3 (0 to 2)"),
                    "{e}"
                );
            }
        }
    }
}

/// Through `load`: the timepoint reaches the reader, and a component asked of a file without
/// components is refused rather than ignored.
#[test]
fn load_passes_the_timepoint_and_refuses_a_component_without_axis() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = Spec::new(true, [2, 2, 1], 4, 16);
    spec.dim[0] = 4;
    spec.dim[4] = 2;
    let data: Vec<u8> = (0..2)
        .flat_map(|t| enc(series_volume(t).iter().map(|v| v.to_le_bytes()), true))
        .collect();
    let p = write(dir.path(), "s.nii", &spec.file(&data));
    let opts = volux_io::LoadOptions {
        timepoint: 1,
        ..Default::default()
    };
    let (volux_io::Dataset::Grid(g), _) = volux_io::load(&p, &opts).unwrap() else {
        panic!("a grid")
    };
    assert_eq!(values(g.samples()), as_f32(&series_volume(1)));
    // No unit and no step: a list of volumes, not time.
    assert_eq!(
        g.extra_axes()[0].describe(),
        "volumes: 2 volumes (timepoint 1 read)"
    );
    let opts = volux_io::LoadOptions {
        component: Some(1),
        ..Default::default()
    };
    let e = volux_io::load(&p, &opts).unwrap_err().to_string();
    assert!(e.contains("component 1 does not exist"), "{e}");
}

/// What dim[4] means follows the header: a statistic intent makes it a list of volumes, a
/// spectral unit (Hz) too, with its step; an FSL `.bval` beside the image gives b-values
/// (a file with the wrong count is noted and not used).
#[test]
fn the_fourth_axis_says_what_the_header_says() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = Spec::new(true, [2, 1, 1], 2, 8);
    spec.dim[0] = 4;
    spec.dim[4] = 3;
    spec.pixdim[4] = 1.5;
    let data = [1u8, 2, 3, 4, 5, 6];
    let axis = |spec: &Spec, name: &str| {
        let p = write(dir.path(), name, &spec.file(&data));
        let g = nifti::read(&p, choice(1, None)).unwrap();
        assert_eq!(values(g.samples()), vec![3.0, 4.0]);
        (g.extra_axes()[0].describe(), g.notes().to_vec())
    };
    let mut stat = spec.clone();
    stat.intent = 3; // NIFTI_INTENT_TTEST
    assert_eq!(
        axis(&stat, "stat.nii").0,
        "volumes: 3 volumes (timepoint 1 read), intent statistic"
    );
    let mut hz = spec.clone();
    hz.xyzt = 32;
    assert_eq!(
        axis(&hz, "hz.nii").0,
        "volumes: 3 volumes (timepoint 1 read), step 1.5 Hz"
    );
    let mut ms = spec.clone();
    ms.xyzt = 2 | 16;
    assert_eq!(
        axis(&ms, "ms.nii").0,
        "time: 3 volumes (timepoint 1 read), step 1.5 ms"
    );
    assert_eq!(
        axis(&spec, "nounit.nii").0,
        "time: 3 volumes (timepoint 1 read), step 1.5 (no unit given)"
    );
    std::fs::write(dir.path().join("dwi.bval"), "0 1000\t2000\n").unwrap();
    assert_eq!(
        axis(&ms, "dwi.nii").0,
        "volumes: 3 volumes (timepoint 1 read), b-value (s/mm²) from the .bval file: 0, 1000, 2000"
    );
    std::fs::write(dir.path().join("short.bval"), "0 1000\n").unwrap();
    let (text, notes) = axis(&ms, "short.nii");
    assert!(text.starts_with("time:"), "{text}");
    assert!(
        notes
            .iter()
            .any(|n| n == "short.bval holds 2 values for 3 volumes; it was not used"),
        "{notes:?}"
    );
}

/// A 5-D vector image (dim[5] 3, intent vector): `component` picks along dim[5] (default 0),
/// and with dim[4] 2 as well the volume (t, c) is the one at `c * dim[4] + t`.
#[test]
fn vector_components_along_dim5() {
    let dir = tempfile::tempdir().unwrap();
    let vol = |k: usize| -> Vec<f32> { (0..4).map(|i| (10 * k + i) as f32 + 0.5).collect() };
    for nt in [1i16, 2] {
        let mut spec = Spec::new(false, [2, 2, 1], 16, 32);
        spec.dim[0] = 5;
        spec.dim[4] = nt;
        spec.dim[5] = 3;
        spec.intent = 1007;
        let n = 3 * nt as usize;
        let data: Vec<u8> = (0..n)
            .flat_map(|k| enc(vol(k).iter().map(|v| v.to_le_bytes()), false))
            .collect();
        let p = write(dir.path(), &format!("vec{nt}.nii.gz"), &spec.file(&data));
        let g = nifti::read(&p, Default::default()).unwrap();
        assert_eq!(values(g.samples()), vol(0));
        let last = nifti::read(&p, choice(nt as usize - 1, Some(2))).unwrap();
        assert_eq!(
            values(last.samples()),
            vol(2 * nt as usize + nt as usize - 1)
        );
        let text: Vec<String> = last.extra_axes().iter().map(|a| a.describe()).collect();
        let comp = "components: 3 components (component 2 read), intent vector".to_string();
        if nt == 1 {
            assert_eq!(text, vec![comp]);
        } else {
            assert_eq!(
                text,
                vec!["volumes: 2 volumes (timepoint 1 read)".to_string(), comp]
            );
        }
        let e = nifti::read(&p, choice(0, Some(3))).unwrap_err().to_string();
        assert!(e.contains("component 3 does not exist"), "{e}");
    }
}

/// int64 and uint64 (1024, 1280) become float32 in one rounding (as numpy's cast), with a
/// note naming the conversion.
#[test]
fn int64_and_uint64_become_float32_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let big = (1i64 << 40) + 1;
    for le in [true, false] {
        let spec = Spec::new(le, [2, 2, 1], 1024, 64);
        let v = [-5i64, big, i64::MIN, 7];
        let p = write(
            dir.path(),
            &format!("i64{le}.nii"),
            &spec.file(&enc(v.map(i64::to_le_bytes), le)),
        );
        let g = nifti::read(&p, Default::default()).unwrap();
        assert_eq!(values(g.samples()), v.map(|x| x as f32).to_vec());
        assert!(
            g.notes()
                .iter()
                .any(|n| n.starts_with("converted from int64 to float32")),
            "{:?}",
            g.notes()
        );
        let spec = Spec::new(le, [2, 1, 1], 1280, 64);
        let v = [u64::MAX, 3u64];
        let p = write(
            dir.path(),
            &format!("u64{le}.nii.gz"),
            &spec.file(&enc(v.map(u64::to_le_bytes), le)),
        );
        let g = nifti::read(&p, Default::default()).unwrap();
        assert_eq!(values(g.samples()), vec![u64::MAX as f32, 3.0]);
        assert!(g.notes().iter().any(|n| n.contains("uint64 to float32")));
    }
}

/// RGB24 and RGBA32 voxels are colour: the grid keeps red, green and blue (its scalar is the
/// luminance), alpha is dropped with a note, and `component` reads one channel as a scalar.
#[test]
fn rgb24_and_rgba32_are_colour() {
    let dir = tempfile::tempdir().unwrap();
    let px: [[u8; 4]; 2] = [[255, 0, 10, 128], [0, 200, 30, 255]];
    let rgb: Vec<u8> = px.iter().flat_map(|p| p[..3].to_vec()).collect();
    let rgba: Vec<u8> = px.iter().flat_map(|p| p.to_vec()).collect();
    for (code, bitpix, data, name) in [(128, 24, rgb, "rgb.nii"), (2304, 32, rgba, "rgba.nii.gz")] {
        let p = write(
            dir.path(),
            name,
            &Spec::new(true, [2, 1, 1], code, bitpix).file(&data),
        );
        let g = nifti::read(&p, Default::default()).unwrap();
        let c = g.color().expect("colour kept");
        for (k, channel) in c.channels().iter().enumerate() {
            assert_eq!(
                values(channel),
                vec![f32::from(px[0][k]), f32::from(px[1][k])]
            );
        }
        assert_eq!(
            g.extra_axes()[0].describe(),
            "colour: 3 channels (all kept)"
        );
        let alpha_note = g
            .notes()
            .iter()
            .any(|n| n.contains("alpha channel was dropped"));
        assert_eq!(alpha_note, code == 2304, "{:?}", g.notes());
        let green = nifti::read(&p, choice(0, Some(1))).unwrap();
        assert!(green.color().is_none());
        assert_eq!(values(green.samples()), vec![0.0, 200.0]);
        assert_eq!(
            green.extra_axes()[0].describe(),
            format!("colour: {} channels (component 1 read)", bitpix / 8)
        );
    }
    let p = dir.path().join("rgba.nii.gz");
    assert_eq!(
        values(nifti::read(&p, choice(0, Some(3))).unwrap().samples()),
        vec![128.0, 255.0]
    );
    let e = nifti::read(&dir.path().join("rgb.nii"), choice(0, Some(3))).unwrap_err();
    assert!(e.to_string().contains("component 3 does not exist"), "{e}");
}

/// A pair is read whichever of its files is named: `x.img` finds `x.hdr` (and is detected as
/// NIfTI by it); a NIfTI-2 header whose image file is missing says NIfTI-2.
#[test]
fn pairs_read_through_either_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = Spec::new(true, [2, 2, 1], 2, 8);
    spec.magic = *b"ni1\0";
    spec.vox_offset = 0.0;
    write(dir.path(), "p.hdr", &spec.header());
    let img = write(dir.path(), "p.img", &[9, 8, 7, 6]);
    assert_eq!(volux_io::detect(&img).unwrap(), volux_io::Format::Nifti);
    let g = nifti::read(&img, Default::default()).unwrap();
    assert_eq!(values(g.samples()), vec![9.0, 8.0, 7.0, 6.0]);
    let p = write(dir.path(), "two.hdr", &spec.header2());
    let e = nifti::read(&p, Default::default()).unwrap_err().to_string();
    assert!(
        e.contains("this NIfTI-2 header (magic \"ni2\") puts the voxels in a separate file")
            && e.contains("two.img"),
        "{e}"
    );
}

// ---------- Analyze 7.5 ----------

/// An Analyze 7.5 header: the NIfTI-1 fields without a magic, SPM's `originator` (three
/// 1-based voxel indices at byte 253), `glmax`/`glmin` and `cal_max`/`cal_min`.
fn analyze_header(spec: &Spec, originator: [i16; 3], gl: [i32; 2], cal: [f32; 2]) -> Vec<u8> {
    let mut s = spec.clone();
    s.magic = [0; 4];
    let mut h = s.header();
    let le = spec.le;
    let mut put = |at: usize, b: &[u8]| {
        let mut b = b.to_vec();
        if !le {
            b.reverse();
        }
        h[at..at + b.len()].copy_from_slice(&b);
    };
    for (i, o) in originator.iter().enumerate() {
        put(253 + 2 * i, &o.to_le_bytes());
    }
    put(124, &cal[0].to_le_bytes());
    put(128, &cal[1].to_le_bytes());
    put(140, &gl[0].to_le_bytes());
    put(144, &gl[1].to_le_bytes());
    h
}

fn position(g: &volux_core::Grid, i: usize, j: usize, k: usize) -> [f64; 3] {
    g.position(i, j, k).to_array()
}

/// Analyze pairs are detected (either file named, both byte orders) and placed as nibabel
/// places them (`Spm99AnalyzeHeader.get_origin_affine`, whose docstring examples these are:
/// dims 3x5x7, zooms 3, 2, 1 give the RAS affine [[-3,0,0,3],[0,2,0,-4],[0,0,1,-3]] from the
/// centre, and [[-3,0,0,6],[0,2,0,-6],[0,0,1,-4]] with originator 3, 4, 5), RAS turned to LPS.
#[test]
fn analyze_pairs_are_placed_as_nibabel_places_them() {
    let dir = tempfile::tempdir().unwrap();
    for le in [true, false] {
        for (originator, ras_origin) in [
            ([0, 0, 0], [3.0, -4.0, -3.0]),
            ([3, 4, 5], [6.0, -6.0, -4.0]),
        ] {
            let mut spec = Spec::new(le, [3, 5, 7], 4, 16);
            spec.pixdim[1..4].copy_from_slice(&[3.0, 2.0, 1.0]);
            spec.vox_offset = 0.0;
            let stem = format!("a{le}{}", originator[0]);
            write(
                dir.path(),
                &format!("{stem}.hdr"),
                &analyze_header(&spec, originator, [0, 0], [0.0, 0.0]),
            );
            let v: Vec<i16> = (0..105).map(|i| i - 50).collect();
            let img = write(
                dir.path(),
                &format!("{stem}.img"),
                &enc(v.iter().map(|x| x.to_le_bytes()), le),
            );
            for p in [dir.path().join(format!("{stem}.hdr")), img] {
                assert_eq!(volux_io::detect(&p).unwrap(), volux_io::Format::Analyze);
                let (volux_io::Dataset::Grid(g), _) =
                    volux_io::load(&p, &Default::default()).unwrap()
                else {
                    panic!("a grid")
                };
                assert_eq!(values(g.samples()), as_f32(&v));
                // LPS = RAS with x and y negated.
                let lps = |[x, y, z]: [f64; 3]| [-x, -y, z];
                assert_eq!(position(&g, 0, 0, 0), lps(ras_origin));
                let step = |i, j, k, d: [f64; 3]| {
                    let p = position(&g, i, j, k);
                    let o = lps(ras_origin);
                    assert_eq!([p[0] - o[0], p[1] - o[1], p[2] - o[2]], lps(d));
                };
                step(1, 0, 0, [-3.0, 0.0, 0.0]);
                step(0, 1, 0, [0.0, 2.0, 0.0]);
                step(0, 0, 1, [0.0, 0.0, 1.0]);
                assert!(
                    g.notes()
                        .iter()
                        .any(|n| n.contains("Analyze 7.5 has no orientation")),
                    "{:?}",
                    g.notes()
                );
            }
        }
    }
}

/// SPM's scale factor (`funused1`, with `funused2` as intercept) is applied, else SPM2's
/// `cal` over `gl` ranges; a NIfTI magic in an Analyze-named read is refused.
#[test]
fn analyze_scaling_as_spm() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = Spec::new(true, [2, 2, 1], 2, 8);
    spec.vox_offset = 0.0;
    write(dir.path(), "s.img", &[0, 1, 2, 100]);
    let read = |spec: &Spec, gl, cal| {
        write(dir.path(), "s.hdr", &analyze_header(spec, [0; 3], gl, cal));
        nifti::read_analyze(&dir.path().join("s.img"), Default::default()).unwrap()
    };
    let mut scaled = spec.clone();
    scaled.slope = 0.5;
    scaled.inter = 10.0;
    let g = read(&scaled, [0, 0], [0.0, 0.0]);
    assert_eq!(values(g.samples()), vec![10.0, 10.5, 11.0, 60.0]);
    assert!(g
        .notes()
        .iter()
        .any(|n| n.contains("SPM scale factor (funused1)")));
    let g = read(&spec, [100, 0], [50.0, -50.0]);
    assert_eq!(values(g.samples()), vec![-50.0, -49.0, -48.0, 50.0]);
    assert!(g.notes().iter().any(|n| n.contains("cal_min/cal_max")));
    let g = read(&spec, [255, 0], [0.0, 0.0]);
    assert_eq!(g.scalar_type(), ScalarType::U8);
    let mut nifti_magic = spec.clone();
    nifti_magic.magic = *b"ni1\0";
    write(dir.path(), "s.hdr", &nifti_magic.header());
    let e = nifti::read_analyze(&dir.path().join("s.hdr"), Default::default()).unwrap_err();
    assert!(e.to_string().contains("it is a NIfTI file"), "{e}");
}
