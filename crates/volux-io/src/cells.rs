//! Helpers shared by the two VTK readers ([`crate::vtk_legacy`], [`crate::vtk_xml`]): typed
//! value arrays, the choice of the scalar array, and the split of VTK cells into tetrahedra.
//!
//! Cell types and node orders follow the VTK file-format document
//! (<https://vtk.org/wp-content/uploads/2015/04/file-formats.pdf>, figures 2 and 3).
//!
//! * tetra (10) is kept as is;
//! * pyramid (14) becomes 2 tets, its base cut along the diagonal through its lowest global
//!   vertex index;
//! * wedge (13) becomes 3 tets and voxel (11) / hexahedron (12) 6 tets, by the same rule
//!   (Dompierre et al., "How to subdivide pyramids, prisms and hexahedra into tetrahedra",
//!   1999): every quadrilateral face is cut along the diagonal through its lowest global index,
//!   so two cells sharing a face cut it the same way and the tet mesh conforms;
//! * quadratic cells (24 tetra, 25 hexahedron, 26 wedge, 27 pyramid, 29 triquadratic
//!   hexahedron) keep their corner nodes (noted);
//! * vertices that no tet uses (the mid-edge nodes of quadratic cells, nodes of 2D cells) are
//!   removed and the tets renumbered (noted), so they neither cost memory nor widen the scalar
//!   range with the 0 that cell-to-point averaging leaves on them;
//! * 0D, 1D and 2D cells (and unknown types) are skipped and counted in a note.
//!
//! No crate is used: VTK cell handling is small and specific to this project.
use std::path::Path;

use glam::Vec3;
use volux_core::{Buffer, Samples, TetMesh};

use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;

/// A numeric type of a VTK array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NumType {
    /// Signed 8-bit.
    I8,
    /// Unsigned 8-bit.
    U8,
    /// Signed 16-bit.
    I16,
    /// Unsigned 16-bit.
    U16,
    /// Signed 32-bit.
    I32,
    /// Unsigned 32-bit.
    U32,
    /// Signed 64-bit.
    I64,
    /// Unsigned 64-bit.
    U64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl NumType {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            NumType::I8 | NumType::U8 => 1,
            NumType::I16 | NumType::U16 => 2,
            NumType::I32 | NumType::U32 | NumType::F32 => 4,
            NumType::I64 | NumType::U64 | NumType::F64 => 8,
        }
    }
    /// The VTK XML name (`Int8` ... `Float64`).
    pub fn name(self) -> &'static str {
        match self {
            NumType::I8 => "Int8",
            NumType::U8 => "UInt8",
            NumType::I16 => "Int16",
            NumType::U16 => "UInt16",
            NumType::I32 => "Int32",
            NumType::U32 => "UInt32",
            NumType::I64 => "Int64",
            NumType::U64 => "UInt64",
            NumType::F32 => "Float32",
            NumType::F64 => "Float64",
        }
    }
    /// Parses a VTK XML name (`Int8`..`UInt64`, `Float32`, `Float64`).
    pub fn from_xml(name: &str) -> Option<Self> {
        [
            NumType::I8,
            NumType::U8,
            NumType::I16,
            NumType::U16,
            NumType::I32,
            NumType::U32,
            NumType::I64,
            NumType::U64,
            NumType::F32,
            NumType::F64,
        ]
        .into_iter()
        .find(|t| t.name().eq_ignore_ascii_case(name))
    }
    /// Parses a VTK legacy type name (`unsigned_char`, `float`, `vtktypeint64`, ...).
    pub fn from_legacy(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "char" | "signed_char" | "vtktypeint8" => NumType::I8,
            "unsigned_char" | "vtktypeuint8" => NumType::U8,
            "short" | "vtktypeint16" => NumType::I16,
            "unsigned_short" | "vtktypeuint16" => NumType::U16,
            "int" | "vtktypeint32" | "vtkidtype" => NumType::I32,
            "unsigned_int" | "vtktypeuint32" => NumType::U32,
            "long" | "vtktypeint64" | "long_long" | "__int64" => NumType::I64,
            "unsigned_long" | "vtktypeuint64" | "unsigned_long_long" | "unsigned___int64" => {
                NumType::U64
            }
            "float" | "vtktypefloat32" => NumType::F32,
            "double" | "vtktypefloat64" => NumType::F64,
            _ => return None,
        })
    }
}

