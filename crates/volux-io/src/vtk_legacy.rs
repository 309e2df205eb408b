//! VTK legacy `.vtk` files, ASCII and BINARY (big-endian), following "VTK File Formats"
//! (<https://vtk.org/wp-content/uploads/2015/04/file-formats.pdf>, simple legacy formats):
//!
//! * `DATASET STRUCTURED_POINTS` (DIMENSIONS, SPACING or ASPECT_RATIO, ORIGIN) → a [`Grid`];
//! * `DATASET UNSTRUCTURED_GRID` (POINTS, CELLS in the classic `n id...` layout or the
//!   VTK 5.1 `OFFSETS`/`CONNECTIVITY` layout, CELL_TYPES) → a [`TetMesh`](volux_core::TetMesh), cells split into
//!   tets by [`crate::cells`];
//! * `DATASET STRUCTURED_GRID` (DIMENSIONS, POINTS) → 5 tets per cell.
//!
//! Data arrays come from `POINT_DATA` / `CELL_DATA` sections: SCALARS (with or without its
//! LOOKUP_TABLE line), VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, FIELD arrays and
//! GLOBAL_IDS/PEDIGREE_IDS; COLOR_SCALARS, standalone LOOKUP_TABLEs and METADATA blocks are
//! skipped. The `array` option picks an array by name; otherwise the first 1-component point
//! array is used. Per-cell data on a mesh is averaged to the vertices (noted). Rectilinear
//! grids and polydata are not volumes Volux renders and are reported as unsupported.
//!
//! No crate is used: the Rust VTK crates (`vtkio`) pull a large dependency tree and build a
//! general in-memory model; the legacy format is a short keyword grammar read here with a
//! byte cursor that checks every announced size against the bytes left before allocating.
use std::path::Path;

use glam::Vec3;
use volux_core::tetrahedralize::curvilinear_to_tets;
use volux_core::Grid;

use crate::cells::{self, Attribute, CellSet, NumType, Values};
use crate::dataset::Dataset;
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;

type R<T> = std::result::Result<T, ErrorKind>;

/// Reads a legacy VTK file; `array` picks a data array by name.
pub fn read(path: &Path, array: Option<&str>) -> Result<Dataset> {
    let bytes = crate::util::read_regular(path, volux_core::limits::memory_limit())?;
    let parsed = parse(&bytes).map_err(|k| ReadError::new(path, k))?;
    build(path, parsed, array)
}

/// A byte cursor over the file with line-numbered errors.
struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
    binary: bool,
    /// Whether the cursor is at the start of a line consumed by [`Cursor::line`].
    fresh_line: bool,
}

