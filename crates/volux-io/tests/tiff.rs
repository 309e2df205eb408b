//! TIFF stacks: multi-page files written here with the `tiff` crate's encoder (every
//! compression and sample type, MINISWHITE, RGB, ImageJ and OME-XML descriptions), numbered
//! slice folders, the small `tifffile` fixtures of `tests/fixtures/tiff/` (see
//! `make_fixtures.py`: colour, palette, sample types, JPEG compared with tifffile's own
//! decoding), and hostile files (truncated, lying sizes), which must fail cleanly.
use std::io::Cursor;
use std::path::{Path, PathBuf};

use tiff::encoder::{colortype, compression::DeflateLevel, Compression, Rational, TiffEncoder};
use tiff::tags::{PhotometricInterpretation, ResolutionUnit, SampleFormat, Tag};
use volux_core::volume_axes::{AxisKind, ExtraAxis};
use volux_core::{Grid, ScalarType};
use volux_io::{detect, load, Dataset, ErrorKind, Format, LoadOptions, ReadError, VolumeChoice};

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
    read_component(path, channel, timepoint, None)
}

/// Loads `path` choosing `channel`, `timepoint` and `component`.
fn read_component(
    path: &Path,
    channel: usize,
    timepoint: usize,
    component: Option<usize>,
) -> volux_io::Result<Grid> {
    let opts = LoadOptions {
        channel,
        timepoint,
        component,
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

/// Asserts that `e` is the typed error for `option` `index` past an axis of `len`.
fn assert_no_such(e: &ReadError, option: &str, index: usize, len: usize) {
    match &e.kind {
        ErrorKind::Data(volux_core::Error::NoSuchVolume {
            option: o,
            index: i,
            len: l,
        }) => assert_eq!((*o, *i, *l), (option, index, len), "{e}"),
        _ => panic!("not NoSuchVolume: {e}"),
    }
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
    let g = read(&p, 1, 1).unwrap();
    assert_eq!(
        g.extra_axes(),
        [
            ExtraAxis::new(AxisKind::Channel, cs, Some(1)),
            ExtraAxis::new(AxisKind::Time, ts, Some(1))
        ]
    );
    let e = read(&p, 2, 0).unwrap_err();
    assert_no_such(&e, "channel", 2, 2);
    assert!(
        e.to_string()
            .contains("channel 2 does not exist: the file holds 2"),
        "{e}"
    );
    assert_no_such(&read(&p, 0, 5).unwrap_err(), "timepoint", 5, 2);
    // The stack is grayscale: no component beyond 0.
    assert_no_such(
        &read_component(&p, 0, 0, Some(1)).unwrap_err(),
        "component",
        1,
        1,
    );
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
    assert_no_such(&read(&p, 3, 0).unwrap_err(), "channel", 3, 3);
    assert_no_such(&read(&p, 0, 1).unwrap_err(), "timepoint", 1, 1);
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
    assert_no_such(&read(&p, 1, 0).unwrap_err(), "channel", 1, 1);
    assert_no_such(&read(&p, 0, 1).unwrap_err(), "timepoint", 1, 1);
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
fn rgb_pages_are_colour_grids() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, d) = (5, 4, 3);
    let rgb = |z: usize| -> Vec<u16> {
        page(w, h, (z, 0, 0), |v| v)
            .into_iter()
            .flat_map(|v| [v as u16, v as u16 + 1000, v as u16 + 2000])
            .collect()
    };
    let pages: Vec<Vec<u16>> = (0..d).map(rgb).collect();
    let bytes = tiff_bytes::<colortype::RGB16>(w, h, &pages, Compression::Lzw, &Meta::default());
    let p = write(dir.path(), "rgb16.tif", &bytes);
    let g = read(&p, 0, 0).unwrap();
    assert_eq!(g.dims(), [w, h, d]);
    assert_eq!(g.scalar_type(), ScalarType::U16);
    let colour = g.color().expect("a colour grid");
    for (c, samples) in colour.channels().iter().enumerate() {
        for (i, want) in (0..d)
            .flat_map(|z| page(w, h, (z, 0, 0), |v| v))
            .enumerate()
        {
            assert_eq!(samples.get_f32(i) as f64, want + 1000.0 * c as f64);
        }
    }
    assert_eq!(g.extra_axes(), [ExtraAxis::new(AxisKind::Color, 3, None)]);
    assert!(notes(&g).contains("16-bit unsigned RGB"), "{}", notes(&g));
    // One channel as a scalar grid.
    let g = read_component(&p, 0, 0, Some(2)).unwrap();
    assert!(g.color().is_none());
    check_values(&g, 0, 0, |v| v + 2000.0);
    assert_eq!(
        g.extra_axes(),
        [ExtraAxis::new(AxisKind::Color, 3, Some(2))]
    );
    assert!(
        notes(&g).contains("colour channel 2 (blue)"),
        "{}",
        notes(&g)
    );
    assert_no_such(
        &read_component(&p, 0, 0, Some(3)).unwrap_err(),
        "component",
        3,
        3,
    );
    // An alpha sample is dropped, with a note.
    let rgba: Vec<Vec<u8>> = (0..d)
        .map(|z| {
            page(w, h, (z, 0, 0), |v| v as u8)
                .into_iter()
                .flat_map(|v| [v, v + 1, v + 2, 255])
                .collect()
        })
        .collect();
    let bytes =
        tiff_bytes::<colortype::RGBA8>(w, h, &rgba, Compression::Packbits, &Meta::default());
    let p = write(dir.path(), "rgba.tif", &bytes);
    let g = read_component(&p, 0, 0, Some(1)).unwrap();
    check_values(&g, 0, 0, |v| v + 1.0);
    assert!(notes(&g).contains("1 extra sample"), "{}", notes(&g));
    // CMYK is refused by name, in one line.
    let cmyk = vec![vec![0u8; w * h * 4]];
    let bytes =
        tiff_bytes::<colortype::CMYK8>(w, h, &cmyk, Compression::Uncompressed, &Meta::default());
    let p = write(dir.path(), "cmyk.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    let text = e.to_string();
    assert!(text.contains("CMYK") && text.lines().count() == 1, "{text}");
}

/// Grayscale samples of type `T` written as MINISWHITE (photometric 0).
struct White<T>(std::marker::PhantomData<T>);

macro_rules! white {
    ($t:ty, $bits:expr, $format:expr) => {
        impl colortype::ColorType for White<$t> {
            type Inner = $t;
            const TIFF_VALUE: PhotometricInterpretation = PhotometricInterpretation::WhiteIsZero;
            const BITS_PER_SAMPLE: &'static [u16] = &[$bits];
            const SAMPLE_FORMAT: &'static [SampleFormat] = &[$format];
            fn horizontal_predict(_: &[Self::Inner], _: &mut Vec<Self::Inner>) {
                unreachable!("no predictor is used")
            }
        }
    };
}
white!(u8, 8, SampleFormat::Uint);
white!(u16, 16, SampleFormat::Uint);
white!(i16, 16, SampleFormat::Int);
white!(f32, 32, SampleFormat::IEEEFP);

#[test]
fn miniswhite_is_inverted_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (4, 3);
    let m = Meta::default();
    let v = |z| page(w, h, (z, 0, 0), |v| v);
    let pages = |f: &dyn Fn(f64) -> f64| -> Vec<Vec<f64>> {
        (0..2).map(|z| v(z).into_iter().map(f).collect()).collect()
    };
    let conv = |p: Vec<Vec<f64>>, f: fn(f64) -> f32| -> Vec<Vec<f32>> {
        p.into_iter()
            .map(|p| p.into_iter().map(f).collect())
            .collect()
    };
    let u8s: Vec<Vec<u8>> = pages(&|v| v % 251.0)
        .into_iter()
        .map(|p| p.into_iter().map(|v| v as u8).collect())
        .collect();
    let u16s: Vec<Vec<u16>> = pages(&|v| v * 50.0)
        .into_iter()
        .map(|p| p.into_iter().map(|v| v as u16).collect())
        .collect();
    // -32768 negates to 32768, which int16 cannot hold: the grid is float32.
    let mut i16s: Vec<Vec<i16>> = pages(&|v| v - 100.0)
        .into_iter()
        .map(|p| p.into_iter().map(|v| v as i16).collect())
        .collect();
    i16s[0][0] = i16::MIN;
    let f32s = conv(pages(&|v| v / 4.0 - 10.0), |v| v as f32);
    let cases = [
        (
            "u8",
            tiff_bytes::<White<u8>>(w, h, &u8s, Compression::Lzw, &m),
            ScalarType::U8,
            "255 - v",
        ),
        (
            "u16",
            tiff_bytes::<White<u16>>(w, h, &u16s, Compression::Uncompressed, &m),
            ScalarType::U16,
            "65535 - v",
        ),
        (
            "i16",
            tiff_bytes::<White<i16>>(w, h, &i16s, Compression::Packbits, &m),
            ScalarType::F32,
            "negated",
        ),
        (
            "f32",
            tiff_bytes::<White<f32>>(w, h, &f32s, Compression::Deflate(DeflateLevel::Fast), &m),
            ScalarType::F32,
            "negated",
        ),
    ];
    for (name, bytes, ty, words) in cases {
        let p = write(dir.path(), &format!("white_{name}.tif"), &bytes);
        let g = read(&p, 0, 0).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.scalar_type(), ty, "{name}");
        let n = notes(&g);
        assert!(n.contains("MINISWHITE") && n.contains(words), "{name}: {n}");
        for z in 0..2 {
            for (i, raw) in v(z).into_iter().enumerate() {
                let (x, y) = (i % w, i / w);
                let want = match name {
                    "u8" => 255.0 - raw % 251.0,
                    "u16" => 65535.0 - raw * 50.0,
                    "i16" if (x, y, z) == (0, 0, 0) => 32768.0,
                    "i16" => -(raw - 100.0),
                    _ => -(raw / 4.0 - 10.0),
                };
                assert_eq!(g.value(x, y, z) as f64, want, "{name} ({x}, {y}, {z})");
            }
        }
    }
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
    assert_no_such(&read(&p, 0, 3).unwrap_err(), "timepoint", 3, 3);
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
    assert_no_such(&read(&p, 2, 0).unwrap_err(), "channel", 2, 2);
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
            if volux_io::tiff::read(&p, 0, VolumeChoice::default()).is_ok() {
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

/// The voxels of `g` (x fastest, then y, then z) as f64.
fn voxels(g: &Grid) -> Vec<f64> {
    let [w, h, d] = g.dims();
    (0..d)
        .flat_map(|z| (0..h).flat_map(move |y| (0..w).map(move |x| (x, y, z))))
        .map(|(x, y, z)| g.value(x, y, z) as f64)
        .collect()
}

/// `value` over the 16 x 12 x 5 fixtures (x fastest), at channel `c` and timepoint `t`.
fn fixture_values(c: usize, t: usize) -> Vec<f64> {
    (0..5)
        .flat_map(|z| page(16, 12, (z, c, t), |v| v))
        .collect()
}

/// The samples of colour channel `c` of a colour grid, as f64.
fn channel(g: &Grid, c: usize) -> Vec<f64> {
    let s = &g.color().expect("a colour grid").channels()[c];
    (0..s.len()).map(|i| s.get_f32(i) as f64).collect()
}

#[test]
fn tifffile_miniswhite_signed_and_float_are_negated() {
    let g = read(&fixture("miniswhite_i16.tif"), 0, 0).unwrap();
    assert_eq!(g.scalar_type(), ScalarType::F32);
    check_values(&g, 0, 0, |v| -(v - 300.0));
    let n = notes(&g);
    assert!(n.contains("MINISWHITE") && n.contains("negated"), "{n}");
    let g = read(&fixture("miniswhite_f32.tif"), 0, 0).unwrap();
    check_values(&g, 0, 0, |v| -(v / 4.0));
    let n = notes(&g);
    assert!(n.contains("MINISWHITE") && n.contains("Zstandard"), "{n}");
}

#[test]
fn tifffile_palette_through_the_colormap() {
    let p = fixture("palette_u8.tif");
    let cmap = |c: usize, i: f64| ((251 * i as u64 + 7000 * c as u64) % 65536) as f64;
    let g = read(&p, 0, 0).unwrap();
    assert_eq!(g.scalar_type(), ScalarType::U16);
    for c in 0..3 {
        let want: Vec<f64> = fixture_values(0, 0)
            .into_iter()
            .map(|v| cmap(c, v % 256.0))
            .collect();
        assert_eq!(channel(&g, c), want, "channel {c}");
    }
    let n = notes(&g);
    assert!(n.contains("palette") && n.contains("PackBits"), "{n}");
    let g = read_component(&p, 0, 0, Some(1)).unwrap();
    check_values(&g, 0, 0, |v| cmap(1, v % 256.0));
    assert!(
        notes(&g).contains("ColorMap's 16-bit green"),
        "{}",
        notes(&g)
    );
}

#[test]
fn tifffile_rgb_planar_tiled_imagej_and_ome() {
    let want = |c: usize, t: usize, m: f64| -> Vec<f64> {
        fixture_values(0, t)
            .into_iter()
            .map(|v| (v + 1000.0 * c as f64) % m)
            .collect()
    };
    for (name, m, ty, words) in [
        (
            "rgb_u16_planar.tif",
            65536.0,
            ScalarType::U16,
            "16-bit unsigned RGB (planar)",
        ),
        (
            "rgb_u8_tiled.tif",
            251.0,
            ScalarType::U8,
            "Deflate compression, 8-bit unsigned RGB",
        ),
        (
            "imagej_rgb.tif",
            256.0,
            ScalarType::U8,
            "ImageJ TIFF: 5 pages",
        ),
    ] {
        let g = read(&fixture(name), 0, 0).unwrap();
        assert_eq!((g.dims(), g.scalar_type()), ([16, 12, 5], ty), "{name}");
        for c in 0..3 {
            assert_eq!(channel(&g, c), want(c, 0, m), "{name} channel {c}");
        }
        assert!(notes(&g).contains(words), "{name}: {}", notes(&g));
    }
    // OME-TIFF: RGB pages are 3 of SizeC = 3; 2 timepoints 2.5 s apart.
    let p = fixture("ome_rgb_t2.ome.tif");
    for t in 0..2 {
        let g = read(&p, 0, t).unwrap();
        for c in 0..3 {
            assert_eq!(channel(&g, c), want(c, t, 256.0), "t {t} channel {c}");
        }
        assert_eq!(
            g.extra_axes(),
            [
                ExtraAxis::new(AxisKind::Color, 3, None),
                ExtraAxis::new(AxisKind::Time, 2, Some(t)).with_meaning("step 2.5 s")
            ]
        );
    }
    let g = read_component(&p, 0, 1, Some(0)).unwrap();
    assert_eq!(voxels(&g), want(0, 1, 256.0));
    assert_no_such(&read(&p, 0, 2).unwrap_err(), "timepoint", 2, 2);
    assert_no_such(&read(&p, 1, 0).unwrap_err(), "channel", 1, 1);
}

#[test]
fn tifffile_sample_types_convert_with_notes() {
    let v = fixture_values(0, 0);
    let n = v.len();
    // The note of an integer conversion, with the count of values float32 rounds.
    let note = |name: &str, f: &dyn Fn(f64) -> f64| {
        let rounded = v.iter().filter(|&&x| (f(x) as f32) as f64 != f(x)).count();
        let why = "integers above 2^24 lose precision";
        if rounded == 0 {
            format!("converted from {name} to float32 ({why}; every value here fits)")
        } else {
            format!("converted from {name} to float32 ({why}: {rounded} of {n} values rounded)")
        }
    };
    type Case<'a> = (&'a str, ScalarType, &'a dyn Fn(f64) -> f64, String);
    let u32s = |x: f64| x * 100003.0;
    let i32s = |x: f64| -x * 100000.0; // 3125 v 2^5: fits float32
    let u64s = |x: f64| x + 2f64.powi(40);
    let cases: [Case; 7] = [
        (
            "int8.tif",
            ScalarType::I16,
            &|x| x % 200.0 - 100.0,
            "converted from int8 to int16 (exact)".into(),
        ),
        ("uint32.tif", ScalarType::F32, &u32s, note("uint32", &u32s)),
        ("int32.tif", ScalarType::F32, &i32s, note("int32", &i32s)),
        (
            "float64.tif",
            ScalarType::F32,
            &|x| x / 3.0,
            "converted from float64 to float32 (precision reduced:".into(),
        ),
        (
            "float16.tif",
            ScalarType::F32,
            &|x| x / 8.0,
            "converted from float16 to float32 (exact)".into(),
        ),
        (
            "uint64_bigtiff.tif",
            ScalarType::F32,
            &u64s,
            note("uint64", &u64s),
        ),
        (
            "bilevel.tif",
            ScalarType::U8,
            &|x| f64::from(x % 3.0 == 0.0),
            "converted from 1-bit to uint8 (exact)".into(),
        ),
    ];
    for (name, ty, f, note) in cases {
        let g = read(&fixture(name), 0, 0).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(g.scalar_type(), ty, "{name}");
        let want: Vec<f64> = v.iter().map(|&x| f(x) as f32 as f64).collect();
        assert_eq!(voxels(&g), want, "{name}");
        assert!(notes(&g).contains(&note), "{name}: {}", notes(&g));
    }
    // Values that fit float32 are exact, and the note says so.
    let dir = tempfile::tempdir().unwrap();
    let small: Vec<Vec<u32>> = (0..2)
        .map(|z| page(3, 2, (z, 0, 0), |v| v as u32))
        .collect();
    let bytes = tiff_bytes::<colortype::Gray32>(3, 2, &small, Compression::Lzw, &Meta::default());
    let p = write(dir.path(), "small_u32.tif", &bytes);
    let g = read(&p, 0, 0).unwrap();
    check_values(&g, 0, 0, |v| v);
    assert!(notes(&g).contains("every value here fits"), "{}", notes(&g));
}

/// The committed `NAME.tifffile.u8`: tifffile's decoding of fixture `NAME.tif`.
fn tifffile_decoding(name: &str) -> Vec<f64> {
    let p = fixture(&name.replace(".tif", ".tifffile.u8"));
    std::fs::read(p)
        .unwrap()
        .into_iter()
        .map(f64::from)
        .collect()
}

#[test]
fn tifffile_jpeg_within_the_lossy_tolerance() {
    // The conformance harness's tolerance for 8-bit JPEG (decoders differ by rounding).
    const TOL: f64 = 3.0;
    let p = fixture("jpeg_tables.tif");
    let g = read(&p, 0, 0).unwrap();
    let want = tifffile_decoding("jpeg_tables.tif");
    let worst = voxels(&g)
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst <= TOL, "jpeg_tables: {worst}");
    assert!(notes(&g).contains("JPEG is lossy"), "{}", notes(&g));
    let p = fixture("jpeg_rgb.tif");
    let g = read(&p, 0, 0).unwrap();
    let want = tifffile_decoding("jpeg_rgb.tif"); // (z, y, x, c)
    let mut worst = 0.0f64;
    for c in 0..3 {
        for (i, v) in channel(&g, c).into_iter().enumerate() {
            worst = worst.max((v - want[i * 3 + c]).abs());
        }
    }
    assert!(worst <= TOL, "jpeg_rgb: {worst}");
    assert!(
        notes(&g).contains("YCbCr converted to RGB"),
        "{}",
        notes(&g)
    );
}

#[test]
fn tifffile_webp_lossy_and_lossless() {
    // Lossy: image-webp decodes as libwebp does here (measured: every sample equal); the
    // JPEG tolerance is the bound the test holds it to.
    let g = read(&fixture("webp_rgb.tif"), 0, 0).unwrap();
    let want = tifffile_decoding("webp_rgb.tif");
    let mut worst = 0.0f64;
    for c in 0..3 {
        for (i, v) in channel(&g, c).into_iter().enumerate() {
            worst = worst.max((v - want[i * 3 + c]).abs());
        }
    }
    assert!(worst <= 3.0, "webp_rgb: {worst}");
    assert!(notes(&g).contains("WebP"), "{}", notes(&g));
    // Lossless: exact.
    let g = read(&fixture("webp_lossless.tif"), 0, 0).unwrap();
    for c in 0..3 {
        let want: Vec<f64> = fixture_values(0, 0)
            .into_iter()
            .map(|v| (v + 1000.0 * c as f64) % 256.0)
            .collect();
        assert_eq!(channel(&g, c), want, "channel {c}");
    }
}

#[test]
fn a_webp_frame_larger_than_its_strip_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(fixture("webp_lossless.tif")).unwrap();
    // The VP8L header: 0x2f, then 14 bits of width - 1 and 14 of height - 1.
    let at = bytes
        .windows(4)
        .position(|w| w == b"VP8L")
        .expect("a lossless stream")
        + 8;
    assert_eq!(bytes[at], 0x2f);
    bytes[at + 1..at + 5].copy_from_slice(&(0x3fffu32 | (0x3fff << 14)).to_le_bytes());
    let p = write(dir.path(), "big_webp.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err().to_string();
    assert!(
        e.contains("WebP strip 0 declares a 16384x16384 frame"),
        "{e}"
    );
}

#[test]
fn lzma_and_other_codecs_are_refused_by_name() {
    let e = read(&fixture("lzma.tif"), 0, 0).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    let text = e.to_string();
    assert!(text.contains("compression 34925 (LZMA)"), "{text}");
    assert_eq!(text.lines().count(), 1, "{text}");
    // Other codes, set in a copy's Compression tag.
    let mut bytes = std::fs::read(fixture("deflate_u8.tif")).unwrap();
    let at = tag_value_at(&bytes, 259);
    for (code, name) in [
        (34712u16, "JPEG 2000"),
        (50002, "JPEG XL"),
        (6, "old-style JPEG"),
        (40000, "unknown"),
    ] {
        bytes[at..at + 2].copy_from_slice(&code.to_le_bytes());
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), "codec.tif", &bytes);
        let text = read(&p, 0, 0).unwrap_err().to_string();
        assert!(
            text.contains(&format!("compression {code} ({name})")),
            "{text}"
        );
    }
}

