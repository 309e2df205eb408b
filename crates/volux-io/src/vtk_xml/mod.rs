//! VTK XML files, following "VTK File Formats" (XML formats section,
//! <https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html>):
//!
//! * `.vti` (`ImageData`: WholeExtent, Origin, Spacing, one Piece, PointData) → a [`Grid`];
//! * `.vtu` (`UnstructuredGrid`: one Piece with Points, Cells connectivity/offsets/types,
//!   PointData, CellData) → a [`TetMesh`](volux_core::TetMesh), cells split into tets by
//!   [`crate::cells`] (quadratic cells keep their corner nodes; the mid-edge nodes, used by no
//!   tet, are removed from the vertex list and the mesh is renumbered, with a note).
//!
//! `<DataArray>` formats `ascii`, `binary` (base64) and `appended` (raw or base64), each with
//! or without `compressor="vtkZLibDataCompressor"`, `header_type` UInt32/UInt64, `byte_order`
//! LittleEndian/BigEndian and types Int8..UInt64, Float32, Float64 are read (see [`data`]).
//! The `array` option picks a data array by name; otherwise the PointData `Scalars` array, the
//! first 1-component point array, or a cell array averaged to the vertices (noted).
//!
//! Crates: `quick-xml` parses the markup (a complete, fast XML parser; hand-parsing XML is
//! error-prone), `base64` and `flate2` decode the payloads. Raw appended data is not XML, so
//! the file is cut before `<AppendedData>` and only the part before it is parsed as XML.
pub mod data;
pub mod tree;

use std::path::Path;

use glam::Vec3;
use volux_core::Grid;

use crate::cells::{self, Attribute, CellSet};
use crate::dataset::Dataset;
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use data::Encoding;
use tree::Elem;

/// Reads a `.vti` or `.vtu` file; `array` picks a data array by name.
pub fn read(path: &Path, array: Option<&str>) -> Result<Dataset> {
    let bytes = crate::util::read_regular(path, volux_core::limits::memory_limit())?;
    let header = |m: String| ReadError::new(path, ErrorKind::Header(m));
    let (xml, appended) = split_appended(&bytes).map_err(header)?;
    let root = tree::parse(xml).map_err(header)?;
    let file = root
        .child("VTKFile")
        .ok_or_else(|| header("no <VTKFile> element".into()))?;
    let enc = encoding(file, appended).map_err(|k| ReadError::new(path, k))?;
    match file.attr("type").unwrap_or("") {
        "ImageData" => image_data(path, file, &enc, array).map(Dataset::Grid),
        "UnstructuredGrid" => unstructured(path, file, &enc, array).map(Dataset::Mesh),
        t => Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "VTKFile type '{t}': only ImageData (.vti) and UnstructuredGrid (.vtu) are read"
            )),
        )),
    }
}

/// Finds `needle` in `hay`.
fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    hay.get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|p| p + from)
}

/// The XML before `<AppendedData>`, and the appended bytes after `_` with whether they are raw.
type Split<'a> = (&'a [u8], Option<(&'a [u8], bool)>);

fn split_appended(bytes: &[u8]) -> std::result::Result<Split<'_>, String> {
    let Some(at) = find(bytes, b"<AppendedData", 0) else {
        return Ok((bytes, None));
    };
    let gt = find(bytes, b">", at).ok_or("unterminated <AppendedData> tag")?;
    let tag = tree::parse(&bytes[at..=gt])?;
    let raw = tag
        .child("AppendedData")
        .and_then(|e| e.attr("encoding"))
        .is_none_or(|e| e == "raw");
    let us = find(bytes, b"_", gt).ok_or("no '_' starting the appended data")?;
    Ok((&bytes[..at], Some((&bytes[us + 1..], raw))))
}

