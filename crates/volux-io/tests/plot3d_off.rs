//! OFF and PLOT3D readers: small files written here (every variant and malformed input) and
//! the real NASA Blunt Fin / LOx Post and VTK post data checked against their sidecars.
use std::path::{Path, PathBuf};
use volux_testkit::mutate::gzip;

use serde_json::Value;
use volux_io::{off, plot3d, ErrorKind, ReadError};
use volux_testkit::data::shared;

fn sidecar(p: &Path) -> Value {
    let s = std::fs::read_to_string(format!("{}.json", p.display())).unwrap();
    serde_json::from_str(&s).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-6)
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn msg(e: &ReadError) -> String {
    e.to_string()
}

// ---------------------------------------------------------------- OFF

const CUBE_OFF: &str = "# two tets\n5 2\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n1 1 1 5\n\
                        0 1 2 3\n1 2 4 3\n";

#[test]
fn off_plain_gzip_and_keyword() {
    let dir = tempfile::tempdir().unwrap();
    let plain = write(dir.path(), "a.off", CUBE_OFF.as_bytes());
    let gz = write(dir.path(), "a.off.gz", &gzip(CUBE_OFF.as_bytes()));
    let kw = format!("OFF\n{CUBE_OFF}\n\n");
    let kw = write(dir.path(), "b.off", kw.as_bytes());
    for p in [plain, gz, kw] {
        let m = off::read(&p).unwrap();
        assert_eq!(m.positions().len(), 5);
        assert_eq!(m.tets().len(), 2);
        assert_eq!(m.range(), [1.0, 5.0]);
        assert_eq!(m.report().inverted_reoriented, 1);
    }
}

fn off_err(text: &str) -> ReadError {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.off", text.as_bytes());
    off::read(&p).unwrap_err()
}

#[test]
fn off_malformed_inputs_are_errors() {
    // Truncated: enough bytes for the counts, but the tet lines are missing.
    let e = off_err("4 2\n0.000000 0.000000 0.000000 1.0000\n1 0 0 2\n0 1 0 3\n0 0 1 4\n0 1 2 3\n");
    assert!(matches!(e.kind, ErrorKind::Invalid(_)), "{e}");
    assert!(
        msg(&e).contains("truncated") && msg(&e).contains("1 of 2"),
        "{e}"
    );
    // Header/data size mismatch: counts need more bytes than the file has.
    let e = off_err("1000000 5000000\n0 0 0 1\n");
    assert!(msg(&e).contains("bytes"), "{e}");
    // Counts that overflow.
    let e = off_err("99999999999999999999999 1\n");
    assert!(msg(&e).contains("not a count"), "{e}");
    let e = off_err("-4 1\n");
    assert!(msg(&e).contains("not a count"), "{e}");
    // Non-numeric token, with its line.
    let e = off_err("4 1\n0 0 0 1\n1 0 0 2\n0 1 zero 3\n0 0 1 4\n0 1 2 3\n");
    assert!(
        msg(&e).contains("line 4") && msg(&e).contains("zero"),
        "{e}"
    );
    // Out-of-range index.
    let e = off_err("4 1\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n0 1 2 7\n");
    assert!(
        msg(&e).contains("line 6") && msg(&e).contains("vertex 7"),
        "{e}"
    );
    // Empty meshes.
    let e = off_err("0 0\n");
    assert!(matches!(e.kind, ErrorKind::Data(_)), "{e}");
    let e = off_err("");
    assert!(msg(&e).contains("empty"), "{e}");
    // Garbage bytes.
    let e = off_err("\u{1}\u{2}garbage\u{fffd}\u{7f} zz\n\u{0}\u{0}\n");
    assert!(matches!(e.kind, ErrorKind::Invalid(_)), "{e}");
    // Wrong value counts.
    let e = off_err("4 1\n0 0 0\n1 0 0 2\n0 1 0 3\n0 0 1 4\n0 1 2 3\n");
    assert!(msg(&e).contains("line 2"), "{e}");
    // A NaN position is rejected by the mesh validation.
    let e = off_err("4 1\n0 0 nan 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n0 1 2 3\n");
    assert!(matches!(e.kind, ErrorKind::Data(_)), "{e}");
}

