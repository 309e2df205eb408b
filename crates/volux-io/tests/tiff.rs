//! TIFF stacks: multi-page files written here with the `tiff` crate's encoder (every
//! compression and sample type, ImageJ and OME-XML descriptions), numbered slice folders, the
//! small `tifffile` fixtures of `tests/fixtures/tiff/` (see `make_fixtures.py`), and hostile
//! files (truncated, lying sizes), which must fail cleanly.
use std::io::Cursor;
use std::path::{Path, PathBuf};

use tiff::encoder::{colortype, compression::DeflateLevel, Compression, Rational, TiffEncoder};
use tiff::tags::{ResolutionUnit, Tag};
use volux_core::{Grid, ScalarType};
use volux_io::{detect, load, Dataset, ErrorKind, Format, LoadOptions};

/// The value of voxel (x, y, z) in channel c, timepoint t (also `make_fixtures.py`'s formula).
fn value(x: usize, y: usize, z: usize, c: usize, t: usize) -> f64 {
    (x + 10 * y + 100 * z + 1000 * c + 3000 * t) as f64
}

/// One page of `value` at (z, c, t), `w` x `h`, converted by `f`.
fn page<T>(w: usize, h: usize, (z, c, t): (usize, usize, usize), f: impl Fn(f64) -> T) -> Vec<T> {
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| f(value(x, y, z, c, t)))
        .collect()
}

/// How a test file's first page is annotated.
#[derive(Default, Clone)]
struct Meta {
    description: Option<String>,
    /// Pixels per unit in x and y, and the unit.
    resolution: Option<(f64, f64, ResolutionUnit)>,
}

/// Writes `pages` (each `w` x `h`) as a multi-page TIFF of colour type `C`.
fn tiff_bytes<C: colortype::ColorType>(
    w: usize,
    h: usize,
    pages: &[Vec<C::Inner>],
    compression: Compression,
    meta: &Meta,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut out = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut out)
        .unwrap()
        .with_compression(compression);
    for (i, p) in pages.iter().enumerate() {
        let mut img = enc.new_image::<C>(w as u32, h as u32).unwrap();
        if i == 0 {
            if let Some(d) = &meta.description {
                img.encoder()
                    .write_tag(Tag::ImageDescription, d.as_str())
                    .unwrap();
            }
        }
        if let Some((xr, yr, unit)) = meta.resolution {
            let r = |v: f64| Rational {
                n: (v * 1000.0).round() as u32,
                d: 1000,
            };
            img.resolution_unit(unit);
            img.x_resolution(r(xr));
            img.y_resolution(r(yr));
        }
        img.write_data(p).unwrap();
    }
    out.into_inner()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn read(path: &Path, channel: usize, timepoint: usize) -> volux_io::Result<Grid> {
    let opts = LoadOptions {
        channel,
        timepoint,
        ..LoadOptions::default()
    };
    let (d, f) = load(path, &opts)?;
    assert_eq!(f, Format::Tiff);
    match d {
        Dataset::Grid(g) => Ok(g),
        _ => panic!("not a grid"),
    }
}

/// Checks every voxel of `g` against `value` at channel `c`, timepoint `t`.
fn check_values(g: &Grid, c: usize, t: usize, conv: impl Fn(f64) -> f64) {
    let [w, h, d] = g.dims();
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                assert_eq!(
                    g.value(x, y, z) as f64,
                    conv(value(x, y, z, c, t)),
                    "voxel ({x}, {y}, {z})"
                );
            }
        }
    }
}

fn notes(g: &Grid) -> String {
    g.notes().join(" | ")
}

#[test]
fn multipage_u16_lzw_stack() {
    let dir = tempfile::tempdir().unwrap();
    let pages: Vec<Vec<u16>> = (0..5)
        .map(|z| page(16, 12, (z, 0, 0), |v| v as u16))
        .collect();
    let bytes = tiff_bytes::<colortype::Gray16>(16, 12, &pages, Compression::Lzw, &Meta::default());
    let p = write(dir.path(), "stack.tif", &bytes);
    let g = read(&p, 0, 0).unwrap();
    assert_eq!(g.dims(), [16, 12, 5]);
    assert_eq!(g.scalar_type(), ScalarType::U16);
    assert_eq!(g.spacing().to_array(), [1.0; 3]);
    check_values(&g, 0, 0, |v| v);
    let n = notes(&g);
    assert!(
        n.contains("5 pages, LZW compression, 16-bit unsigned"),
        "{n}"
    );
    assert!(n.contains("no spacing information"), "{n}");
    // The magic bytes decide without the extension too.
    let q = write(dir.path(), "stack.bin", &bytes);
    assert_eq!(detect(&q).unwrap(), Format::Tiff);
}