fn encoding<'a>(
    file: &Elem,
    appended: Option<(&'a [u8], bool)>,
) -> Result<Encoding<'a>, ErrorKind> {
    let little = match file.attr("byte_order").unwrap_or("LittleEndian") {
        "LittleEndian" => true,
        "BigEndian" => false,
        o => return Err(ErrorKind::Header(format!("unknown byte_order '{o}'"))),
    };
    let word = match file.attr("header_type").unwrap_or("UInt32") {
        "UInt32" => 4,
        "UInt64" => 8,
        h => return Err(ErrorKind::Header(format!("unknown header_type '{h}'"))),
    };
    let compressed = match file.attr("compressor") {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => {
            return Err(ErrorKind::Unsupported(format!(
                "compressor '{c}' (only vtkZLibDataCompressor is read)"
            )))
        }
    };
    Ok(Encoding {
        little,
        word,
        compressed,
        appended,
    })
}

/// The single `<Piece>` of the dataset element `kind`.
fn piece<'a>(file: &'a Elem, kind: &str) -> std::result::Result<(&'a Elem, &'a Elem), ErrorKind> {
    let ds = file
        .child(kind)
        .ok_or_else(|| ErrorKind::Header(format!("no <{kind}> element")))?;
    let pieces: Vec<&Elem> = ds.children_named("Piece").collect();
    match pieces.as_slice() {
        [p] => Ok((ds, p)),
        [] => Err(ErrorKind::Header("no <Piece>".into())),
        _ => Err(ErrorKind::Unsupported(format!(
            "{} pieces (only single-piece files are read)",
            pieces.len()
        ))),
    }
}

/// The arrays of `<PointData>` and `<CellData>`, the active `Scalars` array first; `points`
/// and `cells` are how many tuples each section's arrays must hold.
fn attributes(
    p: &Elem,
    enc: &Encoding,
    points: u64,
    cells: u64,
) -> std::result::Result<Vec<Attribute>, String> {
    let mut out = Vec::new();
    for (sec, on_cells) in [("PointData", false), ("CellData", true)] {
        let Some(s) = p.child(sec) else { continue };
        let active = s.attr("Scalars");
        let tuples = if on_cells { cells } else { points };
        let mut arrays = Vec::new();
        for e in s.children_named("DataArray") {
            let (values, ncomp) = data::decode(e, enc, data::Expect::Tuples(tuples))?;
            let name = e.attr("Name").unwrap_or("").to_string();
            arrays.push(Attribute {
                name,
                ncomp,
                values,
                on_cells,
            });
        }
        arrays.sort_by_key(|a| Some(a.name.as_str()) != active);
        out.extend(arrays);
    }
    Ok(out)
}

fn numbers<const N: usize>(
    s: Option<&str>,
    default: [f64; N],
    what: &str,
) -> Result<[f64; N], ErrorKind> {
    let Some(s) = s else { return Ok(default) };
    let v: Vec<f64> = s
        .split_ascii_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| ErrorKind::Header(format!("{what} '{s}' is not {N} numbers")))?;
    v.try_into()
        .map_err(|_| ErrorKind::Header(format!("{what} '{s}' is not {N} numbers")))
}

fn image_data(path: &Path, file: &Elem, enc: &Encoding, want: Option<&str>) -> Result<Grid> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let (ds, p) = piece(file, "ImageData").map_err(err)?;
    let ext = numbers(ds.attr("WholeExtent"), [f64::NAN; 6], "WholeExtent").map_err(err)?;
    if ext.iter().any(|e| e.fract() != 0.0) {
        return Err(err(ErrorKind::Header(format!("bad WholeExtent {ext:?}"))));
    }
    let dims = [0, 1, 2].map(|k| ((ext[2 * k + 1] - ext[2 * k]) as i64).saturating_add(1));
    let (dims, n) = volux_core::limits::checked_dims(dims).map_err(|e| err(e.into()))?;
    let spacing = numbers(ds.attr("Spacing"), [1.0; 3], "Spacing").map_err(err)?;
    let o = numbers(ds.attr("Origin"), [0.0; 3], "Origin").map_err(err)?;
    let origin = [0, 1, 2].map(|k| o[k] + ext[2 * k] * spacing[k]);
    let cells = dims
        .iter()
        .map(|&d| (d as u64).saturating_sub(1).max(1))
        .product();
    let attrs = attributes(p, enc, n, cells).map_err(|m| err(ErrorKind::Invalid(m)))?;
    let (samples, notes) =
        cells::grid_samples(&attrs, want, n as usize).map_err(|m| err(ErrorKind::Invalid(m)))?;
    let (direction, note) = image_direction(ds.attr("Direction"));
    let origin = match direction {
        Some(d) => (glam::DVec3::from(o) + d * (glam::DVec3::from(origin) - glam::DVec3::from(o)))
            .to_array(),
        None => origin,
    };
    let mut g = Grid::new(dims, spacing, origin, samples)
        .and_then(|g| g.with_direction(direction.unwrap_or(glam::DMat3::IDENTITY)))
        .map_err(|e| err(e.into()))?;
    if let Some(n) = note {
        g = g.with_note(n);
    }
    for n in notes {
        g = g.with_note(n);
    }
    Ok(g)
}