#[test]
fn off_nan_scalars_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "nan.off",
        b"4 1\n0 0 0 NaN\n1 0 0 2\n0 1 0 inf\n0 0 1 4\n0 1 2 3\n",
    );
    let m = off::read(&p).unwrap();
    assert_eq!(m.report().nonfinite_scalars, 2);
    assert_eq!(m.range(), [2.0, 4.0]);
}

fn check_off_against_sidecar(rel: &str) {
    let Some(p) = shared(rel) else { return };
    let side = sidecar(&p);
    let t = std::time::Instant::now();
    let m = off::read(&p).unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "{rel}: {} tets read in {:?} (debug/test profile)",
        m.tets().len(),
        t.elapsed()
    );
    assert_eq!(
        m.positions().len() as u64,
        side["vertices"].as_u64().unwrap()
    );
    assert_eq!(m.tets().len() as u64, side["tets"].as_u64().unwrap());
    let r = f64s(&side["scalar_range"]);
    assert!(
        close(m.range()[0], r[0]) && close(m.range()[1], r[1]),
        "{:?} vs {r:?}",
        m.range()
    );
    assert_eq!(
        m.report().inverted_reoriented,
        0,
        "sidecar: all positively oriented"
    );
    if let (Some(lo), Some(hi)) = (side.get("bounds_min"), side.get("bounds_max")) {
        let b = m.bounds();
        for (a, b) in b.min.to_array().iter().zip(f64s(lo)) {
            assert!(close(*a, b), "min {a} vs {b}");
        }
        for (a, b) in b.max.to_array().iter().zip(f64s(hi)) {
            assert!(close(*a, b), "max {a} vs {b}");
        }
    }
}

#[test]
fn off_real_blunt_fin() {
    check_off_against_sidecar("nasa_blunt_fin/blunt_fin_tets_density.off.gz");
}

#[test]
fn off_real_lox_post() {
    check_off_against_sidecar("nasa_lox_post/lox_post_tets_velmag.off.gz");
}

#[test]
fn off_real_vtk_post() {
    check_off_against_sidecar("vtk_post_tets/post_tets_pressure.off");
}

// ---------------------------------------------------------------- PLOT3D

/// A 3x2x2 grid: x = i, y = j, z = k; q variables density = 2, momentum = (2i, 0, 2k),
/// energy = i + j + k.
fn small_plot3d(little: bool, iblank: bool, trailing: usize) -> (Vec<u8>, Vec<u8>) {
    let dims = [3i32, 2, 2];
    let n = 12;
    let mut xyz = Vec::new();
    let mut q = Vec::new();
    let int = |v: i32, out: &mut Vec<u8>| {
        out.extend(if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        })
    };
    let flt = |v: f32, out: &mut Vec<u8>| {
        out.extend(if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        })
    };
    for d in dims {
        int(d, &mut xyz);
        int(d, &mut q);
    }
    let ijk = |p: usize| [p % 3, (p / 3) % 2, p / 6].map(|c| c as f32);
    for c in 0..3 {
        for p in 0..n {
            flt(ijk(p)[c], &mut xyz);
        }
    }
    if iblank {
        for p in 0..n {
            int(if p == 0 { -1 } else { 1 }, &mut xyz);
        }
    }
    for h in [2.0, 0.5, 1e6, 3.0] {
        flt(h, &mut q);
    }
    let vars: [&dyn Fn([f32; 3]) -> f32; 5] =
        [&|_| 2.0, &|c| 2.0 * c[0], &|_| 0.0, &|c| 2.0 * c[2], &|c| {
            c[0] + c[1] + c[2]
        }];
    for f in vars {
        for p in 0..n {
            flt(f(ijk(p)), &mut q);
        }
    }
    q.extend(std::iter::repeat_n(0u8, trailing));
    (xyz, q)
}

fn plot3d_files(dir: &Path, files: (Vec<u8>, Vec<u8>)) -> PathBuf {
    write(dir, "smallq.bin", &files.1);
    write(dir, "smallxyz.bin", &files.0)
}

