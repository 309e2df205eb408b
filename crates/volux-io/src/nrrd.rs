//! NRRD, following the teem specification (<http://teem.sourceforge.net/nrrd/format.html>).
//!
//! Read: magic `NRRD000X`; fields `type` (every NRRD name of int8, uint8, int16, uint16,
//! int32, uint32, int64, uint64, float, double; the types a [`volux_core::Grid`] does not hold
//! are converted to `f32` with a note), `dimension` (3; 2 is a single slice with z = 1; 4 with
//! one axis that is not spatial, see below), `sizes`, `kinds`, `spacings` or `space directions` (spacing = length of each direction,
//! direction = the unit vectors), `space` (`left-posterior-superior`/`LPS`,
//! `right-anterior-superior`/`RAS`, `left-anterior-superior`/`LAS`: turned into Volux's LPS
//! world by negating the axes that differ; any other space is taken as it is), `space origin`,
//! `endian`, `encoding` (`raw`, `gzip`/`gz`, `bzip2`/`bz2`, `ascii`/`text`/`txt`), `data file` (detached
//! `.nhdr` header, path relative to the header's folder), `line skip` and `byte skip` (-1 = the
//! data ends the file). Comments (`#`) and key/value lines (`:=`) are ignored. Attached data
//! follows the blank line after the header. The data section must match the header exactly.
//!
//! 4-D: the axis that is not spatial is the one whose `kinds` entry is not `domain` or
//! `space`, else the one whose `space directions` entry is `none`, else an axis of size 1 at
//! either end. Its kind says what it holds: `RGB-color`, `RGBA-color`, `3-color`, `4-color`
//! (3 or 4 entries) are colour ([`volux_core::color::Rgb`], alpha dropped with a note; or the
//! one channel `component` asks for); `time` is a time series (`timepoint`, the step from
//! `spacings`); `list` on the first (fastest) axis, and vector, tensor and other per-voxel
//! kinds (`vector`, `covariant-vector`, `normal`, `point`, `N-vector`, `quaternion`,
//! `complex`, `*-matrix`, ...), are components (`component`, default 0); any other axis is a
//! list of volumes (`timepoint`). The grid records the axis it was chosen along
//! ([`volux_core::volume_axes::ExtraAxis`]).
//!
//! No NRRD crate is used: the crates.io `nrrd` crates are unmaintained and do not share our
//! size checks or memory-mapping; the header is a few lines of text, gzip goes through
//! `flate2` and bzip2 through the `bzip2` crate (its pure-Rust `libbz2-rs-sys` backend). [`write()`] writes attached, raw, little-endian files.
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};
use volux_core::orientation::split_scaled_axes;
use volux_core::{Grid, ScalarType};

use crate::dataset::VolumeChoice;
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::error::WriteError;
use crate::raw::{self, Decoded, ElemType};
use crate::util::{
    check_inflatable, header_err, io_error, open_regular, read_exact_checked, regular_metadata,
};
use crate::volumes::{Layout4, Place, Role};

/// Largest header read, in bytes.
pub(crate) const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Reads header lines of `path` up to and excluding the line for which `stop` is true (or to
/// the end of the file), returning the lines and the byte offset just after the stop line.
pub(crate) fn header_lines(
    path: &Path,
    stop: impl Fn(&str) -> bool,
    include_stop: bool,
) -> Result<(Vec<String>, u64, bool)> {
    let file = open_regular(path)?;
    let mut reader = BufReader::new(file.take(MAX_HEADER_BYTES));
    let (mut lines, mut offset, mut buf) = (Vec::new(), 0u64, Vec::new());
    loop {
        buf.clear();
        let n = reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| ReadError::new(path, e))?;
        if n == 0 {
            if offset >= MAX_HEADER_BYTES {
                return Err(header_err(
                    path,
                    format!("no end of header within {MAX_HEADER_BYTES} bytes"),
                ));
            }
            return Ok((lines, offset, false));
        }
        offset += n as u64;
        let line = std::str::from_utf8(&buf)
            .map_err(|_| header_err(path, format!("header line {} is not text", lines.len() + 1)))?
            .trim_end_matches(['\n', '\r']);
        if stop(line) {
            if include_stop {
                lines.push(line.to_string());
            }
            return Ok((lines, offset, true));
        }
        lines.push(line.to_string());
    }
}