fn count(p: &Elem, key: &str) -> Result<usize, ErrorKind> {
    let s = p.attr(key).unwrap_or("");
    s.trim()
        .parse::<usize>()
        .map_err(|_| ErrorKind::Header(format!("bad {key} '{s}'")))
}

fn unstructured(
    path: &Path,
    file: &Elem,
    enc: &Encoding,
    want: Option<&str>,
) -> Result<volux_core::TetMesh> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let invalid = |m: String| err(ErrorKind::Invalid(m));
    let (_, p) = piece(file, "UnstructuredGrid").map_err(err)?;
    let np = count(p, "NumberOfPoints").map_err(err)?;
    let nc = count(p, "NumberOfCells").map_err(err)?;
    let pts = p
        .child("Points")
        .and_then(|e| e.child("DataArray"))
        .ok_or_else(|| err(ErrorKind::Header("no <Points> array".into())))?;
    let (v, _) = data::decode(
        pts,
        enc,
        data::Expect::Values((np as u64).saturating_mul(3)),
    )
    .map_err(invalid)?;
    if v.len() != np.saturating_mul(3) {
        return Err(invalid(format!(
            "Points has {} values, expected 3 x NumberOfPoints = {}",
            v.len(),
            np.saturating_mul(3)
        )));
    }
    let positions: Vec<Vec3> = (0..np)
        .map(|i| {
            Vec3::new(
                v.get(3 * i) as f32,
                v.get(3 * i + 1) as f32,
                v.get(3 * i + 2) as f32,
            )
        })
        .collect();
    drop(v);
    let cells = cell_set(p, enc, nc).map_err(invalid)?;
    let attrs = attributes(p, enc, np as u64, nc as u64).map_err(invalid)?;
    cells::check_counts(np, nc, &attrs).map_err(invalid)?;
    cells::assemble(path, positions, &cells, &attrs, want)
}

fn cell_set(p: &Elem, enc: &Encoding, nc: usize) -> std::result::Result<CellSet, String> {
    let cells = p.child("Cells").ok_or("no <Cells> element")?;
    let get = |name: &str| {
        let e = cells
            .children_named("DataArray")
            .find(|e| e.attr("Name") == Some(name))
            .ok_or_else(|| format!("no Cells array '{name}'"))?;
        // offsets and types hold one value per cell; connectivity's length depends on
        // the cell types (bounded by the file's own size before inflating).
        let expect = match name {
            "connectivity" => data::Expect::Unknown,
            _ => data::Expect::Tuples(nc as u64),
        };
        data::decode(e, enc, expect)?.0.to_indices(name)
    };
    let set = CellSet {
        connectivity: get("connectivity")?,
        offsets: get("offsets")?,
        types: get("types")?.iter().map(|&t| t.min(255) as u8).collect(),
    };
    if set.offsets.len() != nc || set.types.len() != nc {
        return Err(format!(
            "NumberOfCells is {nc} but there are {} offsets and {} types",
            set.offsets.len(),
            set.types.len()
        ));
    }
    Ok(set)
}