#[test]
fn plot3d_small_variants() {
    for (little, iblank, trailing) in [(false, false, 0), (true, false, 0), (false, true, 484)] {
        let dir = tempfile::tempdir().unwrap();
        let xyz = plot3d_files(dir.path(), small_plot3d(little, iblank, trailing));
        let m = plot3d::read(&xyz, None, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.positions().len(), 12);
        assert_eq!(m.tets().len(), 2 * 5);
        assert_eq!(m.range(), [2.0, 2.0]);
        let notes = m.notes().join("\n");
        assert_eq!(notes.contains("IBLANK present: 1 of 12"), iblank, "{notes}");
        assert_eq!(
            notes.contains("484 trailing bytes"),
            trailing > 0,
            "{notes}"
        );
        let e = plot3d::read(&xyz, None, Some("energy")).unwrap();
        assert_eq!(e.range(), [0.0, 4.0]);
        let v = plot3d::read(&xyz, None, Some("velocity-magnitude")).unwrap();
        // |(2i, 0, 2k)| / 2 = |(i, k)|, max at i = 2, k = 1.
        assert!((v.range()[1] - 5f64.sqrt()).abs() < 1e-6, "{:?}", v.range());
        let mx = plot3d::read(&xyz, Some(&dir.path().join("smallq.bin")), Some("1")).unwrap();
        assert_eq!(mx.range(), [0.0, 4.0]);
    }
}

#[test]
fn plot3d_malformed_inputs_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (xyz, q) = small_plot3d(false, false, 0);
    // Unknown variable: the message lists the names.
    let p = plot3d_files(dir.path(), (xyz.clone(), q.clone()));
    let e = plot3d::read(&p, None, Some("pressure")).unwrap_err();
    assert!(msg(&e).contains("velocity-magnitude"), "{e}");
    // Truncated xyz and q.
    let p = plot3d_files(dir.path(), (xyz[..xyz.len() - 8].to_vec(), q.clone()));
    assert!(matches!(
        plot3d::read(&p, None, None).unwrap_err().kind,
        ErrorKind::Header(_)
    ));
    let p = plot3d_files(dir.path(), (xyz.clone(), q[..q.len() - 1].to_vec()));
    let e = plot3d::read(&p, None, None).unwrap_err();
    assert!(
        e.path.ends_with("smallq.bin") && msg(&e).contains("plausible"),
        "{e}"
    );
    // q dims differ from xyz dims.
    let mut q2 = q.clone();
    q2[3] = 2;
    q2[7] = 3;
    let p = plot3d_files(dir.path(), (xyz.clone(), q2));
    assert!(msg(&plot3d::read(&p, None, None).unwrap_err()).contains("differ"));
    // Dims whose product overflows, zero and negative dims, garbage.
    for head in [
        [
            0x7f, 0xff, 0xff, 0xff, 0x7f, 0xff, 0xff, 0xff, 0x7f, 0xff, 0xff, 0xff,
        ],
        [0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 2],
        [0xff, 0xff, 0xff, 0xfd, 0, 0, 0, 2, 0, 0, 0, 2],
        *b"garbage-byte",
    ] {
        let mut x = head.to_vec();
        x.extend(&xyz[12..]);
        let p = plot3d_files(dir.path(), (x, q.clone()));
        assert!(matches!(
            plot3d::read(&p, None, None).unwrap_err().kind,
            ErrorKind::Header(_)
        ));
    }
    // A grid one point thick has no cells.
    let mut flat = xyz.clone();
    flat[11] = 1;
    let mut qf = q.clone();
    qf[11] = 1;
    let p = plot3d_files(dir.path(), (flat, qf));
    assert!(matches!(
        plot3d::read(&p, None, None).unwrap_err().kind,
        ErrorKind::Data(_)
    ));
    // Missing q file.
    let p = write(dir.path(), "onlyxyz.bin", &xyz);
    assert!(matches!(
        plot3d::read(&p, None, None).unwrap_err().kind,
        ErrorKind::Io(_)
    ));
    // No 'xyz' in the name and no q file given.
    let p = write(dir.path(), "grid.bin", &xyz);
    assert!(plot3d::read(&p, None, None).is_err());
}