/// How the data is encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Raw,
    Gzip,
    Bzip2,
    Ascii,
}

/// The header fields Volux uses.
#[derive(Debug, Default)]
struct Header {
    ty: Option<ElemType>,
    dimension: Option<usize>,
    sizes: Vec<i64>,
    /// `kinds`, lowercased (empty when absent).
    kinds: Vec<String>,
    spacings: Vec<f64>,
    directions: Vec<Option<Vec<f64>>>,
    origin: Option<Vec<f64>>,
    /// The signs that turn `space` coordinates into LPS (`None`: no anatomical space).
    space_to_lps: Option<[f64; 3]>,
    /// `space units`, one per space axis (quotes removed).
    space_units: Vec<String>,
    little_endian: Option<bool>,
    encoding: Option<Encoding>,
    data_file: Option<String>,
    byte_skip: i64,
    line_skip: u64,
}

/// Parses an NRRD type name.
fn parse_type(path: &Path, name: &str) -> Result<ElemType> {
    let n = name.trim().to_ascii_lowercase();
    Ok(match n.as_str() {
        "signed char" | "int8" | "int8_t" => ElemType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => ElemType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            ElemType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => ElemType::U16,
        "int" | "signed int" | "int32" | "int32_t" => ElemType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => ElemType::U32,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t" => ElemType::I64,
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            ElemType::U64
        }
        "float" => ElemType::F32,
        "double" => ElemType::F64,
        _ => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!("NRRD type '{n}'")),
            ))
        }
    })
}

/// Splits `(a,b,c) none (d, e, f)` into tokens, keeping parenthesised groups whole.
fn vector_tokens(value: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth) = (Vec::new(), String::new(), 0);
    for c in value.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            c if c.is_whitespace() && depth <= 0 => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Parses `(a,b,c)`; `None` for `none`.
fn parse_vector(path: &Path, tok: &str) -> Result<Option<Vec<f64>>> {
    if tok.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let inner = tok
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or_else(|| header_err(path, format!("'{tok}' is not a vector (a,b,c)")))?;
    inner
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map(Some)
        .map_err(|_| header_err(path, format!("'{tok}' is not a vector of numbers")))
}

fn parse_num<T: std::str::FromStr>(path: &Path, field: &str, value: &str) -> Result<T> {
    value
        .trim()
        .parse()
        .map_err(|_| header_err(path, format!("{field}: '{value}' is not a valid number")))
}

fn parse_list<T: std::str::FromStr>(path: &Path, field: &str, value: &str) -> Result<Vec<T>> {
    value
        .split_whitespace()
        .map(|v| parse_num(path, field, v))
        .collect()
}

/// Applies one `field: value` line.
fn apply_field(path: &Path, h: &mut Header, field: &str, value: &str) -> Result<()> {
    let value = value.trim();
    match field.trim().to_ascii_lowercase().as_str() {
        "type" => h.ty = Some(parse_type(path, value)?),
        "dimension" => h.dimension = Some(parse_num(path, field, value)?),
        "sizes" => h.sizes = parse_list(path, field, value)?,
        "spacings" => {
            // `nan` marks an axis without spacing (a time or vector axis).
            h.spacings = value
                .split_whitespace()
                .map(|v| match v.to_ascii_lowercase().as_str() {
                    "nan" => Ok(f64::NAN),
                    _ => parse_num(path, field, v),
                })
                .collect::<Result<_>>()?
        }
        "kinds" => {
            h.kinds = value
                .split_whitespace()
                .map(str::to_ascii_lowercase)
                .collect()
        }
        "space directions" => {
            h.directions = vector_tokens(value)
                .iter()
                .map(|t| parse_vector(path, t))
                .collect::<Result<_>>()?
        }
        "space origin" => h.origin = parse_vector(path, value)?,
        "space units" => {
            h.space_units = value
                .split('"')
                .map(str::trim)
                .filter(|u| !u.is_empty())
                .map(String::from)
                .collect()
        }
        "space" => h.space_to_lps = space_signs(value),
        "endian" => {
            h.little_endian = Some(match value.to_ascii_lowercase().as_str() {
                "little" => true,
                "big" => false,
                _ => {
                    return Err(header_err(
                        path,
                        format!("endian '{value}' (little or big)"),
                    ))
                }
            })
        }
        "encoding" => h.encoding = Some(parse_encoding(path, value)?),
        "data file" | "datafile" => h.data_file = Some(value.to_string()),
        "byte skip" | "byteskip" => h.byte_skip = parse_num(path, field, value)?,
        "line skip" | "lineskip" => h.line_skip = parse_num(path, field, value)?,
        _ => {}
    }
    Ok(())
}