/// The ImageData `Direction` attribute: nine numbers, the 3x3 matrix row by row (VTK's
/// `vtkImageData::GetDirectionMatrix`), whose columns are the world directions of the index
/// axes; `None` for the identity or when absent; a note when it is malformed or not a
/// rotation (then the grid is read axis-aligned).
fn image_direction(attr: Option<&str>) -> (Option<glam::DMat3>, Option<String>) {
    let Some(text) = attr else {
        return (None, None);
    };
    let v: Option<Vec<f64>> = text
        .split_ascii_whitespace()
        .map(|t| t.parse().ok())
        .collect();
    let m = match v.as_deref() {
        Some(&[a, b, c, d, e, f, g, h, i]) => {
            glam::DMat3::from_cols_array(&[a, d, g, b, e, h, c, f, i])
        }
        _ => {
            return (
                None,
                Some(format!(
                    "Direction '{text}' is not nine numbers: ignored (axis-aligned grid)"
                )),
            )
        }
    };
    if m == glam::DMat3::IDENTITY {
        return (None, None);
    }
    match volux_core::orientation::validate_direction(m) {
        Ok(d) => (Some(d), None),
        Err(e) => (
            None,
            Some(format!(
                "Direction is not usable ({e}): ignored (axis-aligned grid)"
            )),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::hostile::*;
    use base64::Engine as _;
    use volux_testkit::mutate::zlib;

    /// A 2 x 2 x 2 zlib-compressed `.vti` whose one block of `zlib` bytes is announced as
    /// `declared` bytes (header and data as two base64 streams, as VTK writes them).
    fn vti(declared: u32, zlib: &[u8]) -> Vec<u8> {
        let b64 = base64::engine::general_purpose::STANDARD;
        let header: Vec<u8> = [1, declared, declared, zlib.len() as u32]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt32\" \
             compressor=\"vtkZLibDataCompressor\">\n<ImageData WholeExtent=\"0 1 0 1 0 1\" \
             Origin=\"0 0 0\" Spacing=\"1 1 1\">\n<Piece Extent=\"0 1 0 1 0 1\">\n\
             <PointData Scalars=\"s\">\n<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">\
             {}{}</DataArray>\n</PointData>\n</Piece>\n</ImageData>\n</VTKFile>\n",
            b64.encode(header),
            b64.encode(zlib)
        )
        .into_bytes()
    }

    #[test]
    fn a_valid_zlib_vti_reads() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ok.vti");
        std::fs::write(&p, vti(8, &zlib(&[1, 2, 3, 4, 5, 6, 7, 8]))).unwrap();
        let Dataset::Grid(g) = read(&p, None).unwrap() else {
            panic!("not a grid")
        };
        assert_eq!(g.value(1, 1, 1), 8.0);
    }

    #[test]
    fn zlib_blocks_are_bounded_by_their_bytes_and_header() {
        let dir = tempfile::tempdir().unwrap();
        // A size header claiming 1 GiB for a few bytes, where the extent asks for 8: refused
        // before inflating.
        let p = dir.path().join("claim.vti");
        std::fs::write(&p, vti(1 << 30, &zlib(&[0; 8]))).unwrap();
        let e = read(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("claim.vti")
                && e.contains("declares 1073741824 bytes")
                && e.contains("asks for 8 bytes")
                && e.contains("nothing was decoded"),
            "{e}"
        );
        // A block inflating to 64 MiB where 8 bytes are announced: stops after 9 bytes.
        let p = dir.path().join("bomb.vti");
        std::fs::write(&p, vti(8, &zlib(&vec![0; 64 << 20]))).unwrap();
        let e = read(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("bomb.vti") && e.contains("more than the 8 bytes"),
            "{e}"
        );
    }

    #[test]
    fn special_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert_refused(
            read(&zero_link(dir.path(), "z.vti"), None),
            "z.vti",
            "(a character device)",
        );
        assert_refused(read(&link_loop(dir.path(), "l.vtu"), None), "l.vtu", "loop");
        if let Some(f) = fifo(dir.path(), "f.vti") {
            assert_refused(read(&f, None), "f.vti", "(a FIFO)");
        }
    }
}