/// Decoded values: the grid types natively, every other type as `f64` (with its source type).
#[derive(Clone, Debug)]
pub enum Values {
    /// Unsigned 8-bit.
    U8(Vec<u8>),
    /// Unsigned 16-bit.
    U16(Vec<u16>),
    /// Signed 16-bit.
    I16(Vec<i16>),
    /// 32-bit float.
    F32(Vec<f32>),
    /// Any other type, widened to `f64`.
    F64(Vec<f64>, NumType),
}

/// Reads one value of `N` bytes in the given byte order.
fn word<const N: usize>(c: &[u8], little: bool) -> [u8; N] {
    let mut b = [0u8; N];
    b.copy_from_slice(&c[..N]);
    if !little {
        b.reverse();
    }
    b
}

impl Values {
    /// Decodes `bytes` (a whole number of values) of type `ty`; trailing partial values are
    /// ignored by the caller's length check.
    pub fn decode(bytes: &[u8], ty: NumType, little: bool) -> Self {
        let n = ty.size();
        let it = bytes.chunks_exact(n);
        match ty {
            NumType::U8 => Values::U8(bytes.to_vec()),
            NumType::U16 => Values::U16(it.map(|c| u16::from_le_bytes(word(c, little))).collect()),
            NumType::I16 => Values::I16(it.map(|c| i16::from_le_bytes(word(c, little))).collect()),
            NumType::F32 => Values::F32(it.map(|c| f32::from_le_bytes(word(c, little))).collect()),
            _ => Values::F64(
                it.map(|c| match ty {
                    NumType::I8 => c[0] as i8 as f64,
                    NumType::I32 => i32::from_le_bytes(word(c, little)) as f64,
                    NumType::U32 => u32::from_le_bytes(word(c, little)) as f64,
                    NumType::I64 => i64::from_le_bytes(word(c, little)) as f64,
                    NumType::U64 => u64::from_le_bytes(word(c, little)) as f64,
                    _ => f64::from_le_bytes(word(c, little)),
                })
                .collect(),
                ty,
            ),
        }
    }