fn parse_encoding(path: &Path, value: &str) -> Result<Encoding> {
    Ok(match value.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "bzip2" | "bz2" => Encoding::Bzip2,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!(
                    "NRRD encoding '{other}' (raw, gzip, bzip2, ascii)"
                )),
            ))
        }
    })
}

/// Reads and parses the header; returns it with the offset where attached data starts.
fn read_header(path: &Path) -> Result<(Header, u64)> {
    let (lines, offset, _) = header_lines(path, |l| l.is_empty(), false)?;
    let magic = lines.first().map(String::as_str).unwrap_or("");
    let version = magic.strip_prefix("NRRD000").unwrap_or("");
    if version.len() != 1 || !version.bytes().all(|b| b.is_ascii_digit()) {
        return Err(header_err(
            path,
            format!(
                "not an NRRD file: first line '{}' is not NRRD000X",
                truncate(magic)
            ),
        ));
    }
    let mut h = Header::default();
    for line in lines.iter().skip(1) {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let kv = line.find(":=");
        match line.find(':') {
            Some(i) if kv != Some(i) => {
                let (field, value) = line.split_at(i);
                let value = value.strip_prefix(':').unwrap_or(value);
                apply_field(path, &mut h, field, value)?;
            }
            Some(_) => {} // key/value pair
            None => {
                return Err(header_err(
                    path,
                    format!("line '{}' is not a field", truncate(line)),
                ))
            }
        }
    }
    Ok((h, offset))
}

fn truncate(s: &str) -> String {
    s.chars().take(60).collect()
}

/// A 4-D file's axis that is not spatial (its index among the header's axes) and its role.
type ExtraAxis = (usize, Role);

/// The spatial axes (indices into the header's axes) and, for a 4-D file, the one that is not
/// with what it holds (`None` when it has a single entry: the file is one volume).
fn spatial_axes(path: &Path, h: &Header) -> Result<(Vec<usize>, Option<ExtraAxis>)> {
    let dim = h
        .dimension
        .ok_or_else(|| header_err(path, "no 'dimension' field"))?;
    if h.sizes.len() != dim {
        return Err(header_err(
            path,
            format!("'sizes' has {} values for dimension {dim}", h.sizes.len()),
        ));
    }
    match dim {
        1..=3 => Ok(((0..dim).collect(), None)),
        4 => {
            let extra = extra_axis(h).ok_or_else(|| {
                ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!(
                        "4-D NRRD with sizes {:?}: no axis is marked as not spatial (by \
                         'kinds' or a 'none' space direction)",
                        h.sizes
                    )),
                )
            })?;
            let axes = (0..4).filter(|&a| a != extra).collect();
            if h.sizes[extra] == 1 {
                return Ok((axes, None));
            }
            Ok((axes, Some((extra, role(h, extra)))))
        }
        _ => Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!("NRRD dimension {dim} (1 to 4)")),
        )),
    }
}