impl<'a> Cursor<'a> {
    fn line_no(&self) -> usize {
        1 + self.buf[..self.pos.min(self.buf.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }
    fn err(&self, msg: impl std::fmt::Display) -> ErrorKind {
        ErrorKind::Header(format!("line {}: {msg}", self.line_no()))
    }
    fn rest(&self) -> &'a [u8] {
        self.buf.get(self.pos..).unwrap_or(&[])
    }
    /// The next whitespace-separated token, or `None` at the end.
    fn token(&mut self) -> Option<&'a str> {
        let skip = self.rest().iter().take_while(|b| b.is_ascii_whitespace());
        self.pos += skip.count();
        let len = self
            .rest()
            .iter()
            .take_while(|b| !b.is_ascii_whitespace())
            .count();
        let t = &self.rest()[..len];
        self.pos += len;
        self.fresh_line = false;
        (len > 0).then(|| std::str::from_utf8(t).unwrap_or("\u{fffd}"))
    }
    fn need(&mut self, what: &str) -> R<&'a str> {
        self.token()
            .ok_or_else(|| self.err(format!("the file ends where {what} was expected")))
    }
    fn count(&mut self, what: &str) -> R<usize> {
        let t = self.need(what)?;
        t.parse::<usize>()
            .map_err(|_| self.err(format!("{what} '{t}' is not a non-negative integer")))
    }
    fn number(&mut self, what: &str) -> R<f64> {
        let t = self.need(what)?;
        t.parse::<f64>()
            .map_err(|_| self.err(format!("{what} '{t}' is not a number")))
    }
    /// The rest of the current line (consumed, newline included).
    fn line(&mut self) -> &'a str {
        let rest = self.rest();
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.pos += (len + 1).min(rest.len());
        self.fresh_line = true;
        std::str::from_utf8(&rest[..len]).unwrap_or("").trim()
    }
    /// Whether the next token is `word` (case-insensitive); consumes it only if so.
    fn peek_is(&mut self, word: &str) -> bool {
        let (at, fresh) = (self.pos, self.fresh_line);
        let yes = self.token().is_some_and(|t| t.eq_ignore_ascii_case(word));
        if !yes {
            self.pos = at;
            self.fresh_line = fresh;
        }
        yes
    }
    /// `n` values of `ty`: big-endian bytes after the end of the current line, or tokens.
    fn values(&mut self, n: usize, ty: NumType, what: &str) -> R<Values> {
        if self.binary && !self.fresh_line {
            self.line();
        }
        let left = self.rest().len() as u64;
        if self.binary {
            let need = (n as u64).saturating_mul(ty.size() as u64);
            if need > left {
                return Err(ErrorKind::Truncated {
                    expected: need,
                    found: left,
                });
            }
            let bytes = &self.rest()[..need as usize];
            self.pos += need as usize;
            return Ok(Values::decode(bytes, ty, false));
        }
        // Each ASCII value takes at least one digit and one separator.
        if (n as u64).saturating_mul(2) > left + 1 {
            return Err(self.err(format!(
                "{n} values announced, but only {left} bytes are left in the file"
            )));
        }
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            v.push(self.number(what)?);
        }
        Ok(Values::from_f64(v, ty))
    }
    fn num_type(&mut self, t: &str) -> R<NumType> {
        if t.eq_ignore_ascii_case("bit") {
            return Err(ErrorKind::Unsupported("'bit' arrays".into()));
        }
        NumType::from_legacy(t).ok_or_else(|| self.err(format!("unknown data type '{t}'")))
    }
}

/// What the file holds.
#[derive(Default)]
struct Parsed {
    kind: String,
    dims: Option<[i64; 3]>,
    spacing: Option<[f64; 3]>,
    origin: Option<[f64; 3]>,
    points: Option<Vec<Vec3>>,
    cells: Option<CellSet>,
    types: Option<Vec<u8>>,
    attrs: Vec<Attribute>,
    point_count: Option<usize>,
    cell_count: Option<usize>,
}

fn parse(buf: &[u8]) -> R<Parsed> {
    let mut c = Cursor {
        buf,
        pos: 0,
        binary: false,
        fresh_line: true,
    };
    if !c.line().starts_with("# vtk DataFile") {
        return Err(c.err("not a VTK legacy file (no '# vtk DataFile' line)"));
    }
    c.line();
    let mode = c.need("ASCII or BINARY")?;
    c.binary = match mode.to_ascii_uppercase().as_str() {
        "ASCII" => false,
        "BINARY" => true,
        _ => return Err(c.err(format!("expected ASCII or BINARY, found '{mode}'"))),
    };
    if !c.need("DATASET")?.eq_ignore_ascii_case("DATASET") {
        return Err(c.err("expected 'DATASET type'"));
    }
    let mut p = Parsed {
        kind: c.need("the dataset type")?.to_ascii_uppercase(),
        ..Parsed::default()
    };
    let mut on_cells: Option<bool> = None;
    while let Some(key) = c.token() {
        let key = key.to_ascii_uppercase();
        if !geometry(&mut c, &mut p, &key)? {
            section(&mut c, &mut p, &key, &mut on_cells)?;
        }
    }
    Ok(p)
}

fn triple(c: &mut Cursor, what: &str) -> R<[f64; 3]> {
    Ok([c.number(what)?, c.number(what)?, c.number(what)?])
}