    /// Converts parsed text values to type `ty` (out-of-range integers saturate).
    pub fn from_f64(v: Vec<f64>, ty: NumType) -> Self {
        match ty {
            NumType::U8 => Values::U8(v.iter().map(|&x| x as u8).collect()),
            NumType::U16 => Values::U16(v.iter().map(|&x| x as u16).collect()),
            NumType::I16 => Values::I16(v.iter().map(|&x| x as i16).collect()),
            NumType::F32 => Values::F32(v.iter().map(|&x| x as f32).collect()),
            _ => Values::F64(v, ty),
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Values::U8(v) => v.len(),
            Values::U16(v) => v.len(),
            Values::I16(v) => v.len(),
            Values::F32(v) => v.len(),
            Values::F64(v, _) => v.len(),
        }
    }
    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Value `i` as `f64`.
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Values::U8(v) => v[i] as f64,
            Values::U16(v) => v[i] as f64,
            Values::I16(v) => v[i] as f64,
            Values::F32(v) => v[i] as f64,
            Values::F64(v, _) => v[i],
        }
    }
    /// The source type.
    pub fn num_type(&self) -> NumType {
        match self {
            Values::U8(_) => NumType::U8,
            Values::U16(_) => NumType::U16,
            Values::I16(_) => NumType::I16,
            Values::F32(_) => NumType::F32,
            Values::F64(_, t) => *t,
        }
    }
    /// The values as non-negative integers (cell connectivity, offsets, types).
    pub fn to_indices(&self, what: &str) -> std::result::Result<Vec<u64>, String> {
        (0..self.len())
            .map(|i| {
                let v = self.get(i);
                if v >= 0.0 && v.fract() == 0.0 && v < 2f64.powi(53) {
                    Ok(v as u64)
                } else {
                    Err(format!(
                        "{what} value {i} is {v}, not a non-negative integer"
                    ))
                }
            })
            .collect()
    }
    /// One `f32` per tuple of `ncomp` components: the value itself, or the Euclidean norm of a
    /// vector tuple.
    pub fn tuples_f32(&self, ncomp: usize) -> Vec<f32> {
        let ncomp = ncomp.max(1);
        (0..self.len() / ncomp)
            .map(|t| {
                if ncomp == 1 {
                    self.get(t) as f32
                } else {
                    let s: f64 = (0..ncomp).map(|c| self.get(t * ncomp + c).powi(2)).sum();
                    s.sqrt() as f32
                }
            })
            .collect()
    }
    /// Grid samples: native for `u8`/`u16`/`i16`/`f32`, else converted to `f32` (with a note).
    pub fn into_samples(self) -> (Samples, Option<String>) {
        match self {
            Values::U8(v) => (Samples::U8(Buffer::owned(v)), None),
            Values::U16(v) => (Samples::U16(Buffer::owned(v)), None),
            Values::I16(v) => (Samples::I16(Buffer::owned(v)), None),
            Values::F32(v) => (Samples::F32(Buffer::owned(v)), None),
            Values::F64(v, t) => (
                Samples::F32(Buffer::owned(v.iter().map(|&x| x as f32).collect())),
                Some(format!("converted from {} to float32", t.name())),
            ),
        }
    }
}

/// A named data array attached to points or cells.
#[derive(Clone, Debug)]
pub struct Attribute {
    /// The array name.
    pub name: String,
    /// Components per tuple.
    pub ncomp: usize,
    /// The values, `ncomp` per tuple.
    pub values: Values,
    /// Whether the array is per cell (else per point).
    pub on_cells: bool,
}

/// Picks the scalar array: the one named `want`, else the first 1-component point array, else
/// the first point array, else the first cell array. `Ok(None)` when there is no array at all.
pub fn pick<'a>(
    attrs: &'a [Attribute],
    want: Option<&str>,
) -> std::result::Result<Option<&'a Attribute>, String> {
    if let Some(w) = want {
        return match attrs.iter().find(|a| a.name == w) {
            Some(a) => Ok(Some(a)),
            None => Err(format!(
                "no data array named '{w}' (arrays: {})",
                names(attrs)
            )),
        };
    }
    let point = |one: bool| attrs.iter().find(|a| !a.on_cells && (!one || a.ncomp == 1));
    Ok(point(true)
        .or_else(|| point(false))
        .or_else(|| attrs.iter().find(|a| a.on_cells)))
}

/// The names of the arrays, for messages.
pub fn names(attrs: &[Attribute]) -> String {
    if attrs.is_empty() {
        return "none".into();
    }
    let v: Vec<String> = attrs
        .iter()
        .map(|a| {
            let at = if a.on_cells { "cell" } else { "point" };
            format!("'{}' ({at}, {} comp.)", a.name, a.ncomp)
        })
        .collect();
    v.join(", ")
}

/// Point arrays must have one tuple per point, cell arrays one per cell (unless `cells` is 0:
/// datasets without cells ignore cell arrays).
pub fn check_counts(
    points: usize,
    cells: usize,
    attrs: &[Attribute],
) -> std::result::Result<(), String> {
    for a in attrs {
        let (want, what) = if a.on_cells {
            (cells, "cells")
        } else {
            (points, "points")
        };
        if (a.on_cells && cells == 0) || a.values.len() == want.saturating_mul(a.ncomp) {
            continue;
        }
        return Err(format!(
            "array '{}' has {} values for {want} {what} of {} components",
            a.name,
            a.values.len(),
            a.ncomp
        ));
    }
    Ok(())
}

