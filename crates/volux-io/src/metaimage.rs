//! MetaImage (ITK / VTK), `.mhd` with a separate data file or `.mha` with the data after the
//! header, following the MetaIO documentation (<https://itk.org/Wiki/ITK/MetaIO/Documentation>).
//!
//! Read: `ObjectType = Image`, `NDims` (3; 2 is one slice with z = 1; 4 is a series of
//! volumes, `timepoint` chooses, recorded as a time axis whose step is the 4th
//! `ElementSpacing`), `DimSize`, `ElementType` (`MET_UCHAR`, `MET_CHAR`, `MET_USHORT`,
//! `MET_SHORT`, `MET_UINT`, `MET_INT`, `MET_ULONG`, `MET_LONG` (4 bytes, MetaIO's
//! `MET_ValueTypeSize`), `MET_ULONG_LONG`, `MET_LONG_LONG`, `MET_FLOAT`, `MET_DOUBLE`; the
//! types a [`volux_core::Grid`] does not hold are converted to `f32` with a note),
//! `ElementSpacing` (or `ElementSize`), `Offset` / `Origin` / `Position`,
//! `BinaryDataByteOrderMSB` / `ElementByteOrderMSB`, `BinaryData = False` (ASCII values),
//! `CompressedData = True` (a zlib stream, decoded with `flate2`), `CompressedDataSize`,
//! `HeaderSize` (bytes skipped in the data file; -1 = the data ends the file),
//! `ElementNumberOfChannels` (interleaved per voxel: 3 or 4 channels of uint8 or uint16 are
//! colour, as ITK writes RGB and RGBA pixels, kept as [`volux_core::color::Rgb`] with alpha
//! dropped, or the one channel `component` asks for; any other number, or other types, are
//! vector components, `component` choosing, default 0) and `ElementDataFile` (`LOCAL` or a file name relative
//! to the header's folder; it must be the last header line). `TransformMatrix` (or
//! `Rotation` / `Orientation`) is the direction matrix as ITK writes it, axis by axis (the first
//! `NDims` values are the world direction of the first axis), in ITK's LPS world, as `Offset`;
//! a non-orthonormal matrix is noted and the grid read axis-aligned. `AnatomicalOrientation`
//! is informational and not used, as in ITK's reader (the matrix is authoritative). The data
//! section must match the header.
//!
//! No MetaImage crate is used: none on crates.io is maintained, and the header is a few
//! `Key = Value` lines; compression goes through `flate2`.
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use volux_core::orientation::validate_direction;
use volux_core::Grid;

use crate::dataset::VolumeChoice;
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::nrrd::header_lines;
use crate::raw::{self, Decoded, ElemType};
use crate::util::{
    check_inflatable, header_err, io_error, open_regular, read_exact_checked, regular_metadata,
};
use crate::volumes::{Layout4, Place, Role};

/// The header fields Volux uses (keys lowercased).
struct Header {
    fields: Vec<(String, String)>,
}

impl Header {
    /// The value of the first of `keys` present.
    fn get(&self, keys: &[&str]) -> Option<&str> {
        keys.iter().find_map(|k| {
            self.fields
                .iter()
                .find(|(f, _)| f == k)
                .map(|(_, v)| v.as_str())
        })
    }

    fn bool(&self, path: &Path, keys: &[&str], default: bool) -> Result<bool> {
        match self.get(keys).map(str::to_ascii_lowercase).as_deref() {
            None => Ok(default),
            Some("true" | "1" | "yes") => Ok(true),
            Some("false" | "0" | "no") => Ok(false),
            Some(v) => Err(header_err(
                path,
                format!("{}: '{v}' is not True or False", keys[0]),
            )),
        }
    }

    fn numbers<T: std::str::FromStr>(&self, path: &Path, keys: &[&str]) -> Result<Option<Vec<T>>> {
        let Some(v) = self.get(keys) else {
            return Ok(None);
        };
        v.split_whitespace()
            .map(|x| x.parse())
            .collect::<std::result::Result<Vec<T>, _>>()
            .map(Some)
            .map_err(|_| header_err(path, format!("{}: '{v}' is not a list of numbers", keys[0])))
    }
}