#[test]
fn plot3d_nan_values_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let (xyz, mut q) = small_plot3d(false, false, 0);
    q[28..32].copy_from_slice(&f32::NAN.to_be_bytes());
    let p = plot3d_files(dir.path(), (xyz.clone(), q));
    let m = plot3d::read(&p, None, None).unwrap();
    assert_eq!(m.report().nonfinite_scalars, 1);
    let mut x = xyz;
    x[12..16].copy_from_slice(&f32::NAN.to_be_bytes());
    let (_, q) = small_plot3d(false, false, 0);
    let p = plot3d_files(dir.path(), (x, q));
    assert!(matches!(
        plot3d::read(&p, None, None).unwrap_err().kind,
        ErrorKind::Data(_)
    ));
}

fn check_plot3d(xyz: &str, var: &str, off_rel: &str) {
    let (Some(p), Some(off_path)) = (shared(xyz), shared(off_rel)) else {
        return;
    };
    let side = sidecar(&off_path);
    let m = plot3d::read(&p, None, Some(var)).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{xyz}: notes {:?}", m.notes());
    assert_eq!(
        m.positions().len() as u64,
        side["vertices"].as_u64().unwrap()
    );
    assert_eq!(m.tets().len() as u64, side["tets"].as_u64().unwrap());
    let r = f64s(&side["scalar_range"]);
    assert!(
        close(m.range()[0], r[0]) && close(m.range()[1], r[1]),
        "{:?} vs {r:?}",
        m.range()
    );
    let b = m.bounds();
    for (a, b) in b.min.to_array().iter().zip(f64s(&side["bounds_min"])) {
        assert!(close(*a, b), "min {a} vs {b}");
    }
    for (a, b) in b.max.to_array().iter().zip(f64s(&side["bounds_max"])) {
        assert!(close(*a, b), "max {a} vs {b}");
    }
    // Same vertices and scalars as the OFF mesh derived from the same files.
    // (The OFF text keeps about 7 significant digits.)
    let o = off::read(&off_path).unwrap();
    assert_eq!(m.positions().len(), o.positions().len());
    for (i, (a, b)) in m.positions().iter().zip(o.positions()).enumerate() {
        assert!(
            (*a - *b).abs().max_element() <= 1e-5 * (1.0 + a.abs().max_element()),
            "vertex {i}: {a} vs {b}"
        );
    }
    for (a, b) in m.scalars().iter().zip(o.scalars()) {
        assert!(close(*a as f64, *b as f64), "{a} vs {b}");
    }
}

#[test]
fn plot3d_real_blunt_fin_matches_off() {
    check_plot3d(
        "nasa_blunt_fin/bluntfinxyz.bin",
        "density",
        "nasa_blunt_fin/blunt_fin_tets_density.off.gz",
    );
}

#[test]
fn plot3d_real_lox_post_matches_off() {
    check_plot3d(
        "nasa_lox_post/postxyz.bin",
        "velocity-magnitude",
        "nasa_lox_post/lox_post_tets_velmag.off.gz",
    );
}

/// Deterministic byte mutations (flips, truncations) of valid files never panic.
#[test]
fn mutated_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut mutate = |seed: &[u8]| {
        let mut b = seed.to_vec();
        for _ in 0..1 + next() % 4 {
            let i = (next() % b.len() as u64) as usize;
            b[i] = match next() % 3 {
                0 => next() as u8,
                1 => b"0123456789 -.e\n#"[(next() % 16) as usize],
                _ => b[i] ^ 0x80,
            };
        }
        if next() % 4 == 0 {
            b.truncate((next() % b.len() as u64) as usize);
        }
        b
    };
    for _ in 0..200 {
        let p = write(dir.path(), "m.off", &mutate(CUBE_OFF.as_bytes()));
        let _ = off::read(&p);
    }
    let (xyz, q) = small_plot3d(false, true, 4);
    for _ in 0..200 {
        let p = plot3d_files(dir.path(), (mutate(&xyz), mutate(&q)));
        let _ = plot3d::read(&p, None, Some("velocity-magnitude"));
    }
}