#[test]
fn every_compression_and_sample_type() {
    let dir = tempfile::tempdir().unwrap();
    let comps = [
        ("none", Compression::Uncompressed, "uncompressed"),
        ("lzw", Compression::Lzw, "LZW compression"),
        (
            "deflate",
            Compression::Deflate(DeflateLevel::Balanced),
            "Deflate compression",
        ),
        ("packbits", Compression::Packbits, "PackBits compression"),
    ];
    let (w, h, d) = (7, 5, 3);
    for (name, comp, words) in comps {
        let m = Meta::default();
        let u8s: Vec<Vec<u8>> = (0..d)
            .map(|z| page(w, h, (z, 0, 0), |v| (v as u32 % 251) as u8))
            .collect();
        let i16s: Vec<Vec<i16>> = (0..d)
            .map(|z| page(w, h, (z, 0, 0), |v| -(v as i16)))
            .collect();
        let f32s: Vec<Vec<f32>> = (0..d)
            .map(|z| page(w, h, (z, 0, 0), |v| v as f32 * 0.25))
            .collect();
        let cases = [
            (
                "u8",
                tiff_bytes::<colortype::Gray8>(w, h, &u8s, comp, &m),
                ScalarType::U8,
                "8-bit unsigned",
            ),
            (
                "i16",
                tiff_bytes::<colortype::GrayI16>(w, h, &i16s, comp, &m),
                ScalarType::I16,
                "16-bit signed",
            ),
            (
                "f32",
                tiff_bytes::<colortype::Gray32Float>(w, h, &f32s, comp, &m),
                ScalarType::F32,
                "32-bit float",
            ),
        ];
        for (ty, bytes, st, tw) in cases {
            let p = write(dir.path(), &format!("{name}_{ty}.tiff"), &bytes);
            let g = read(&p, 0, 0).unwrap_or_else(|e| panic!("{name} {ty}: {e}"));
            assert_eq!(g.dims(), [w, h, d]);
            assert_eq!(g.scalar_type(), st);
            let conv: Box<dyn Fn(f64) -> f64> = match st {
                ScalarType::U8 => Box::new(|v| (v as u32 % 251) as f64),
                ScalarType::I16 => Box::new(|v| -v),
                _ => Box::new(|v| v * 0.25),
            };
            check_values(&g, 0, 0, conv);
            let n = notes(&g);
            assert!(n.contains(&format!("{words}, {tw}")), "{name} {ty}: {n}");
        }
    }
}

#[test]
fn imagej_hyperstack_chooses_channel_and_timepoint() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, cs, zs, ts) = (6, 4, 2, 3, 2);
    // ImageJ stores hyperstacks in CZT order: channel fastest, then z, then t.
    let mut pages = Vec::new();
    for t in 0..ts {
        for z in 0..zs {
            for c in 0..cs {
                pages.push(page(w, h, (z, c, t), |v| v as u16));
            }
        }
    }
    let meta = Meta {
        description: Some(format!(
            "ImageJ=1.54f\nimages={}\nchannels={cs}\nslices={zs}\nframes={ts}\nhyperstack=true\nunit=micron\nspacing=0.5\nloop=false\n",
            cs * zs * ts
        )),
        resolution: Some((4.0, 2.0, ResolutionUnit::None)),
    };
    let bytes = tiff_bytes::<colortype::Gray16>(
        w,
        h,
        &pages,
        Compression::Deflate(DeflateLevel::Fast),
        &meta,
    );
    let p = write(dir.path(), "hyper.tif", &bytes);
    for (c, t) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let g = read(&p, c, t).unwrap();
        assert_eq!(g.dims(), [w, h, zs]);
        assert_eq!(g.spacing().to_array(), [0.25, 0.5, 0.5]);
        check_values(&g, c, t, |v| v);
        let n = notes(&g);
        assert!(n.contains("micrometres") && n.contains("ImageJ"), "{n}");
        assert!(n.contains(&format!("channel {c}, timepoint {t}")), "{n}");
    }
    let e = read(&p, 2, 0).unwrap_err().to_string();
    assert!(e.contains("--channel 2") && e.contains("2 channels"), "{e}");
    let e = read(&p, 0, 5).unwrap_err().to_string();
    assert!(e.contains("2 timepoints"), "{e}");
}