/// The offset of the first JPEG frame header's height in `bytes`.
fn sof_height_at(bytes: &[u8]) -> usize {
    bytes
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("a baseline frame header")
        + 5
}

#[test]
fn a_jpeg_frame_larger_than_its_strip_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(fixture("jpeg_tables.tif")).unwrap();
    let at = sof_height_at(&bytes);
    bytes[at..at + 2].copy_from_slice(&16000u16.to_be_bytes());
    bytes[at + 2..at + 4].copy_from_slice(&16000u16.to_be_bytes());
    let p = write(dir.path(), "big_frame.tif", &bytes);
    let e = read(&p, 0, 0).unwrap_err().to_string();
    assert!(
        e.contains("16000x16000 frame, larger than the 16x12 strip"),
        "{e}"
    );
}

/// Random corruptions of the colour, palette, MINISWHITE, JPEG and Zstandard fixtures, read
/// in-process with and without a component: an error or a grid, never a panic.
/// `VOLUX_TIFF_CORRUPTIONS=N` runs N cases per file (default 300).
#[test]
fn random_corruptions_of_colour_and_codecs_never_panic() {
    let cases = std::env::var("VOLUX_TIFF_CORRUPTIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300);
    let dir = tempfile::tempdir().unwrap();
    let mut rng = volux_testkit::TestRng::new(0x636f_6c72);
    let mut grids = 0;
    for name in [
        "palette_u8.tif",
        "miniswhite_i16.tif",
        "miniswhite_f32.tif",
        "rgb_u16_planar.tif",
        "rgb_u8_tiled.tif",
        "jpeg_rgb.tif",
        "jpeg_tables.tif",
        "uint64_bigtiff.tif",
        "bilevel.tif",
        "ome_rgb_t2.ome.tif",
        "webp_rgb.tif",
        "webp_lossless.tif",
    ] {
        let seed = std::fs::read(fixture(name)).unwrap();
        for k in 0..cases {
            let mut bytes = seed.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                match rng.below(4) {
                    0 => bytes[at] ^= 1 << rng.below(8),
                    1 => bytes[at] = [0, 0xff, 0x7f, 0x80][rng.below(4)],
                    2 => {
                        let v = [0u32, 1, 2, 3, 0xffff, 0x7fff_ffff, 0xffff_ffff][rng.below(7)];
                        let end = (at + 4).min(bytes.len());
                        bytes[at..end].copy_from_slice(&v.to_le_bytes()[..end - at]);
                    }
                    _ => bytes.truncate(at.max(8)),
                }
            }
            let p = write(dir.path(), name, &bytes);
            let choice = VolumeChoice {
                timepoint: 0,
                component: (k % 2 == 1).then_some(1),
            };
            if volux_io::tiff::read(&p, 0, choice).is_ok() {
                grids += 1;
            }
        }
    }
    assert!(grids > 0);
}