/// Reads the header; returns it and the offset just after the `ElementDataFile` line.
fn read_header(path: &Path) -> Result<(Header, u64)> {
    let is_data_file_line = |l: &str| {
        l.split('=')
            .next()
            .is_some_and(|k| k.trim().eq_ignore_ascii_case("ElementDataFile"))
    };
    let (lines, offset, found) = header_lines(path, is_data_file_line, true)?;
    if !found {
        return Err(header_err(path, "no ElementDataFile line ends the header"));
    }
    let mut fields = Vec::new();
    for line in lines.iter().filter(|l| !l.trim().is_empty()) {
        let (k, v) = line.split_once('=').ok_or_else(|| {
            let shown: String = line.chars().take(60).collect();
            header_err(path, format!("line '{shown}' is not 'Key = Value'"))
        })?;
        fields.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    Ok((Header { fields }, offset))
}

fn element_type(path: &Path, h: &Header) -> Result<ElemType> {
    let t = h
        .get(&["elementtype"])
        .ok_or_else(|| header_err(path, "no ElementType"))?;
    Ok(match t.to_ascii_uppercase().as_str() {
        "MET_CHAR" => ElemType::I8,
        "MET_UCHAR" => ElemType::U8,
        "MET_SHORT" => ElemType::I16,
        "MET_USHORT" => ElemType::U16,
        "MET_INT" => ElemType::I32,
        "MET_UINT" | "MET_ULONG" => ElemType::U32,
        "MET_LONG" => ElemType::I32,
        "MET_LONG_LONG" => ElemType::I64,
        "MET_ULONG_LONG" => ElemType::U64,
        "MET_FLOAT" => ElemType::F32,
        "MET_DOUBLE" => ElemType::F64,
        _ => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!("ElementType '{t}'")),
            ))
        }
    })
}

/// Checks ObjectType, channels and NDims; returns NDims and the channels per voxel.
fn check_kind(path: &Path, h: &Header) -> Result<(usize, usize)> {
    if let Some(o) = h.get(&["objecttype"]) {
        if !o.eq_ignore_ascii_case("image") {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!("ObjectType '{o}' (only Image)")),
            ));
        }
    }
    let channels: i64 = h
        .numbers(path, &["elementnumberofchannels"])?
        .and_then(|v| v.first().copied())
        .unwrap_or(1);
    let channels = usize::try_from(channels)
        .ok()
        .filter(|&c| (1..=1 << 16).contains(&c))
        .ok_or_else(|| header_err(path, format!("ElementNumberOfChannels = {channels}")))?;
    let ndims = h
        .numbers::<usize>(path, &["ndims"])?
        .and_then(|v| v.first().copied())
        .ok_or_else(|| header_err(path, "no NDims"))?;
    if !(1..=4).contains(&ndims) {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!("NDims = {ndims} (1 to 4)")),
        ));
    }
    if ndims == 4 && channels > 1 {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "NDims = 4 with {channels} channels per voxel (a 5-D image)"
            )),
        ));
    }
    Ok((ndims, channels))
}

/// Pads or checks a per-axis list to 3 values.
fn per_axis(path: &Path, key: &str, v: Option<Vec<f64>>, n: usize, pad: f64) -> Result<[f64; 3]> {
    let mut out = [pad; 3];
    if let Some(v) = v {
        if v.len() < n {
            return Err(header_err(
                path,
                format!("{key} has {} values for NDims = {n}", v.len()),
            ));
        }
        for (o, x) in out.iter_mut().zip(v.iter().take(n)) {
            *o = *x;
        }
    }
    Ok(out)
}

/// Geometry: dims, voxel count, spacing, origin, notes.
struct Geometry {
    dims: [usize; 3],
    /// Values in the file (every volume, every channel).
    count: u64,
    /// A 4-D file (or one with several channels): the layout and what the extra axis holds.
    four: Option<(Layout4, Role)>,
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: DMat3,
    notes: Vec<String>,
}

/// The direction matrix of `TransformMatrix` values `v` for `n` axes (2 or 3): axis `a`'s world
/// direction is `v[n a .. n a + n]` (ITK's `MetaImageIO` order); a 2-D image's third axis is
/// the normal of the other two.
fn direction_of(v: &[f64], n: usize) -> std::result::Result<DMat3, String> {
    if !(2..=4).contains(&n) || v.len() != n * n {
        return Err(format!("{} values for NDims = {n}", v.len()));
    }
    // NDims 4: the spatial 3x3 block of the 4x4 matrix (the 4th axis is not spatial).
    let axis = |a: usize| {
        let c = &v[n * a..n * a + n];
        DVec3::new(c[0], c[1], if n > 2 { c[2] } else { 0.0 })
    };
    let (x, y) = (axis(0), axis(1));
    let z = if n >= 3 { axis(2) } else { x.cross(y) };
    validate_direction(DMat3::from_cols(x, y, z)).map_err(|e| e.to_string())
}