/// The axis of a 4-D file that is not spatial: the one whose kind is not `domain` or `space`,
/// else the one whose space direction is `none`, else a size-1 axis at either end.
fn extra_axis(h: &Header) -> Option<usize> {
    let only = |v: Vec<usize>| (v.len() == 1).then(|| v[0]);
    if h.kinds.len() == 4 {
        let spatial = |k: &str| matches!(k, "domain" | "space");
        if let Some(a) = only((0..4).filter(|&a| !spatial(&h.kinds[a])).collect()) {
            return Some(a);
        }
    }
    if h.directions.len() == 4 {
        if let Some(a) = only((0..4).filter(|&a| h.directions[a].is_none()).collect()) {
            return Some(a);
        }
    }
    match (h.sizes.first(), h.sizes.last()) {
        (Some(1), _) => Some(0),
        (_, Some(1)) => Some(3),
        _ => None,
    }
}

/// What the non-spatial axis `a` holds, by its kind (see the module docs).
fn role(h: &Header, a: usize) -> Role {
    let kind = h.kinds.get(a).map(String::as_str).unwrap_or("");
    let size = h.sizes[a];
    let named = |k: &str| {
        if k.is_empty() || k == "???" || k == "none" {
            String::new()
        } else {
            format!("kind {k}")
        }
    };
    match kind {
        "rgb-color" | "rgba-color" | "3-color" | "4-color" if (3..=4).contains(&size) => {
            Role::Colour
        }
        "time" => Role::Time(match h.spacings.get(a) {
            Some(s) if s.is_finite() && *s > 0.0 => format!("step {s}"),
            _ => String::new(),
        }),
        "list" if a == 0 => Role::Component("kind list".into()),
        "list" | "domain" | "space" | "stub" => Role::Volume(named(kind)),
        "" | "???" | "none" if a != 0 => Role::Volume(String::new()),
        k => Role::Component(named(k)),
    }
}

/// The signs that turn coordinates of the NRRD `space` named `value` into LPS: x negated for
/// right-, y for anterior-; `None` for a non-anatomical space (scanner-xyz, 3D-right-handed).
fn space_signs(value: &str) -> Option<[f64; 3]> {
    let v = value.trim().to_ascii_lowercase();
    let (lr, ap) = match v.as_str() {
        "left-posterior-superior" | "lps" => (1.0, 1.0),
        "right-anterior-superior" | "ras" => (-1.0, -1.0),
        "left-anterior-superior" | "las" => (1.0, -1.0),
        _ => return None,
    };
    Some([lr, ap, 1.0])
}

/// Geometry of the grid: dims, spacing, origin, direction and notes.
struct Geometry {
    dims: [usize; 3],
    /// Values in the file: the 3-D volume's, times the entries of a 4th axis.
    count: u64,
    /// A 4-D file's layout and what its extra axis holds.
    four: Option<(Layout4, Role)>,
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: DMat3,
    notes: Vec<String>,
}