/// Grid samples from the chosen point array (`n` values): native type where possible, the
/// magnitude of vector arrays as `f32`; plus notes.
pub fn grid_samples(
    attrs: &[Attribute],
    want: Option<&str>,
    n: usize,
) -> std::result::Result<(Samples, Vec<String>), String> {
    let a = pick(attrs, want)?.filter(|a| !a.on_cells).ok_or_else(|| {
        format!(
            "no point data array to use as the grid values (arrays: {})",
            names(attrs)
        )
    })?;
    if a.values.len() != n.saturating_mul(a.ncomp) {
        return Err(format!(
            "array '{}' has {} values, the grid has {n} points of {} components",
            a.name,
            a.values.len(),
            a.ncomp
        ));
    }
    let mut notes = vec![format!("values: point array '{}'", a.name)];
    let (samples, note) = if a.ncomp == 1 {
        a.values.clone().into_samples()
    } else {
        notes.push(format!("magnitude of its {} components", a.ncomp));
        (
            Values::F32(a.values.tuples_f32(a.ncomp)).into_samples().0,
            None,
        )
    };
    notes.extend(note);
    Ok((samples, notes))
}

/// Cells in the VTK XML layout: all node indices, the end offset of each cell, its type.
#[derive(Clone, Debug, Default)]
pub struct CellSet {
    /// Node indices of all cells, concatenated.
    pub connectivity: Vec<u64>,
    /// End offset (exclusive) of each cell in `connectivity`.
    pub offsets: Vec<u64>,
    /// VTK cell type of each cell.
    pub types: Vec<u8>,
}

/// What a VTK cell type becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A 3D cell with `corners` linear corner nodes, needing at least `nodes` nodes.
    Solid {
        corners: usize,
        nodes: usize,
        quadratic: bool,
    },
    /// A 0D, 1D or 2D cell.
    Lower,
    /// A type this reader does not split.
    Unknown,
}

fn kind(ty: u8) -> Kind {
    let solid = |corners, nodes, quadratic| Kind::Solid {
        corners,
        nodes,
        quadratic,
    };
    match ty {
        10 => solid(4, 4, false),
        11 | 12 => solid(8, 8, false),
        13 => solid(6, 6, false),
        14 => solid(5, 5, false),
        24 => solid(4, 10, true),
        25 => solid(8, 20, true),
        26 => solid(6, 15, true),
        27 => solid(5, 13, true),
        29 => solid(8, 27, true),
        1..=9 | 21 | 22 | 23 | 28 | 30..=32 | 34 | 35 | 36 | 37 => Kind::Lower,
        _ => Kind::Unknown,
    }
}

/// Hexahedron faces (VTK node order), each a quad.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// Two tets of the pyramid with base `q` (a quad, in order) and apex `a`, the base cut along
/// the diagonal through its lowest index.
fn pyramid(q: [u32; 4], a: u32, out: &mut Vec<[u32; 4]>) {
    let lowest = (0..4).min_by_key(|&i| q[i]).unwrap_or(0);
    if lowest % 2 == 0 {
        out.push([q[0], q[1], q[2], a]);
        out.push([q[0], q[2], q[3], a]);
    } else {
        out.push([q[1], q[2], q[3], a]);
        out.push([q[1], q[3], q[0], a]);
    }
}

/// Three tets of a wedge (triangles 0-1-2 and 3-4-5): the tet from the lowest node to the
/// opposite triangle, and the pyramid from that node to the quad that does not hold it.
fn wedge(n: [u32; 6], out: &mut Vec<[u32; 4]>) {
    let v = (0..6).min_by_key(|&i| n[i]).unwrap_or(0);
    let (flip, rot) = (v / 3, v % 3);
    let l: [u32; 6] = std::array::from_fn(|i| n[((i / 3) ^ flip) * 3 + (i % 3 + rot) % 3]);
    out.push([l[0], l[3], l[4], l[5]]);
    pyramid([l[1], l[2], l[5], l[4]], l[0], out);
}