/// Handles a geometry keyword; `false` if `key` is not one.
fn geometry(c: &mut Cursor, p: &mut Parsed, key: &str) -> R<bool> {
    match key {
        "DIMENSIONS" => {
            let d = triple(c, "a dimension")?;
            p.dims = Some(d.map(|x| if x.fract() == 0.0 { x as i64 } else { -1 }));
        }
        "SPACING" | "ASPECT_RATIO" => p.spacing = Some(triple(c, "a spacing")?),
        "ORIGIN" => p.origin = Some(triple(c, "an origin")?),
        "POINTS" => {
            let n = c.count("the point count")?;
            let t = c.need("the point type")?;
            let ty = c.num_type(t)?;
            let v = c.values(n.saturating_mul(3), ty, "a coordinate")?;
            p.points = Some(
                (0..n)
                    .map(|i| {
                        let g = |k| v.get(3 * i + k) as f32;
                        Vec3::new(g(0), g(1), g(2))
                    })
                    .collect(),
            );
        }
        "CELLS" => p.cells = Some(cells_section(c)?),
        "CELL_TYPES" => {
            let n = c.count("the cell count")?;
            let v = c.values(n, NumType::I32, "a cell type")?;
            let t = v.to_indices("cell type").map_err(|m| c.err(m))?;
            p.types = Some(t.iter().map(|&x| x.min(255) as u8).collect());
        }
        "X_COORDINATES" | "POLYGONS" | "LINES" | "VERTICES" | "TRIANGLE_STRIPS" => {
            return Err(ErrorKind::Unsupported(format!(
                "DATASET {} ({key}): only STRUCTURED_POINTS, STRUCTURED_GRID and UNSTRUCTURED_GRID are volumes",
                p.kind
            )))
        }
        _ => return Ok(false),
    }
    Ok(true)
}

/// `CELLS n size`, in the classic or the VTK 5.1 offsets/connectivity layout.
fn cells_section(c: &mut Cursor) -> R<CellSet> {
    let n = c.count("the cell count")?;
    let size = c.count("the cell list size")?;
    if c.peek_is("OFFSETS") {
        let t = c.need("the offsets type")?;
        let ty = c.num_type(t)?;
        let off = c.values(n, ty, "an offset")?;
        let off = off.to_indices("offset").map_err(|m| c.err(m))?;
        if !c.peek_is("CONNECTIVITY") {
            return Err(c.err("expected CONNECTIVITY after the OFFSETS"));
        }
        let t = c.need("the connectivity type")?;
        let ty = c.num_type(t)?;
        let conn = c.values(size, ty, "a node index")?;
        let connectivity = conn.to_indices("node index").map_err(|m| c.err(m))?;
        let offsets = off.get(1..).unwrap_or(&[]).to_vec();
        let types = Vec::new();
        return Ok(CellSet {
            connectivity,
            offsets,
            types,
        });
    }
    let list = c.values(size, NumType::I32, "a cell entry")?;
    let list = list.to_indices("cell entry").map_err(|m| c.err(m))?;
    classic_cells(&list, n).map_err(|m| c.err(m))
}

/// Converts the classic `npts id id ...` list of `n` cells.
fn classic_cells(list: &[u64], n: usize) -> std::result::Result<CellSet, String> {
    let mut set = CellSet::default();
    let mut at = 0usize;
    for i in 0..n {
        let k = *list
            .get(at)
            .ok_or_else(|| format!("the cell list ends before cell {i} of {n}"))?;
        let ids = list
            .get(at + 1..at.saturating_add(1).saturating_add(k as usize))
            .ok_or_else(|| format!("cell {i} announces {k} nodes beyond the cell list"))?;
        set.connectivity.extend_from_slice(ids);
        set.offsets.push(set.connectivity.len() as u64);
        at += 1 + k as usize;
    }
    Ok(set)
}