fn geometry(path: &Path, h: &Header) -> Result<Geometry> {
    let (axes, extra) = spatial_axes(path, h)?;
    let mut dims = [1i64; 3];
    let mut spacing = [1.0f64; 3];
    let mut notes = Vec::new();
    for (k, &a) in axes.iter().enumerate() {
        dims[k] = h.sizes.get(a).copied().unwrap_or(1);
        if let Some(Some(d)) = h.directions.get(a) {
            spacing[k] = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        } else if let Some(s) = h.spacings.get(a).filter(|s| s.is_finite()) {
            spacing[k] = s.abs();
        }
    }
    let signs = DVec3::from(h.space_to_lps.unwrap_or([1.0; 3]));
    let mut direction = DMat3::IDENTITY;
    if let Some(m) = direction_vectors(h, &axes) {
        let m = DMat3::from_cols(m.x_axis * signs, m.y_axis * signs, m.z_axis * signs);
        match split_scaled_axes(m) {
            Ok((s, d)) => (spacing, direction) = (s, d),
            Err(e) => notes.push(format!(
                "space directions are not usable as a rotation ({e}): read as an axis-aligned \
                 grid with the same spacing"
            )),
        }
    }
    let (dims, count) =
        volux_core::limits::checked_dims(dims).map_err(|e| ReadError::new(path, e))?;
    let four = match extra {
        Some((a, role)) => {
            let n = usize::try_from(h.sizes[a])
                .ok()
                .filter(|&n| n > 0)
                .ok_or_else(|| header_err(path, format!("axis {a} has size {}", h.sizes[a])))?;
            let mut sizes = [0usize; 4];
            for (k, &s) in axes.iter().enumerate() {
                sizes[s] = dims[k];
            }
            sizes[a] = n;
            Some((Layout4 { sizes, extra: a }, role))
        }
        None => None,
    };
    let count = match &four {
        Some((l, _)) => count
            .checked_mul(l.sizes[l.extra] as u64)
            .ok_or_else(|| header_err(path, "the value count overflows"))?,
        None => count,
    };
    let mut origin = [0.0; 3];
    for (o, v) in origin.iter_mut().zip(h.origin.iter().flatten()) {
        *o = *v;
    }
    if h.origin.as_ref().is_some_and(|o| o.len() == 3) {
        origin = (DVec3::from(origin) * signs).to_array();
    }
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

/// The `space directions` of the three spatial axes as matrix columns, when every one is a
/// 3-vector (a 2-D image's missing third axis is the unit normal of the other two).
fn direction_vectors(h: &Header, axes: &[usize]) -> Option<DMat3> {
    let vec3 = |a: usize| match h.directions.get(a) {
        Some(Some(d)) if d.len() == 3 => Some(DVec3::new(d[0], d[1], d[2])),
        _ => None,
    };
    let cols: Vec<DVec3> = axes.iter().map(|&a| vec3(a)).collect::<Option<_>>()?;
    match cols[..] {
        [x, y, z] => Some(DMat3::from_cols(x, y, z)),
        [x, y] => Some(DMat3::from_cols(x, y, x.cross(y).normalize_or_zero())),
        _ => None,
    }
}

/// Skips `n` lines of `reader`, returning the bytes skipped.
fn skip_lines(path: &Path, reader: &mut impl BufRead, n: u64) -> Result<u64> {
    let mut skipped = 0u64;
    for _ in 0..n {
        loop {
            let buf = reader.fill_buf().map_err(|e| ReadError::new(path, e))?;
            if buf.is_empty() {
                return Err(header_err(
                    path,
                    format!("line skip {n} passes the end of the file"),
                ));
            }
            let (used, done) = match buf.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (buf.len(), false),
            };
            reader.consume(used);
            skipped += used as u64;
            if done {
                break;
            }
        }
    }
    Ok(skipped)
}

/// Opens `file` positioned at `offset` plus `line_skip` lines; returns the reader and position.
fn open_at(path: &Path, offset: u64, line_skip: u64) -> Result<(BufReader<std::fs::File>, u64)> {
    let mut f = open_regular(path)?;
    f.seek(SeekFrom::Start(offset))
        .map_err(|e| io_error(path, e))?;
    let mut reader = BufReader::new(f);
    let skipped = skip_lines(path, &mut reader, line_skip)?;
    Ok((reader, offset + skipped))
}

/// Where the data is: its file and the offset where it starts there.
fn data_location(path: &Path, h: &Header, attached_at: u64) -> Result<(PathBuf, u64)> {
    match &h.data_file {
        None => Ok((path.to_path_buf(), attached_at)),
        Some(name) if name == "LIST" || name.split_whitespace().count() > 1 => Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!("multiple data files ('data file: {name}')")),
        )),
        Some(name) => {
            let dir = path.parent().unwrap_or(Path::new("."));
            Ok((dir.join(name), 0))
        }
    }
}

