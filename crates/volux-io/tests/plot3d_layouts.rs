//! PLOT3D layouts and hostile inputs: the block-count layout in both byte orders (which the
//! file size, not the order of trial, picks), multi-block files, and coordinates that a wrong
//! byte order or a non-PLOT3D file gives (refused with how the grid was read).
use std::path::{Path, PathBuf};

use volux_io::{plot3d, ErrorKind, ReadError};

/// How a test file is written.
#[derive(Clone, Copy)]
struct Style {
    /// Byte order of the header ints.
    little: bool,
    /// Byte order of the floats (differs from `little` in a hostile file).
    float_little: bool,
    /// A leading block count of 1.
    blocks: bool,
    /// IBLANK after the coordinates.
    iblank: bool,
}

impl Style {
    fn new(little: bool, blocks: bool) -> Self {
        Style {
            little,
            float_little: little,
            blocks,
            iblank: false,
        }
    }
    fn int(&self, v: i32, out: &mut Vec<u8>) {
        out.extend(if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }
    fn float(&self, v: f32, out: &mut Vec<u8>) {
        out.extend(if self.float_little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }
    fn head(&self, out: &mut Vec<u8>) {
        if self.blocks {
            self.int(1, out);
        }
        for d in DIMS {
            self.int(d as i32, out);
        }
    }
}

const DIMS: [usize; 3] = [3, 2, 2];
const N: usize = 12;

/// The (i, j, k) index of point `p`.
fn ijk(p: usize) -> [f32; 3] {
    [p % 3, (p / 3) % 2, p / 6].map(|c| c as f32)
}

/// Where a test puts point `p`.
type Placement = fn(usize) -> [f32; 3];

/// An xyz file whose point `p` is at `at(p)`.
fn xyz(style: Style, at: impl Fn(usize) -> [f32; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    style.head(&mut out);
    for c in 0..3 {
        for p in 0..N {
            style.float(at(p)[c], &mut out);
        }
    }
    if style.iblank {
        for _ in 0..N {
            style.int(1, &mut out);
        }
    }
    out
}

/// A q file: density 2, momentum (i, 0, k), energy i + j + k.
fn q(style: Style) -> Vec<u8> {
    let mut out = Vec::new();
    style.head(&mut out);
    for h in [0.5, 10.0, 1e6, 0.0] {
        style.float(h, &mut out);
    }
    let vars: [fn([f32; 3]) -> f32; 5] =
        [|_| 2.0, |c| c[0], |_| 0.0, |c| c[2], |c| c[0] + c[1] + c[2]];
    for f in vars {
        for p in 0..N {
            style.float(f(ijk(p)), &mut out);
        }
    }
    out
}

/// Writes `gridxyz.bin` and `gridq.bin` in `dir`; returns the xyz path.
fn files(dir: &Path, xyz: &[u8], q: &[u8]) -> PathBuf {
    std::fs::write(dir.join("gridq.bin"), q).unwrap();
    let p = dir.join("gridxyz.bin");
    std::fs::write(&p, xyz).unwrap();
    p
}

fn read_err(xyz_bytes: &[u8], q_bytes: &[u8]) -> ReadError {
    let dir = tempfile::tempdir().unwrap();
    let p = files(dir.path(), xyz_bytes, q_bytes);
    match plot3d::read(&p, None, None) {
        Ok(m) => panic!("hostile file read: {} tets", m.tets().len()),
        Err(e) => e,
    }
}

/// Files with a block count of 1 are read in both byte orders, with and without IBLANK:
/// the block count is not mistaken for a dim (which the data would also fit).
#[test]
fn block_count_layout_in_both_byte_orders() {
    for little in [false, true] {
        for iblank in [false, true] {
            let mut style = Style::new(little, true);
            style.iblank = iblank;
            let dir = tempfile::tempdir().unwrap();
            let p = files(dir.path(), &xyz(style, ijk), &q(style));
            let m = plot3d::read(&p, None, Some("energy")).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(m.positions().len(), N);
            assert_eq!(m.tets().len(), 2 * 5);
            assert_eq!(m.report().degenerate, 0);
            assert_eq!(m.range(), [0.0, 4.0]);
            let notes = m.notes().join("\n");
            let order = if little { "little" } else { "big" };
            assert!(
                notes.contains(&format!("{order}-endian grid 3x2x2")),
                "{notes}"
            );
            assert_eq!(notes.contains("IBLANK present"), iblank, "{notes}");
            assert!(!notes.contains("trailing"), "{notes}");
        }
    }
}

/// Plain single-block files still read exactly as before (both byte orders).
#[test]
fn plain_layout_still_reads() {
    for little in [false, true] {
        let style = Style::new(little, false);
        let dir = tempfile::tempdir().unwrap();
        let p = files(dir.path(), &xyz(style, ijk), &q(style));
        let m = plot3d::read(&p, None, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((m.positions().len(), m.tets().len()), (N, 10));
        assert_eq!(m.range(), [2.0, 2.0]);
    }
}

/// Big-endian ints with little-endian floats (the floats of a wrong byte order): the small
/// coordinates read as subnormal garbage, which is refused with how the grid was read.
#[test]
fn floats_in_the_wrong_byte_order_are_refused() {
    let mut style = Style::new(false, false);
    style.float_little = true;
    let e = read_err(&xyz(style, ijk), &q(Style::new(false, false)));
    let m = e.to_string();
    assert!(matches!(e.kind, ErrorKind::Data(_)), "{m}");
    assert!(
        m.contains("across") && m.contains("read as big-endian 3x2x2"),
        "{m}"
    );
    assert_eq!(m.lines().count(), 1, "{m}");
}

/// Coordinates that cannot make a mesh: all equal, in one plane, not finite.
#[test]
fn unusable_coordinates_are_refused() {
    let style = Style::new(false, false);
    let qb = q(style);
    let cases: [(&str, Placement); 4] = [
        ("all 12 vertices coincide", |_| [0.0; 3]),
        ("flat", |p| {
            let [i, j, _] = ijk(p);
            [i, j, 5.0]
        }),
        ("all 10 tets are degenerate", |p| {
            // The plane x + y + z = 3, not aligned with an axis.
            let [i, j, k] = ijk(p);
            let (u, v) = (i + 0.5 * k, j + 0.25 * k);
            [u, v, 3.0 - u - v]
        }),
        ("non-finite", |p| {
            if p == 7 {
                [f32::NAN, 0.0, 0.0]
            } else {
                ijk(p)
            }
        }),
    ];
    for (want, at) in cases {
        let e = read_err(&xyz(style, at), &qb);
        let m = e.to_string();
        assert!(matches!(e.kind, ErrorKind::Data(_)), "{m}");
        assert!(m.contains(want), "{want}: {m}");
        assert!(m.contains("read as big-endian 3x2x2"), "{m}");
    }
}

/// A file of two blocks is refused as unsupported, not read as one block with trailing data.
#[test]
fn multi_block_file_is_unsupported() {
    let style = Style::new(true, false);
    let mut two = Vec::new();
    for v in [2, 3, 2, 2, 3, 2, 2] {
        style.int(v, &mut two);
    }
    for _ in 0..2 {
        for p in 0..N {
            for c in 0..3 {
                style.float(ijk(p)[c], &mut two);
            }
        }
    }
    let e = read_err(&two, &q(style));
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    assert!(
        e.to_string()
            .contains("multi-block PLOT3D file with 2 blocks"),
        "{e}"
    );
    assert!(e.path.ends_with("gridxyz.bin"), "{e}");
}

/// The q file is checked the same way: its dims must match the grid's.
#[test]
fn q_with_other_dims_is_refused() {
    let style = Style::new(false, true);
    let mut other = Vec::new();
    style.int(1, &mut other);
    for d in [2, 3, 2] {
        style.int(d, &mut other);
    }
    other.extend(&q(style)[16..]);
    let e = read_err(&xyz(style, ijk), &other);
    assert!(e.path.ends_with("gridq.bin"), "{e}");
    assert!(e.to_string().contains("q dims [2, 3, 2] differ"), "{e}");
}

/// A FIFO given as the xyz or q file is refused by its type, without opening it (opening a
/// FIFO with no writer would block forever).
#[cfg(unix)]
#[test]
fn fifo_inputs_are_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifoxyz.bin");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo unavailable: skipped");
        return;
    }
    let style = Style::new(false, false);
    let good = files(dir.path(), &xyz(style, ijk), &q(style));
    for (x, qf) in [(&fifo, dir.path().join("gridq.bin")), (&good, fifo.clone())] {
        let e = plot3d::read(x, Some(&qf), None).unwrap_err();
        assert!(matches!(e.kind, ErrorKind::NotRegular(_)), "{e}");
        assert!(e.path.ends_with("fifoxyz.bin"), "{e}");
    }
}

/// A q file that is a link to `/dev/zero` is refused by its type before any byte is read
/// (it used to be read until 4 GiB were used: the size cap trusted the metadata length, 0
/// for devices).
#[cfg(unix)]
#[test]
fn a_q_file_linked_to_dev_zero_is_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let style = Style::new(false, false);
    let good = files(dir.path(), &xyz(style, ijk), &q(style));
    let zero = dir.path().join("zeroq.bin");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let e = plot3d::read(&good, Some(&zero), None).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::NotRegular(_)), "{e}");
    assert!(e.to_string().contains("not a regular file"), "{e}");
}