/// An OME-XML description for a `w` x `h` stack of `z` x `c` x `t` planes.
fn ome_xml(
    w: usize,
    h: usize,
    (z, c, t): (usize, usize, usize),
    order: &str,
    extra: &str,
) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OME xmlns="http://www.openmicroscopy.org/Schemas/OME/2016-06" Creator="volux test"><Image ID="Image:0" Name="t"><Pixels ID="Pixels:0" DimensionOrder="{order}" Type="uint8" SizeX="{w}" SizeY="{h}" SizeZ="{z}" SizeC="{c}" SizeT="{t}" {extra}><Channel ID="Channel:0:0"/><TiffData/></Pixels></Image></OME>"#
    )
}

#[test]
fn ome_tiff_dimension_order_and_physical_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, zs, cs) = (5, 4, 4, 3);
    // XYZCT: z fastest, then channel.
    let mut pages = Vec::new();
    for c in 0..cs {
        for z in 0..zs {
            pages.push(page(w, h, (z, c, 0), |v| (v as u32 % 256) as u8));
        }
    }
    let meta = Meta {
        description: Some(ome_xml(
            w,
            h,
            (zs, cs, 1),
            "XYZCT",
            r#"PhysicalSizeX="250" PhysicalSizeXUnit="nm" PhysicalSizeY="0.25" PhysicalSizeZ="0.002" PhysicalSizeZUnit="mm""#,
        )),
        resolution: None,
    };
    let bytes = tiff_bytes::<colortype::Gray8>(w, h, &pages, Compression::Packbits, &meta);
    let p = write(dir.path(), "cells.ome.tif", &bytes);
    for c in 0..cs {
        let g = read(&p, c, 0).unwrap();
        assert_eq!(g.dims(), [w, h, zs]);
        let s = g.spacing().to_array();
        for (a, b) in s.iter().zip([0.25, 0.25, 2.0]) {
            assert!((a - b).abs() < 1e-9, "{s:?}");
        }
        check_values(&g, c, 0, |v| (v as u32 % 256) as f64);
        let n = notes(&g);
        assert!(n.contains("OME") && n.contains("micrometres"), "{n}");
    }
    let e = read(&p, 3, 0).unwrap_err().to_string();
    assert!(e.contains("3 channels"), "{e}");
    let e = read(&p, 0, 1).unwrap_err().to_string();
    assert!(e.contains("1 timepoint "), "{e}");
}

#[test]
fn plain_resolution_tags_give_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let pages: Vec<Vec<u8>> = (0..2).map(|z| page(3, 3, (z, 0, 0), |v| v as u8)).collect();
    let meta = Meta {
        description: None,
        resolution: Some((1000.0, 500.0, ResolutionUnit::Centimeter)),
    };
    let bytes = tiff_bytes::<colortype::Gray8>(3, 3, &pages, Compression::Uncompressed, &meta);
    let p = write(dir.path(), "plain.tif", &bytes);
    let g = read(&p, 0, 0).unwrap();
    assert_eq!(g.spacing().to_array(), [10.0, 20.0, 10.0]);
    assert!(notes(&g).contains("pixels per cm"), "{}", notes(&g));
    let e = read(&p, 1, 0).unwrap_err().to_string();
    assert!(e.contains("1 channel "), "{e}");
}

#[test]
fn numbered_folder_in_natural_order() {
    let dir = tempfile::tempdir().unwrap();
    let slices = dir.path().join("slices");
    std::fs::create_dir(&slices).unwrap();
    for z in 0..12 {
        let p = vec![page(4, 3, (z, 0, 0), |v| v as u16)];
        let bytes = tiff_bytes::<colortype::Gray16>(4, 3, &p, Compression::Lzw, &Meta::default());
        // slice_1 ... slice_12: lexical order would put slice_10 before slice_2.
        write(&slices, &format!("slice_{}.tif", z + 1), &bytes);
    }
    write(&slices, "notes.txt", b"not a slice");
    assert_eq!(detect(&slices).unwrap(), Format::Tiff);
    let g = read(&slices, 0, 0).unwrap();
    assert_eq!(g.dims(), [4, 3, 12]);
    check_values(&g, 0, 0, |v| v);
    assert!(
        notes(&g).contains("12 slices, LZW compression"),
        "{}",
        notes(&g)
    );
    // A slice of another size is named.
    let odd = vec![page(5, 3, (0, 0, 0), |v| v as u16)];
    let bytes = tiff_bytes::<colortype::Gray16>(5, 3, &odd, Compression::Lzw, &Meta::default());
    write(&slices, "slice_7.tif", &bytes);
    let e = read(&slices, 0, 0).unwrap_err().to_string();
    assert!(e.contains("slice_7.tif") && e.contains("5x3"), "{e}");
    // A folder of other files stays DICOM.
    let other = dir.path().join("dicom");
    std::fs::create_dir(&other).unwrap();
    write(&other, "IM0001", b"x");
    write(&other, "IM0002", b"x");
    write(&other, "preview.tif", b"x");
    assert_eq!(detect(&other).unwrap(), Format::Dicom);
}