/// Reads the data section that starts at `start` of `file`.
fn read_data(
    file: &Path,
    h: &Header,
    start: u64,
    count: u64,
    notes: &mut Vec<String>,
) -> Result<Decoded> {
    let ty = h.ty.ok_or_else(|| header_err(file, "no 'type' field"))?;
    let encoding = h
        .encoding
        .ok_or_else(|| header_err(file, "no 'encoding' field"))?;
    let le = h.little_endian.unwrap_or_else(|| {
        if ty.size() > 1 && encoding != Encoding::Ascii {
            notes.push("no 'endian' field: little-endian assumed".into());
        }
        true
    });
    if h.byte_skip < -1 || (h.byte_skip == -1 && encoding != Encoding::Raw) {
        return Err(header_err(
            file,
            format!("byte skip {} (>= 0, or -1 with raw encoding)", h.byte_skip),
        ));
    }
    let (reader, pos) = open_at(file, start, h.line_skip)?;
    match encoding {
        Encoding::Raw => read_raw(file, h.byte_skip, pos, ty, le, count),
        Encoding::Gzip => {
            let compressed = regular_metadata(file)?.len().saturating_sub(pos);
            let skip = h.byte_skip as u64;
            let need = raw::data_bytes(file, ty, count)?;
            check_inflatable(file, compressed, need.saturating_add(skip))?;
            read_gzip(file, reader, skip, ty, le, count)
        }
        Encoding::Bzip2 => {
            // bzip2 has no useful bound on its expansion; memory still grows only with what
            // the stream delivers, up to the declared size ([`raw::read_stream`]).
            let skip = h.byte_skip as u64;
            read_bzip2(file, reader, skip, ty, le, count)
        }
        Encoding::Ascii => read_ascii(file, reader, pos, ty, count),
    }
}

/// Raw data at `pos` plus `byte_skip` (-1: the data ends the file).
fn read_raw(
    file: &Path,
    byte_skip: i64,
    pos: u64,
    ty: ElemType,
    le: bool,
    count: u64,
) -> Result<Decoded> {
    let len = regular_metadata(file)?.len();
    let need = raw::data_bytes(file, ty, count)?;
    let offset = if byte_skip == -1 {
        len.checked_sub(need).filter(|&o| o >= pos).ok_or_else(|| {
            ReadError::new(
                file,
                ErrorKind::Truncated {
                    expected: need,
                    found: len.saturating_sub(pos),
                },
            )
        })?
    } else {
        pos.saturating_add(byte_skip as u64)
    };
    raw::read_plain(file, offset, ty, le, count)
}

/// Gzip data; `skip` bytes of the decompressed stream are skipped first. The caller has
/// checked that the compressed bytes can hold what the header declares; inflation stops one
/// byte after the declared size ([`raw::read_stream`]).
fn read_gzip(
    file: &Path,
    reader: impl Read,
    skip: u64,
    ty: ElemType,
    le: bool,
    count: u64,
) -> Result<Decoded> {
    let mut gz = flate2::read::MultiGzDecoder::new(reader);
    let skipped = std::io::copy(&mut (&mut gz).take(skip), &mut std::io::sink())
        .map_err(|e| ReadError::new(file, e))?;
    if skipped < skip {
        return Err(ReadError::new(
            file,
            ErrorKind::Truncated {
                expected: skip,
                found: skipped,
            },
        ));
    }
    raw::read_stream(file, gz, ty, le, count)
}

/// Bzip2 data; `skip` bytes of the decompressed stream are skipped first.
fn read_bzip2(
    file: &Path,
    reader: impl Read,
    skip: u64,
    ty: ElemType,
    le: bool,
    count: u64,
) -> Result<Decoded> {
    let mut bz = bzip2::read::MultiBzDecoder::new(reader);
    let skipped = std::io::copy(&mut (&mut bz).take(skip), &mut std::io::sink())
        .map_err(|e| ReadError::new(file, e))?;
    if skipped < skip {
        return Err(ReadError::new(
            file,
            ErrorKind::Truncated {
                expected: skip,
                found: skipped,
            },
        ));
    }
    raw::read_stream(file, bz, ty, le, count)
}