#[test]
fn ccitt_group4_bilevel_miniswhite() {
    use fax::{encoder::Encoder, Color, VecWriter};
    let (w, h) = (37usize, 9usize);
    // Black where (x + y) % 5 == 0 or x > 30; fax data is MINISWHITE (black is 1).
    let black = |x: usize, y: usize| (x + y).is_multiple_of(5) || x > 30;
    let mut enc = Encoder::new(VecWriter::new());
    for y in 0..h {
        let line = (0..w).map(|x| {
            if black(x, y) {
                Color::Black
            } else {
                Color::White
            }
        });
        enc.encode_line(line, w as u16).unwrap();
    }
    let data = enc.finish().unwrap().finish();
    let bytes = fax::tiff::wrap(&data, w as u32, h as u32);
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "fax.tif", &bytes);
    let g = read(&p, 0, 0).unwrap();
    assert_eq!((g.dims(), g.scalar_type()), ([w, h, 1], ScalarType::U8));
    for y in 0..h {
        for x in 0..w {
            // Inverted: white 1, black 0.
            assert_eq!(
                g.value(x, y, 0),
                if black(x, y) { 0.0 } else { 1.0 },
                "({x}, {y})"
            );
        }
    }
    let n = notes(&g);
    assert!(
        n.contains("CCITT Group 4 fax compression, 1-bit unsigned") && n.contains("1 - v"),
        "{n}"
    );
}

#[test]
fn bigtiff_big_endian_miniswhite_and_palette_are_patched() {
    // tifffile: BigTIFF, big-endian, MINISWHITE uint16 (v * 100) and palette (v % 256).
    let g = read(&fixture("miniswhite_u16_be_bigtiff.tif"), 0, 0).unwrap();
    check_values(&g, 0, 0, |v| 65535.0 - v * 100.0);
    assert!(notes(&g).contains("MINISWHITE"), "{}", notes(&g));
    let g = read_component(&fixture("palette_be_bigtiff.tif"), 0, 0, Some(2)).unwrap();
    check_values(&g, 0, 0, |v| {
        ((251 * (v as u64 % 256) + 14000) % 65536) as f64
    });
}