#[test]
fn colour_pages_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = vec![vec![0u8; 4 * 4 * 3]];
    let bytes =
        tiff_bytes::<colortype::RGB8>(4, 4, &rgb, Compression::Uncompressed, &Meta::default());
    let p = write(dir.path(), "rgb.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    assert!(e.to_string().contains("grayscale"), "{e}");
}

/// The byte offset of the value of tag `tag` in the first IFD of a little-endian TIFF.
fn tag_value_at(bytes: &[u8], tag: u16) -> usize {
    let ifd = u32::from_le_bytes(bytes[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(bytes[ifd..ifd + 2].try_into().unwrap()) as usize;
    (0..n)
        .map(|i| ifd + 2 + 12 * i)
        .find(|&e| u16::from_le_bytes(bytes[e..e + 2].try_into().unwrap()) == tag)
        .map(|e| e + 8)
        .expect("tag present")
}

#[test]
fn hostile_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let pages: Vec<Vec<u16>> = (0..4)
        .map(|z| page(32, 32, (z, 0, 0), |v| v as u16))
        .collect();
    for comp in [
        Compression::Uncompressed,
        Compression::Lzw,
        Compression::Deflate(DeflateLevel::Fast),
    ] {
        let bytes = tiff_bytes::<colortype::Gray16>(32, 32, &pages, comp, &Meta::default());
        // Truncated anywhere: an error or (when only the last IFD link is cut) a grid, never a panic.
        for cut in (0..bytes.len()).step_by(97) {
            let p = write(dir.path(), "cut.tif", &bytes[..cut]);
            let _ = read(&p, 0, 0);
        }
        // A width and height far beyond what the file holds: refused before allocating.
        let mut big = bytes.clone();
        for tag in [256u16, 257, 278] {
            let at = tag_value_at(&big, tag);
            big[at..at + 2].copy_from_slice(&60000u16.to_le_bytes());
        }
        let p = write(dir.path(), "big.tif", &big);
        let e = read(&p, 0, 0).unwrap_err();
        assert!(
            matches!(e.kind, ErrorKind::Undeliverable { .. } | ErrorKind::Data(_)),
            "{e}"
        );
    }
    // A lying ImageJ description.
    let meta = Meta {
        description: Some("ImageJ=1.54f\nimages=40\nslices=40\n".into()),
        resolution: None,
    };
    let bytes = tiff_bytes::<colortype::Gray16>(32, 32, &pages, Compression::Lzw, &meta);
    let p = write(dir.path(), "lying.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err().to_string();
    assert!(e.contains("4 pages"), "{e}");
    // A lying OME description.
    let meta = Meta {
        description: Some(ome_xml(32, 32, (9, 1, 1), "XYZCT", "").replace("uint8", "uint16")),
        resolution: None,
    };
    let bytes = tiff_bytes::<colortype::Gray16>(32, 32, &pages, Compression::Lzw, &meta);
    let p = write(dir.path(), "lying.ome.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err().to_string();
    assert!(e.contains("4 pages"), "{e}");
}

/// The committed `tifffile` fixtures.
fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/tiff")
        .join(name)
}

#[test]
fn tifffile_imagej_hyperstack() {
    let p = fixture("imagej_hyperstack.tif");
    for (c, t) in [(0, 0), (1, 2), (0, 1)] {
        let g = read(&p, c, t).unwrap();
        assert_eq!(g.dims(), [16, 12, 5]);
        assert_eq!(g.spacing().to_array(), [0.25, 0.5, 1.5]);
        check_values(&g, c, t, |v| v);
    }
    let e = read(&p, 0, 3).unwrap_err().to_string();
    assert!(e.contains("3 timepoints"), "{e}");
}

#[test]
fn tifffile_ome_two_channels() {
    let p = fixture("two_channels.ome.tif");
    for c in 0..2 {
        let g = read(&p, c, 0).unwrap();
        assert_eq!(g.dims(), [16, 12, 5]);
        let s = g.spacing().to_array();
        for (a, b) in s.iter().zip([0.2, 0.2, 1.0]) {
            assert!((a - b).abs() < 1e-9, "{s:?}");
        }
        check_values(&g, c, 0, |v| v);
        let n = notes(&g);
        assert!(n.contains("XYCZT") && n.contains("micrometres"), "{n}");
    }
    let e = read(&p, 2, 0).unwrap_err().to_string();
    assert!(e.contains("2 channels"), "{e}");
}

#[test]
fn tifffile_compressions_and_types() {
    type Case = (&'static str, ScalarType, &'static str, fn(f64) -> f64);
    let cases: [Case; 4] = [
        ("lzw_u16.tif", ScalarType::U16, "LZW compression", |v| v),
        (
            "deflate_u8.tif",
            ScalarType::U8,
            "Deflate compression",
            |v| v % 251.0,
        ),
        ("float32.tif", ScalarType::F32, "Deflate compression", |v| {
            v / 2.0
        }),
        ("int16_be.tif", ScalarType::I16, "uncompressed", |v| -v),
    ];
    for (name, ty, comp, conv) in cases {
        let g = read(&fixture(name), 0, 0).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.dims(), [16, 12, 5], "{name}");
        assert_eq!(g.scalar_type(), ty, "{name}");
        check_values(&g, 0, 0, conv);
        let n = notes(&g);
        assert!(n.contains(comp), "{name}: {n}");
    }
}

/// Random corruptions (bytes set to boundary values, bit flips, cuts) of an LZW stack, a
/// Deflate ImageJ hyperstack and a PackBits OME-TIFF, read in-process: an error or a grid,
/// never a panic. `VOLUX_TIFF_CORRUPTIONS=N` runs N cases per file (default 700).
#[test]
fn random_corruptions_never_panic() {
    let cases = std::env::var("VOLUX_TIFF_CORRUPTIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(700);
    let dir = tempfile::tempdir().unwrap();
    let pages: Vec<Vec<u16>> = (0..4)
        .map(|z| page(9, 7, (z, 0, 0), |v| v as u16))
        .collect();
    let lzw = tiff_bytes::<colortype::Gray16>(9, 7, &pages, Compression::Lzw, &Meta::default());
    let ij = Meta {
        description: Some(
            "ImageJ=1.54f\nimages=4\nchannels=2\nslices=2\nunit=micron\nspacing=2\n".into(),
        ),
        resolution: Some((2.0, 2.0, ResolutionUnit::None)),
    };
    let hyper = tiff_bytes::<colortype::Gray16>(
        9,
        7,
        &pages,
        Compression::Deflate(DeflateLevel::Fast),
        &ij,
    );
    let ome = Meta {
        description: Some(ome_xml(9, 7, (2, 2, 1), "XYCZT", r#"PhysicalSizeX="1""#)),
        resolution: None,
    };
    let u8s: Vec<Vec<u8>> = (0..4).map(|z| page(9, 7, (z, 0, 0), |v| v as u8)).collect();
    let ome = tiff_bytes::<colortype::Gray8>(9, 7, &u8s, Compression::Packbits, &ome);
    let mut rng = volux_testkit::TestRng::new(0x7469_6666);
    let mut grids = 0;
    for (name, seed) in [("a.tif", &lzw), ("b.tif", &hyper), ("c.ome.tif", &ome)] {
        for _ in 0..cases {
            let mut bytes = seed.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                match rng.below(4) {
                    0 => bytes[at] ^= 1 << rng.below(8),
                    1 => bytes[at] = [0, 0xff, 0x7f, 0x80][rng.below(4)],
                    2 => {
                        let v = [0u32, 1, 0xffff, 0x7fff_ffff, 0xffff_ffff][rng.below(5)];
                        let end = (at + 4).min(bytes.len());
                        bytes[at..end].copy_from_slice(&v.to_le_bytes()[..end - at]);
                    }
                    _ => bytes.truncate(at.max(8)),
                }
            }
            let p = write(dir.path(), name, &bytes);
            if volux_io::tiff::read(&p, 0, 0).is_ok() {
                grids += 1;
            }
        }
    }
    assert!(grids > 0);
}

#[test]
fn bigtiff_stack() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new_big(&mut out)
        .unwrap()
        .with_compression(Compression::Lzw);
    for z in 0..3 {
        let p: Vec<u16> = page(5, 4, (z, 0, 0), |v| v as u16);
        enc.write_image::<colortype::Gray16>(5, 4, &p).unwrap();
    }
    let bytes = out.into_inner();
    assert_eq!(&bytes[..4], b"II+\0");
    let p = write(dir.path(), "big.tf8", &bytes);
    assert_eq!(detect(&p).unwrap(), Format::Tiff);
    let g = read(&p, 0, 0).unwrap();
    assert_eq!(g.dims(), [5, 4, 3]);
    check_values(&g, 0, 0, |v| v);
}