/// ASCII data: the rest of the file from `pos`.
fn read_ascii(
    file: &Path,
    reader: impl Read,
    pos: u64,
    ty: ElemType,
    count: u64,
) -> Result<Decoded> {
    let len = regular_metadata(file)?.len();
    let bytes = read_exact_checked(file, reader, len.saturating_sub(pos))?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|_| ReadError::new(file, ErrorKind::Invalid("ASCII data is not text".into())))?;
    raw::parse_ascii(file, text, ty, count)
}

/// Reads an NRRD file (`.nrrd` with attached data, or a `.nhdr` detached header): the volume
/// of `choice` when a 4th axis holds several.
pub fn read(path: &Path, choice: VolumeChoice) -> Result<Grid> {
    let (h, attached_at) = read_header(path)?;
    let mut g = geometry(path, &h)?;
    let (file, start) = data_location(path, &h, attached_at)?;
    let data = read_data(&file, &h, start, g.count, &mut g.notes)?;
    let place = Place {
        spacing: g.spacing,
        origin: g.origin,
        direction: g.direction,
    };
    let four = g.four.as_ref().map(|(l, r)| (*l, r));
    let grid = crate::volumes::grid(&file, g.dims, place, data, g.notes, four, choice)?;
    space_unit(path, &h.space_units).map(|u| match u {
        Some(u) => grid.with_unit(u),
        None => grid,
    })
}

/// The unit of `space units` when every axis gives the same length unit (`None`: absent,
/// millimetres); units that differ or are not lengths are refused rather than read as mm.
fn space_unit(path: &Path, units: &[String]) -> Result<Option<&'static str>> {
    let symbols: Vec<_> = units
        .iter()
        .map(|u| volux_core::units::length_symbol(u))
        .collect();
    match symbols.as_slice() {
        [] => Ok(None),
        [Some(first), rest @ ..] if rest.iter().all(|s| s == &Some(*first)) => Ok(Some(first)),
        _ => Err(header_err(
            path,
            format!(
                "space units {units:?}: Volux reads one length unit for every axis (mm, µm, \
                 nm, cm, m)"
            ),
        )),
    }
}

/// The NRRD type name of a grid type.
fn type_name(t: ScalarType) -> &'static str {
    match t {
        ScalarType::U8 => "uint8",
        ScalarType::U16 => "uint16",
        ScalarType::I16 => "int16",
        _ => "float",
    }
}