fn geometry(path: &Path, h: &Header, n: usize, channels: usize, ty: ElemType) -> Result<Geometry> {
    let sizes: Vec<i64> = h
        .numbers(path, &["dimsize"])?
        .ok_or_else(|| header_err(path, "no DimSize"))?;
    if sizes.len() != n {
        return Err(header_err(
            path,
            format!("DimSize has {} values for NDims = {n}", sizes.len()),
        ));
    }
    let mut dims = [1i64; 3];
    let spatial = n.min(3);
    dims[..spatial].copy_from_slice(&sizes[..spatial]);
    let (dims, count) =
        volux_core::limits::checked_dims(dims).map_err(|e| ReadError::new(path, e))?;
    let sp: Option<Vec<f64>> = h.numbers(path, &["elementspacing", "elementsize"])?;
    let step = sp.as_ref().and_then(|v| v.get(3).copied());
    let spacing = per_axis(path, "ElementSpacing", sp, spatial, 1.0)?.map(f64::abs);
    let or = h.numbers(path, &["offset", "origin", "position"])?;
    let origin = per_axis(path, "Offset", or, spatial, 0.0)?;
    let four = if n == 4 && sizes[3] > 1 {
        let len = usize::try_from(sizes[3]).map_err(|_| header_err(path, "DimSize is negative"))?;
        let meaning = match step {
            Some(s) if s.is_finite() && s > 0.0 => format!("step {s}"),
            _ => String::new(),
        };
        let sizes = [dims[0], dims[1], dims[2], len];
        Some((Layout4 { sizes, extra: 3 }, Role::Time(meaning)))
    } else if channels > 1 {
        let colour = (3..=4).contains(&channels) && matches!(ty, ElemType::U8 | ElemType::U16);
        let role = if colour {
            Role::Colour
        } else {
            Role::Component(String::new())
        };
        let sizes = [channels, dims[0], dims[1], dims[2]];
        Some((Layout4 { sizes, extra: 0 }, role))
    } else {
        None
    };
    let count = match &four {
        Some((l, _)) => count
            .checked_mul(l.sizes[l.extra] as u64)
            .ok_or_else(|| header_err(path, "the value count overflows"))?,
        None => count,
    };
    let mut notes = Vec::new();
    let m: Option<Vec<f64>> = h.numbers(path, &["transformmatrix", "rotation", "orientation"])?;
    let direction = match m.map(|v| direction_of(&v, n)).transpose() {
        Ok(d) => d.unwrap_or(DMat3::IDENTITY),
        Err(why) => {
            notes.push(format!(
                "TransformMatrix is not usable ({why}): read as an axis-aligned grid with the same spacing"
            ));
            DMat3::IDENTITY
        }
    };
    Ok(Geometry {
        dims,
        count,
        four,
        spacing,
        origin,
        direction,
        notes,
    })
}

/// The data file and where its data starts.
fn data_location(path: &Path, h: &Header, header_end: u64) -> Result<(PathBuf, u64)> {
    let name = h.get(&["elementdatafile"]).unwrap_or("");
    if name.eq_ignore_ascii_case("local") {
        return Ok((path.to_path_buf(), header_end));
    }
    if name.is_empty() || name.starts_with("LIST") || name.contains('%') || name.contains(' ') {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "ElementDataFile = '{name}' (only LOCAL or one file name)"
            )),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    Ok((dir.join(name), 0))
}

/// How the data is stored.
struct Storage {
    ty: ElemType,
    little_endian: bool,
    binary: bool,
    compressed: bool,
    compressed_size: Option<u64>,
    header_size: i64,
}

fn storage(path: &Path, h: &Header) -> Result<Storage> {
    let first = |v: Option<Vec<i64>>| v.and_then(|v| v.first().copied());
    let header_size = first(h.numbers(path, &["headersize"])?).unwrap_or(0);
    let compressed_size = match first(h.numbers(path, &["compresseddatasize"])?) {
        Some(s) if s < 0 => return Err(header_err(path, format!("CompressedDataSize = {s}"))),
        s => s.map(|s| s as u64),
    };
    let s = Storage {
        ty: element_type(path, h)?,
        little_endian: !h.bool(
            path,
            &["binarydatabyteordermsb", "elementbyteordermsb"],
            false,
        )?,
        binary: h.bool(path, &["binarydata"], true)?,
        compressed: h.bool(path, &["compresseddata"], false)?,
        compressed_size,
        header_size,
    };
    if s.header_size < -1 || (s.header_size == -1 && (s.compressed || !s.binary)) {
        return Err(header_err(
            path,
            format!(
                "HeaderSize = {} (>= 0, or -1 for uncompressed binary data)",
                s.header_size
            ),
        ));
    }
    Ok(s)
}