/// Handles the data-section keywords.
fn section(c: &mut Cursor, p: &mut Parsed, key: &str, on_cells: &mut Option<bool>) -> R<()> {
    let tuples = |on: Option<bool>, p: &Parsed| match on {
        Some(true) => p.cell_count.unwrap_or(0),
        _ => p.point_count.unwrap_or(0),
    };
    match key {
        "POINT_DATA" => {
            p.point_count = Some(c.count("the point count")?);
            *on_cells = Some(false);
        }
        "CELL_DATA" => {
            p.cell_count = Some(c.count("the cell count")?);
            *on_cells = Some(true);
        }
        "FIELD" => {
            c.need("the field name")?;
            let arrays = c.count("the number of arrays")?;
            for _ in 0..arrays {
                if let Some(a) = field_array(c, *on_cells)? {
                    p.attrs.push(a);
                }
            }
        }
        "METADATA" => skip_metadata(c),
        "LOOKUP_TABLE" => {
            c.need("the table name")?;
            let n = c.count("the table size")?;
            let ty = if c.binary { NumType::U8 } else { NumType::F32 };
            c.values(n.saturating_mul(4), ty, "a table entry")?;
        }
        "COLOR_SCALARS" => {
            c.need("the array name")?;
            let k = c.count("the number of components")?;
            let ty = if c.binary { NumType::U8 } else { NumType::F32 };
            c.values(tuples(*on_cells, p).saturating_mul(k), ty, "a color")?;
        }
        _ => {
            let on = on_cells.ok_or_else(|| c.err(format!("unknown keyword '{key}'")))?;
            let a = attribute(c, key, on, tuples(*on_cells, p))?;
            p.attrs.push(a);
        }
    }
    Ok(())
}

/// SCALARS, VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, GLOBAL_IDS, PEDIGREE_IDS.
fn attribute(c: &mut Cursor, key: &str, on_cells: bool, n: usize) -> R<Attribute> {
    let name = c.need("the array name")?.to_string();
    let (ncomp, ty) = match key {
        "SCALARS" => {
            let rest = c.line();
            let mut it = rest.split_ascii_whitespace();
            let t = it.next().unwrap_or("");
            let ty = c.num_type(t)?;
            let k = match it.next() {
                Some(k) => k
                    .parse::<usize>()
                    .ok()
                    .filter(|k| (1..=4).contains(k))
                    .ok_or_else(|| c.err(format!("bad component count '{k}'")))?,
                None => 1,
            };
            if c.peek_is("LOOKUP_TABLE") {
                c.need("the table name")?;
            }
            (k, ty)
        }
        "VECTORS" | "NORMALS" | "TENSORS" | "GLOBAL_IDS" | "PEDIGREE_IDS" => {
            let t = c.need("the data type")?;
            let k = match key {
                "TENSORS" => 9,
                "VECTORS" | "NORMALS" => 3,
                _ => 1,
            };
            (k, c.num_type(t)?)
        }
        "TEXTURE_COORDINATES" => {
            let k = c.count("the dimension")?;
            let t = c.need("the data type")?;
            (k.clamp(1, 3), c.num_type(t)?)
        }
        _ => return Err(c.err(format!("unknown keyword '{key}'"))),
    };
    let values = c.values(n.saturating_mul(ncomp), ty, "a value")?;
    Ok(Attribute {
        name,
        ncomp,
        values,
        on_cells,
    })
}

/// One FIELD array; `None` for NULL_ARRAY and dataset-level field data.
fn field_array(c: &mut Cursor, on_cells: Option<bool>) -> R<Option<Attribute>> {
    let name = c.need("the array name")?.to_string();
    if name == "NULL_ARRAY" {
        return Ok(None);
    }
    let ncomp = c.count("the number of components")?;
    let ntuples = c.count("the number of tuples")?;
    let t = c.need("the data type")?;
    let ty = c.num_type(t)?;
    let values = c.values(ntuples.saturating_mul(ncomp), ty, "a value")?;
    Ok(on_cells.map(|on_cells| Attribute {
        name,
        ncomp: ncomp.max(1),
        values,
        on_cells,
    }))
}

/// Skips a METADATA block: lines up to an empty line.
fn skip_metadata(c: &mut Cursor) {
    c.line();
    while !c.rest().is_empty() && !c.line().is_empty() {}
}