/// Writes `grid` as an NRRD file with attached, raw, little-endian data (written atomically),
/// placed in `left-posterior-superior` space by its spacing, direction and origin. An RGB
/// grid ([`Grid::color`]) is written with its colour, as a 4-D NRRD whose first axis is
/// `RGB-color`.
pub fn write(grid: &Grid, path: &Path) -> Result<(), WriteError> {
    let werr = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let color = grid.color();
    let per_voxel = if color.is_some() { 3 } else { 1 };
    volux_core::limits::check_alloc("NRRD output", grid.len() as u64 * per_voxel, 4)
        .map_err(werr)?;
    let [x, y, z] = grid.dims();
    let [ox, oy, oz] = grid.origin().to_array();
    let (d, s) = (grid.direction(), grid.spacing());
    let axis = |c: DVec3| format!("({},{},{})", c.x, c.y, c.z);
    let dirs = [d.x_axis * s.x, d.y_axis * s.y, d.z_axis * s.z].map(axis);
    // An RGB grid keeps its colour: a 4-D NRRD whose fastest axis is the colour (as 3D
    // Slicer and ITK write RGB volumes).
    let (ty, dimension, sizes, kinds, none) = match color {
        Some(c) => (
            c.scalar_type(),
            4,
            format!("3 {x} {y} {z}"),
            "kinds: RGB-color domain domain domain\n",
            "none ",
        ),
        None => (grid.scalar_type(), 3, format!("{x} {y} {z}"), "", ""),
    };
    // Millimetres are NRRD's patient space unit; any other unit is said.
    let units = match grid.unit() {
        "mm" => String::new(),
        u => format!("space units: \"{u}\" \"{u}\" \"{u}\"\n"),
    };
    let header = format!(
        "NRRD0004\n# written by Volux\ntype: {}\ndimension: {dimension}\n\
         space: left-posterior-superior\nsizes: {sizes}\n{kinds}\
         space directions: {none}{} {} {}\nspace origin: ({ox},{oy},{oz})\n{units}\
         endian: little\nencoding: raw\n\n",
        type_name(ty),
        dirs[0],
        dirs[1],
        dirs[2]
    );
    let mut bytes = header.into_bytes();
    match color {
        Some(c) => {
            let [r, g, b] = c.channels().each_ref().map(raw::samples_le_bytes);
            let size = c.scalar_type().size();
            for ((r, g), b) in r
                .chunks_exact(size)
                .zip(g.chunks_exact(size))
                .zip(b.chunks_exact(size))
            {
                bytes.extend_from_slice(r);
                bytes.extend_from_slice(g);
                bytes.extend_from_slice(b);
            }
        }
        None => bytes.extend_from_slice(&raw::samples_le_bytes(grid.samples())),
    }
    volux_core::image::write_atomically(path, &bytes).map_err(werr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::hostile::*;
    use volux_testkit::mutate::gzip;

    /// An NRRD header for a `dims` uint8 volume with `encoding` and optional `data file`.
    fn header(dims: [u64; 3], encoding: &str, data_file: Option<&str>) -> String {
        let detached = data_file
            .map(|f| format!("data file: {f}\n"))
            .unwrap_or_default();
        format!(
            "NRRD0004\ntype: uint8\ndimension: 3\nsizes: {} {} {}\nencoding: {encoding}\n{detached}\n",
            dims[0], dims[1], dims[2]
        )
    }

    #[test]
    fn special_headers_and_data_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        if let Some(f) = fifo(d, "t.nrrd") {
            // `volux info` on this blocked forever.
            assert_refused(
                read(&f, Default::default()),
                "t.nrrd",
                "not a regular file (a FIFO)",
            );
            assert_refused(crate::load(&f, &Default::default()), "t.nrrd", "(a FIFO)");
        }
        let nhdr = d.join("z.nhdr");
        std::fs::write(&nhdr, header([2, 2, 2], "raw", Some("zero.raw"))).unwrap();
        zero_link(d, "zero.raw");
        assert_refused(
            read(&nhdr, Default::default()),
            "zero.raw",
            "(a character device)",
        );
        let nhdr = d.join("zg.nhdr");
        std::fs::write(&nhdr, header([2, 2, 2], "gzip", Some("zero.raw"))).unwrap();
        assert_refused(
            read(&nhdr, Default::default()),
            "zero.raw",
            "(a character device)",
        );
        let nhdr = d.join("l.nhdr");
        std::fs::write(&nhdr, header([2, 2, 2], "raw", Some("l.raw"))).unwrap();
        link_loop(d, "l.raw");
        assert_refused(
            read(&nhdr, Default::default()),
            "l.raw",
            "loop of symbolic links",
        );
        assert_refused(
            read(&link_loop(d, "h.nrrd"), Default::default()),
            "h.nrrd",
            "loop",
        );
    }

    #[test]
    fn gzip_data_is_bounded_by_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // A bomb: 64 MiB of zeros where the header declares 1 KiB.
        let p = d.join("bomb.nrrd");
        let mut bytes = header([16, 16, 4], "gzip", None).into_bytes();
        bytes.extend(gzip(&vec![0u8; 64 << 20]));
        std::fs::write(&p, bytes).unwrap();
        let e = read(&p, Default::default()).unwrap_err().to_string();
        assert!(
            e.contains("bomb.nrrd") && e.contains("more than the 1024 bytes"),
            "{e}"
        );
        // A matching header of 6 GiB behind 100 compressed bytes: refused before inflating.
        let p = d.join("huge.nrrd");
        let mut bytes = header([2048, 2048, 1536], "gzip", None).into_bytes();
        bytes.extend(gzip(&[0u8; 1000]));
        std::fs::write(&p, bytes).unwrap();
        let e = read(&p, Default::default()).unwrap_err();
        crate::util::hostile::assert_undeliverable(&e, 6442450944);
    }
}