/// Reads the data section that starts at `start` of `file` (before `HeaderSize`).
fn read_data(file: &Path, s: &Storage, start: u64, count: u64) -> Result<Decoded> {
    let len = regular_metadata(file)?.len();
    let need = raw::data_bytes(file, s.ty, count)?;
    let pos = if s.header_size == -1 {
        len.checked_sub(need)
            .filter(|&o| o >= start)
            .ok_or_else(|| {
                ReadError::new(
                    file,
                    ErrorKind::Truncated {
                        expected: need,
                        found: len.saturating_sub(start),
                    },
                )
            })?
    } else {
        start.saturating_add(s.header_size as u64)
    };
    if s.binary && !s.compressed {
        return raw::read_plain(file, pos, s.ty, s.little_endian, count);
    }
    let mut f = open_regular(file)?;
    f.seek(SeekFrom::Start(pos))
        .map_err(|e| io_error(file, e))?;
    let rest = len.saturating_sub(pos);
    if !s.binary {
        let bytes = read_exact_checked(file, f, rest)?;
        let text = std::str::from_utf8(&bytes).map_err(|_| {
            ReadError::new(file, ErrorKind::Invalid("ASCII data is not text".into()))
        })?;
        return raw::parse_ascii(file, text, s.ty, count);
    }
    let size = s.compressed_size.unwrap_or(rest);
    if size > rest {
        return Err(ReadError::new(
            file,
            ErrorKind::Truncated {
                expected: size,
                found: rest,
            },
        ));
    }
    // Refused before inflating when `size` compressed bytes cannot hold the declared data;
    // inflation stops one byte after the declared size.
    check_inflatable(file, size, need)?;
    let z = flate2::read::ZlibDecoder::new(BufReader::new(f.take(size)));
    raw::read_stream(file, z, s.ty, s.little_endian, count)
}

/// Reads a MetaImage file (`.mhd` header with a data file, or `.mha` with local data): the
/// volume (or channel) of `choice` when it holds several.
pub fn read(path: &Path, choice: VolumeChoice) -> Result<Grid> {
    let (h, header_end) = read_header(path)?;
    let (n, channels) = check_kind(path, &h)?;
    let s = storage(path, &h)?;
    let g = geometry(path, &h, n, channels, s.ty)?;
    let (file, start) = data_location(path, &h, header_end)?;
    let data = read_data(&file, &s, start, g.count)?;
    let place = Place {
        spacing: g.spacing,
        origin: g.origin,
        direction: g.direction,
    };
    let four = g.four.as_ref().map(|(l, r)| (*l, r));
    crate::volumes::grid(&file, g.dims, place, data, g.notes, four, choice)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::hostile::*;
    use volux_testkit::mutate::zlib;

    /// A MetaImage header for a `dims` uint8 volume stored in `data` (zlib when `zlib`).
    fn header(dims: [u64; 3], zlib: bool, data: &str) -> String {
        let compressed = if zlib { "True" } else { "False" };
        format!(
            "ObjectType = Image\nNDims = 3\nDimSize = {} {} {}\nElementType = MET_UCHAR\n\
             CompressedData = {compressed}\nElementDataFile = {data}\n",
            dims[0], dims[1], dims[2]
        )
    }

    #[test]
    fn special_element_data_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        zero_link(d, "zero.raw");
        for zlib in [false, true] {
            let mhd = d.join(format!("z{zlib}.mhd"));
            std::fs::write(&mhd, header([2, 2, 2], zlib, "zero.raw")).unwrap();
            assert_refused(
                read(&mhd, Default::default()),
                "zero.raw",
                "(a character device)",
            );
        }
        let mhd = d.join("l.mhd");
        std::fs::write(&mhd, header([2, 2, 2], false, "l.raw")).unwrap();
        link_loop(d, "l.raw");
        assert_refused(
            read(&mhd, Default::default()),
            "l.raw",
            "loop of symbolic links",
        );
        if let Some(f) = fifo(d, "f.mha") {
            assert_refused(read(&f, Default::default()), "f.mha", "(a FIFO)");
        }
    }

    #[test]
    fn zlib_data_is_bounded_by_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let p = d.join("bomb.mha");
        let mut bytes = header([16, 16, 4], true, "LOCAL").into_bytes();
        bytes.extend(zlib(&vec![0u8; 64 << 20]));
        std::fs::write(&p, bytes).unwrap();
        let e = read(&p, Default::default()).unwrap_err().to_string();
        assert!(
            e.contains("bomb.mha") && e.contains("more than the 1024 bytes"),
            "{e}"
        );
        let p = d.join("huge.mha");
        let mut bytes = header([2048, 2048, 1536], true, "LOCAL").into_bytes();
        bytes.extend(zlib(&[0u8; 1000]));
        std::fs::write(&p, bytes).unwrap();
        let e = read(&p, Default::default()).unwrap_err();
        crate::util::hostile::assert_undeliverable(&e, 6442450944);
    }
}