/// Builds the dataset.
fn build(path: &Path, p: Parsed, array: Option<&str>) -> Result<Dataset> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let header = |m: &str| err(ErrorKind::Header(m.to_string()));
    match p.kind.as_str() {
        "STRUCTURED_POINTS" => build_grid(path, p, array).map(Dataset::Grid),
        "UNSTRUCTURED_GRID" => {
            let points = p.points.ok_or_else(|| header("no POINTS"))?;
            let mut cells = p.cells.ok_or_else(|| header("no CELLS"))?;
            cells.types = p.types.ok_or_else(|| header("no CELL_TYPES"))?;
            check_counts(path, points.len(), cells.types.len(), &p.attrs)?;
            cells::assemble(path, points, &cells, &p.attrs, array).map(Dataset::Mesh)
        }
        "STRUCTURED_GRID" => {
            let dims = p.dims.ok_or_else(|| header("no DIMENSIONS"))?;
            let (dims, n) = volux_core::limits::checked_dims(dims).map_err(|e| err(e.into()))?;
            let points = p.points.ok_or_else(|| header("no POINTS"))?;
            check_counts(path, n as usize, 0, &p.attrs)?;
            let (scalars, note) = point_scalars(&p.attrs, array, n as usize).map_err(err)?;
            let mesh =
                curvilinear_to_tets(dims, points, scalars, None).map_err(|e| err(e.into()))?;
            Ok(Dataset::Mesh(mesh.with_note(note)))
        }
        k => Err(err(ErrorKind::Unsupported(format!(
            "DATASET {k}: only STRUCTURED_POINTS, STRUCTURED_GRID and UNSTRUCTURED_GRID are read"
        )))),
    }
}

fn check_counts(path: &Path, points: usize, cells: usize, attrs: &[Attribute]) -> Result<()> {
    cells::check_counts(points, cells, attrs)
        .map_err(|m| ReadError::new(path, ErrorKind::Header(m)))
}

/// One `f32` per point from the chosen point array.
fn point_scalars(attrs: &[Attribute], want: Option<&str>, n: usize) -> R<(Vec<f32>, String)> {
    let a = cells::pick(attrs, want)
        .map_err(ErrorKind::Invalid)?
        .filter(|a| !a.on_cells);
    match a {
        Some(a) => Ok((
            a.values.tuples_f32(a.ncomp),
            format!("scalars: point array '{}'", a.name),
        )),
        None => Ok((vec![0.0; n], "no point data: scalars set to 0".into())),
    }
}

fn build_grid(path: &Path, p: Parsed, want: Option<&str>) -> Result<Grid> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let dims = p
        .dims
        .ok_or_else(|| err(ErrorKind::Header("no DIMENSIONS".into())))?;
    let (dims, n) = volux_core::limits::checked_dims(dims).map_err(|e| err(e.into()))?;
    check_counts(path, n as usize, 0, &p.attrs)?;
    let (samples, notes) =
        cells::grid_samples(&p.attrs, want, n as usize).map_err(|m| err(ErrorKind::Invalid(m)))?;
    let spacing = p.spacing.unwrap_or([1.0; 3]);
    let origin = p.origin.unwrap_or([0.0; 3]);
    let mut g = Grid::new(dims, spacing, origin, samples).map_err(|e| err(e.into()))?;
    for n in notes {
        g = g.with_note(n);
    }
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused() {
        use crate::util::hostile::*;
        let dir = tempfile::tempdir().unwrap();
        let zero = zero_link(dir.path(), "zm.vtk");
        assert_refused(read(&zero, None), "zm.vtk", "(a character device)");
        let looped = link_loop(dir.path(), "lm.vtk");
        assert_refused(read(&looped, None), "lm.vtk", "loop");
        if let Some(f) = fifo(dir.path(), "fm.vtk") {
            assert_refused(read(&f, None), "fm.vtk", "(a FIFO)");
        }
    }

    #[test]
    fn classic_cells_reject_overruns() {
        assert!(classic_cells(&[4, 0, 1, 2, 3], 1).is_ok());
        assert!(classic_cells(&[4, 0, 1, 2], 1).is_err());
        assert!(classic_cells(&[4, 0, 1, 2, 3], 2).is_err());
        assert!(classic_cells(&[u32::MAX as u64], 1).is_err());
    }
}