/// Six tets of a hexahedron: pyramids from the lowest node to the three faces without it.
fn hexahedron(n: [u32; 8], out: &mut Vec<[u32; 4]>) {
    let v = (0..8).min_by_key(|&i| n[i]).unwrap_or(0);
    for f in HEX_FACES.iter().filter(|f| !f.contains(&v)) {
        pyramid(f.map(|i| n[i]), n[v], out);
    }
}

/// Appends the tets of one cell with `c` the corner nodes.
fn split(ty: u8, c: &[u32], out: &mut Vec<[u32; 4]>) {
    let arr = |i: usize| c.get(i).copied().unwrap_or(0);
    match ty {
        10 | 24 => out.push([arr(0), arr(1), arr(2), arr(3)]),
        11 => hexahedron([0, 1, 3, 2, 4, 5, 7, 6].map(arr), out),
        12 | 25 | 29 => hexahedron(std::array::from_fn(arr), out),
        13 | 26 => wedge(std::array::from_fn(arr), out),
        14 | 27 => pyramid([arr(0), arr(1), arr(2), arr(3)], arr(4), out),
        _ => {}
    }
}

/// Tets from the cells, plus notes on what was converted or skipped.
#[derive(Clone, Debug, Default)]
pub struct Split {
    /// The tets (orientation fixed later by [`TetMesh::new`]).
    pub tets: Vec<[u32; 4]>,
    /// Notes for the mesh.
    pub notes: Vec<String>,
}

/// Validates the cells and splits them into tets. `n_points` bounds the node indices.
pub fn to_tets(cells: &CellSet, n_points: usize) -> std::result::Result<Split, String> {
    check_layout(cells)?;
    let mut out = Split::default();
    let (mut quadratic, mut lower, mut unknown, mut split_cells) = (0usize, 0usize, 0usize, 0usize);
    let mut start = 0usize;
    for (i, (&end, &ty)) in cells.offsets.iter().zip(&cells.types).enumerate() {
        let nodes = &cells.connectivity[start..end as usize];
        start = end as usize;
        match kind(ty) {
            Kind::Solid {
                corners,
                nodes: need,
                quadratic: q,
            } => {
                if nodes.len() < need {
                    return Err(format!(
                        "cell {i} (type {ty}) has {} nodes, needs {need}",
                        nodes.len()
                    ));
                }
                let mut c = [0u32; 8];
                for (k, &v) in nodes.iter().take(corners).enumerate() {
                    if v >= n_points as u64 {
                        return Err(format!(
                            "cell {i} uses node {v}, but there are {n_points} points"
                        ));
                    }
                    c[k] = v as u32;
                }
                quadratic += q as usize;
                split_cells += (!matches!(ty, 10 | 24)) as usize;
                split(ty, &c[..corners], &mut out.tets);
            }
            Kind::Lower => lower += 1,
            Kind::Unknown => unknown += 1,
        }
    }
    if quadratic > 0 {
        out.notes.push(format!(
            "{quadratic} quadratic cells: only their corner nodes are used (mid-edge nodes unused)"
        ));
    }
    if split_cells > 0 {
        out.notes.push(format!(
            "{split_cells} hexahedra/voxels/wedges/pyramids split into tetrahedra"
        ));
    }
    if lower > 0 {
        out.notes
            .push(format!("{lower} 0D/1D/2D cells ignored (not volumes)"));
    }
    if unknown > 0 {
        out.notes.push(format!(
            "{unknown} cells of unsupported types (polyhedra, higher order) ignored"
        ));
    }
    Ok(out)
}

/// Offsets must increase and stay within the connectivity; one type per cell.
fn check_layout(cells: &CellSet) -> std::result::Result<(), String> {
    if cells.offsets.len() != cells.types.len() {
        return Err(format!(
            "{} cell offsets but {} cell types",
            cells.offsets.len(),
            cells.types.len()
        ));
    }
    let mut prev = 0u64;
    for (i, &o) in cells.offsets.iter().enumerate() {
        if o < prev || o > cells.connectivity.len() as u64 {
            return Err(format!(
                "cell {i} ends at offset {o}, outside {}..={} (connectivity has {} entries)",
                prev,
                cells.connectivity.len(),
                cells.connectivity.len()
            ));
        }
        prev = o;
    }
    Ok(())
}

/// Averages per-cell values to the corner nodes of the 3D cells (0 where no cell touches).
pub fn cell_to_point(cells: &CellSet, n_points: usize, values: &[f32]) -> Vec<f32> {
    let mut sum = vec![0f64; n_points];
    let mut count = vec![0u32; n_points];
    let mut start = 0usize;
    for (i, (&end, &ty)) in cells.offsets.iter().zip(&cells.types).enumerate() {
        let nodes = cells.connectivity.get(start..end as usize).unwrap_or(&[]);
        start = end as usize;
        let (Kind::Solid { corners, .. }, Some(&v)) = (kind(ty), values.get(i)) else {
            continue;
        };
        for &n in nodes.iter().take(corners) {
            if let (Some(s), Some(c)) = (sum.get_mut(n as usize), count.get_mut(n as usize)) {
                *s += v as f64;
                *c += 1;
            }
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(&s, &c)| if c > 0 { (s / c as f64) as f32 } else { 0.0 })
        .collect()
}

/// Builds the mesh from points, cells and data arrays, choosing the scalar array with
/// [`pick`]; `n_cells` is the cell count that cell arrays must match.
pub fn assemble(
    path: &Path,
    positions: Vec<Vec3>,
    cells: &CellSet,
    attrs: &[Attribute],
    want: Option<&str>,
) -> Result<TetMesh> {
    let invalid = |m: String| ReadError::new(path, ErrorKind::Invalid(m));
    let n = positions.len();
    let split = to_tets(cells, n).map_err(invalid)?;
    if split.tets.is_empty() {
        return Err(invalid(format!(
            "no volume cells: {} cells, none of them 3D ({})",
            cells.types.len(),
            split.notes.join("; ")
        )));
    }
    let (scalars, note) = scalars_for(cells, n, attrs, want).map_err(invalid)?;
    let mut tets = split.tets;
    let (positions, scalars, removed) = compact(positions, scalars, &mut tets);
    let mut mesh = TetMesh::new(positions, scalars, tets).map_err(|e| ReadError::new(path, e))?;
    let removed = (removed > 0).then(|| format!("{removed} vertices used by no tet removed"));
    for s in split.notes.into_iter().chain(note).chain(removed) {
        mesh = mesh.with_note(s);
    }
    Ok(mesh)
}

/// Drops the vertices no tet uses and renumbers the tets; returns how many were dropped.
fn compact(
    positions: Vec<Vec3>,
    scalars: Vec<f32>,
    tets: &mut [[u32; 4]],
) -> (Vec<Vec3>, Vec<f32>, usize) {
    let mut used = vec![false; positions.len()];
    for t in tets.iter() {
        for &v in t {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
    }
    let kept = used.iter().filter(|&&u| u).count();
    if kept == positions.len() {
        return (positions, scalars, 0);
    }
    let mut new_id = vec![u32::MAX; positions.len()];
    let (mut p, mut s) = (Vec::with_capacity(kept), Vec::with_capacity(kept));
    for (i, _) in used.iter().enumerate().filter(|(_, &u)| u) {
        new_id[i] = p.len() as u32;
        p.push(positions[i]);
        s.push(scalars.get(i).copied().unwrap_or(0.0));
    }
    for t in tets.iter_mut() {
        *t = t.map(|v| new_id.get(v as usize).copied().unwrap_or(v));
    }
    let removed = positions.len() - kept;
    (p, s, removed)
}

/// One scalar per point from the chosen array, and a note on how it was obtained.
fn scalars_for(
    cells: &CellSet,
    n: usize,
    attrs: &[Attribute],
    want: Option<&str>,
) -> std::result::Result<(Vec<f32>, Option<String>), String> {
    let Some(a) = pick(attrs, want)? else {
        return Ok((
            vec![0.0; n],
            Some("no data arrays: scalars set to 0".into()),
        ));
    };
    let tuples = a.values.tuples_f32(a.ncomp);
    let expect = if a.on_cells { cells.types.len() } else { n };
    if tuples.len() != expect || a.values.len() != expect * a.ncomp.max(1) {
        return Err(format!(
            "array '{}' has {} values, expected {expect} tuples of {} components",
            a.name,
            a.values.len(),
            a.ncomp
        ));
    }
    let mut notes = vec![format!("scalars: array '{}'", a.name)];
    if a.ncomp > 1 {
        notes.push(format!("magnitude of its {} components", a.ncomp));
    }
    if a.on_cells {
        notes.push("per-cell values averaged to the vertices".into());
        return Ok((cell_to_point(cells, n, &tuples), Some(notes.join(", "))));
    }
    Ok((tuples, Some(notes.join(", "))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::mesh::signed_volume6;

    fn volume(p: &[Vec3], tets: &[[u32; 4]]) -> f64 {
        tets.iter()
            .map(|t| {
                let q = t.map(|v| p[v as usize]);
                signed_volume6(q[0], q[1], q[2], q[3]).abs() / 6.0
            })
            .sum()
    }

    fn unit_cube() -> Vec<Vec3> {
        // VTK hexahedron order.
        [
            [0., 0., 0.],
            [1., 0., 0.],
            [1., 1., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [1., 1., 1.],
            [0., 1., 1.],
        ]
        .map(Vec3::from)
        .to_vec()
    }

    #[test]
    fn hexahedron_fills_its_volume_for_every_lowest_node() {
        let p = unit_cube();
        for v in 0..8u32 {
            // Renumber so that node v is the lowest.
            let ids: [u32; 8] = std::array::from_fn(|i| (i as u32 + 8 - v) % 8);
            let mut q = vec![Vec3::ZERO; 8];
            for (i, &id) in ids.iter().enumerate() {
                q[id as usize] = p[i];
            }
            let mut out = Vec::new();
            hexahedron(ids, &mut out);
            assert_eq!(out.len(), 6);
            assert!((volume(&q, &out) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn wedge_and_pyramid_fill_their_volume() {
        let p: Vec<Vec3> = [
            [0., 0., 0.],
            [1., 0., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [0., 1., 1.],
        ]
        .map(Vec3::from)
        .to_vec();
        for v in 0..6u32 {
            let ids: [u32; 6] = std::array::from_fn(|i| (i as u32 + 6 - v) % 6);
            let mut q = vec![Vec3::ZERO; 6];
            for (i, &id) in ids.iter().enumerate() {
                q[id as usize] = p[i];
            }
            let mut out = Vec::new();
            wedge(ids, &mut out);
            assert_eq!(out.len(), 3);
            assert!((volume(&q, &out) - 0.5).abs() < 1e-6, "v={v}");
        }
        let p = unit_cube();
        let mut out = Vec::new();
        pyramid([1, 2, 3, 0], 6, &mut out);
        assert!((volume(&p, &out) - 1.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn bad_cells_are_errors() {
        let cells = CellSet {
            connectivity: vec![0, 1, 2],
            offsets: vec![3],
            types: vec![10],
        };
        assert!(to_tets(&cells, 4).is_err());
        let cells = CellSet {
            connectivity: vec![0, 1, 2, 9],
            offsets: vec![4],
            types: vec![10],
        };
        assert!(to_tets(&cells, 4).is_err());
        let cells = CellSet {
            connectivity: vec![0, 1, 2, 3],
            offsets: vec![5],
            types: vec![10],
        };
        assert!(to_tets(&cells, 4).is_err());
    }
}
