//! VTK legacy and VTK XML readers: small files written here for every variant (ASCII/BINARY
//! legacy; ascii, base64, appended raw/base64 and zlib-compressed XML arrays), malformed
//! inputs, and the real `post.vtk` and `dataset.vtu` checked against their sidecars.
use std::io::Write;
use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::Value;
use volux_io::{vtk_legacy, vtk_xml, Dataset, ErrorKind, ReadError};
use volux_testkit::data::shared;

fn sidecar(p: &Path) -> Value {
    let s = std::fs::read_to_string(format!("{}.json", p.display())).unwrap();
    serde_json::from_str(&s).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-6)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn grid(d: Dataset) -> volux_core::Grid {
    match d {
        Dataset::Grid(g) => g,
        other => panic!("expected a grid, got {other:?}"),
    }
}

fn mesh(d: Dataset) -> volux_core::TetMesh {
    match d {
        Dataset::Mesh(m) => m,
        other => panic!("expected a mesh, got {other:?}"),
    }
}

fn legacy(text: &[u8]) -> volux_io::Result<Dataset> {
    let dir = tempfile::tempdir().unwrap();
    vtk_legacy::read(&write(dir.path(), "t.vtk", text), None)
}

fn legacy_err(text: &[u8]) -> ReadError {
    legacy(text).unwrap_err()
}

// ------------------------------------------------------------------ legacy

const SP_ASCII: &str = "# vtk DataFile Version 3.0\ntest\nASCII\nDATASET STRUCTURED_POINTS\n\
DIMENSIONS 3 2 2\nSPACING 0.5 1 2\nORIGIN 1 2 3\nPOINT_DATA 12\n\
SCALARS density short 1\nLOOKUP_TABLE default\n0 1 2 3 4 5\n6 7 8 9 10 -11\n";

#[test]
fn legacy_structured_points_ascii() {
    let g = grid(legacy(SP_ASCII.as_bytes()).unwrap());
    assert_eq!(g.dims(), [3, 2, 2]);
    assert_eq!(g.spacing().to_array(), [0.5, 1.0, 2.0]);
    assert_eq!(g.origin().to_array(), [1.0, 2.0, 3.0]);
    assert_eq!(g.scalar_type(), volux_core::ScalarType::I16);
    assert_eq!(g.range(), [-11.0, 10.0]);
}

fn sp_binary(ty: &str, data: &[u8], n: usize) -> Vec<u8> {
    let mut v = format!(
        "# vtk DataFile Version 3.0\nbin\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS {n} 1 1\n\
         ASPECT_RATIO 1 1 1\nORIGIN 0 0 0\nPOINT_DATA {n}\nSCALARS v {ty}\nLOOKUP_TABLE default\n"
    )
    .into_bytes();
    v.extend_from_slice(data);
    v.push(b'\n');
    v
}

#[test]
fn legacy_structured_points_binary_big_endian() {
    let data: Vec<u8> = [-5i16, 300, 7]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    let g = grid(legacy(&sp_binary("short", &data, 3)).unwrap());
    assert_eq!(g.range(), [-5.0, 300.0]);
    let data: Vec<u8> = [1.5f64, -2.0]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    let g = grid(legacy(&sp_binary("double", &data, 2)).unwrap());
    assert_eq!(g.scalar_type(), volux_core::ScalarType::F32);
    assert_eq!(g.range(), [-2.0, 1.5]);
    assert!(
        g.notes().iter().any(|n| n.contains("Float64")),
        "{:?}",
        g.notes()
    );
    // NaN values are replaced and noted by the grid.
    let data: Vec<u8> = [1.0f32, f32::NAN]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    let g = grid(legacy(&sp_binary("float", &data, 2)).unwrap());
    assert!(
        g.notes().iter().any(|n| n.contains("non-finite")),
        "{:?}",
        g.notes()
    );
}

/// Points of a unit cube (VTK hexahedron order) plus an apex above it and two wedge points.
const POINTS: &str = "POINTS 11 float\n0 0 0 1 0 0 1 1 0 0 1 0\n0 0 1 1 0 1 1 1 1 0 1 1\n\
0.5 0.5 2  2 0 0  2 1 0\n";

fn ug_ascii(data: &str) -> String {
    // hexahedron, pyramid on its top face, wedge beside it, a tet, a triangle.
    format!(
        "# vtk DataFile Version 3.0\nug\nASCII\nDATASET UNSTRUCTURED_GRID\n{POINTS}\
         CELLS 5 31\n8 0 1 2 3 4 5 6 7\n5 4 5 6 7 8\n6 1 9 5 2 10 6\n4 0 1 3 4\n3 0 1 2\n\
         CELL_TYPES 5\n12 14 13 10 5\n{data}"
    )
}

#[test]
fn legacy_unstructured_ascii_splits_cells() {
    let data = "POINT_DATA 11\nSCALARS s float\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7 8 9 10\n\
                VECTORS vel float\n1 0 0 0 3 4 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0\n";
    let m = mesh(legacy(ug_ascii(data).as_bytes()).unwrap());
    assert_eq!(m.tets().len(), 6 + 2 + 3 + 1);
    assert_eq!(m.range(), [0.0, 10.0]);
    let notes = m.notes().join("\n");
    assert!(notes.contains("1 0D/1D/2D cells ignored"), "{notes}");
    assert!(notes.contains("split into tetrahedra"), "{notes}");
    assert_eq!(m.report().degenerate, 0);
    // The array option picks the vectors (magnitude).
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "v.vtk", ug_ascii(data).as_bytes());
    let v = mesh(vtk_legacy::read(&p, Some("vel")).unwrap());
    assert_eq!(v.range(), [1.0, 5.0]);
    let e = vtk_legacy::read(&p, Some("nope")).unwrap_err();
    assert!(
        e.to_string().contains("'s'") && e.to_string().contains("'vel'"),
        "{e}"
    );
}

#[test]
fn legacy_cell_data_is_averaged_to_points() {
    let data = "CELL_DATA 5\nSCALARS c float 1\nLOOKUP_TABLE default\n1 3 5 7 100\n";
    let m = mesh(legacy(ug_ascii(data).as_bytes()).unwrap());
    assert!(
        m.notes().iter().any(|n| n.contains("averaged")),
        "{:?}",
        m.notes()
    );
    // Node 8 (the apex) only belongs to the pyramid, node 9 only to the wedge.
    assert_eq!(m.scalars()[8], 3.0);
    assert_eq!(m.scalars()[9], 5.0);
    // Node 0 is in the hexahedron and the tet.
    assert_eq!(m.scalars()[0], 4.0);
}

#[test]
fn legacy_vtk51_offsets_layout_and_binary_field_data() {
    let mut v = b"# vtk DataFile Version 5.1\nnew\nBINARY\nDATASET UNSTRUCTURED_GRID\n\
FIELD FieldData 1\nTIME 1 1 double\n"
        .to_vec();
    v.extend(1.5f64.to_be_bytes());
    v.extend(b"\nPOINTS 4 float\n");
    for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]] {
        for c in p {
            v.extend(c.to_be_bytes());
        }
    }
    v.extend(b"\nCELLS 2 4\nOFFSETS vtktypeint64\n");
    for o in [0i64, 4] {
        v.extend(o.to_be_bytes());
    }
    v.extend(b"\nCONNECTIVITY vtktypeint64\n");
    for c in [0i64, 1, 2, 3] {
        v.extend(c.to_be_bytes());
    }
    v.extend(b"\nCELL_TYPES 1\n");
    v.extend(10i32.to_be_bytes());
    v.extend(b"\nPOINT_DATA 4\nFIELD FieldData 1\nPressure 1 4 float\n");
    for s in [0.5f32, 1.0, 1.5, 2.0] {
        v.extend(s.to_be_bytes());
    }
    v.extend(b"\n");
    let m = mesh(legacy(&v).unwrap());
    assert_eq!(m.tets().len(), 1);
    assert_eq!(m.range(), [0.5, 2.0]);
}

#[test]
fn legacy_structured_grid() {
    let text = "# vtk DataFile Version 3.0\nsg\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 2 2 2\n\
POINTS 8 double\n0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1\n\
POINT_DATA 8\nSCALARS t int\n1 2 3 4 5 6 7 8\n";
    let m = mesh(legacy(text.as_bytes()).unwrap());
    assert_eq!(m.tets().len(), 5);
    assert_eq!(m.range(), [1.0, 8.0]);
}

#[test]
fn legacy_malformed_inputs_are_errors() {
    // Truncated binary data.
    let e = legacy_err(&sp_binary("float", &[0, 0], 1));
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
    // Header/data size mismatch: POINT_DATA differs from the grid.
    let e = legacy_err(
        SP_ASCII
            .replace("DIMENSIONS 3 2 2", "DIMENSIONS 3 2 3")
            .as_bytes(),
    );
    assert!(matches!(e.kind, ErrorKind::Header(_)), "{e}");
    // Dims whose product overflows; zero and negative dims.
    for d in ["4000000000 4000000000 4000000000", "0 2 2", "-3 2 2"] {
        let t = SP_ASCII.replace("3 2 2", d);
        let e = legacy_err(t.as_bytes());
        assert!(matches!(e.kind, ErrorKind::Data(_)), "{d}: {e}");
    }
    // Unknown dtype.
    let e = legacy_err(SP_ASCII.replace("short", "quaternion").as_bytes());
    assert!(e.to_string().contains("quaternion"), "{e}");
    // A non-numeric value names its line.
    let e = legacy_err(SP_ASCII.replace(" 7 ", " seven ").as_bytes());
    assert!(e.to_string().contains("line 12"), "{e}");
    // Out-of-range node index.
    let bad = ug_ascii("").replace("4 0 1 3 4\n", "4 0 1 3 44\n");
    let e = legacy_err(bad.as_bytes());
    assert!(e.to_string().contains("node 44"), "{e}");
    // A cell list that lies about its node count.
    let bad = ug_ascii("").replace("CELLS 5 31", "CELLS 5 3000000000");
    assert!(legacy(bad.as_bytes()).is_err());
    // Empty mesh: only 2D cells.
    let bad = ug_ascii("").replace("12 14 13 10 5", "5 5 5 5 5");
    let e = legacy_err(bad.as_bytes());
    assert!(e.to_string().contains("no volume cells"), "{e}");
    // Garbage bytes and a file that is not VTK.
    assert!(legacy(b"# vtk DataFile Version 3.0\n\xff\xfe\x00garbage").is_err());
    assert!(legacy(b"\x00\x01\x02\x03garbage").is_err());
    // Unsupported dataset kinds.
    let e = legacy_err(b"# vtk DataFile Version 3.0\np\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
}

#[test]
fn legacy_real_post_vtk() {
    let Some(p) = shared("vtk_post_tets/post.vtk") else {
        return;
    };
    let side = sidecar(&p);
    let m = mesh(vtk_legacy::read(&p, None).unwrap_or_else(|e| panic!("{e}")));
    assert_eq!(
        m.positions().len() as u64,
        side["vertices"].as_u64().unwrap()
    );
    assert_eq!(m.tets().len() as u64, side["tets"].as_u64().unwrap());
    let Some(off) = shared("vtk_post_tets/post_tets_pressure.off") else {
        return;
    };
    let r: Vec<f64> = sidecar(&off)["scalar_range"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        close(m.range()[0], r[0]) && close(m.range()[1], r[1]),
        "{:?}",
        m.range()
    );
    let o = volux_io::off::read(&off).unwrap();
    for (a, b) in m.scalars().iter().zip(o.scalars()) {
        assert!(close(*a as f64, *b as f64));
    }
}

// ------------------------------------------------------------------ XML

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Ascii,
    Binary,
    /// Binary with the size header encoded as its own base64 stream.
    BinarySplit,
    Appended,
    AppendedB64,
}

/// Writes VTK XML arrays in one encoding.
struct Xml {
    mode: Mode,
    zlib: bool,
    word64: bool,
    big: bool,
    appended: Vec<u8>,
}

fn b64(b: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(b)
}

impl Xml {
    fn new(mode: Mode, zlib: bool, word64: bool, big: bool) -> Self {
        Self {
            mode,
            zlib,
            word64,
            big,
            appended: Vec::new(),
        }
    }

    fn word(&self, v: usize, out: &mut Vec<u8>) {
        match (self.word64, self.big) {
            (true, true) => out.extend((v as u64).to_be_bytes()),
            (true, false) => out.extend((v as u64).to_le_bytes()),
            (false, true) => out.extend((v as u32).to_be_bytes()),
            (false, false) => out.extend((v as u32).to_le_bytes()),
        }
    }

    fn encode(&self, ty: &str, values: &[f64]) -> Vec<u8> {
        let mut out = Vec::new();
        for &v in values {
            let mut b: Vec<u8> = match ty {
                "Float32" => (v as f32).to_le_bytes().to_vec(),
                "Float64" => v.to_le_bytes().to_vec(),
                "Int32" => (v as i32).to_le_bytes().to_vec(),
                "Int64" => (v as i64).to_le_bytes().to_vec(),
                "UInt8" => vec![v as u8],
                "Int16" => (v as i16).to_le_bytes().to_vec(),
                _ => panic!("{ty}"),
            };
            if self.big {
                b.reverse();
            }
            out.extend(b);
        }
        out
    }

    /// Size header and body (blocks of 16 bytes when compressed).
    fn header_body(&self, data: &[u8]) -> (Vec<u8>, Vec<u8>) {
        let mut h = Vec::new();
        if !self.zlib {
            self.word(data.len(), &mut h);
            return (h, data.to_vec());
        }
        let blocks: Vec<&[u8]> = data.chunks(16).collect();
        let comp: Vec<Vec<u8>> = blocks
            .iter()
            .map(|b| {
                let mut e =
                    flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
                e.write_all(b).unwrap();
                e.finish().unwrap()
            })
            .collect();
        self.word(blocks.len(), &mut h);
        self.word(16, &mut h);
        self.word(data.len() % 16, &mut h);
        for c in &comp {
            self.word(c.len(), &mut h);
        }
        (h, comp.concat())
    }

    fn array(&mut self, name: &str, ty: &str, ncomp: usize, values: &[f64]) -> String {
        let head =
            format!("<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{ncomp}\"");
        let (h, body) = self.header_body(&self.encode(ty, values));
        match self.mode {
            Mode::Ascii => {
                let t: Vec<String> = values.iter().map(|v| v.to_string()).collect();
                format!("{head} format=\"ascii\">\n{}\n</DataArray>\n", t.join(" "))
            }
            Mode::Binary | Mode::BinarySplit => {
                let text = if self.mode == Mode::Binary && !self.zlib {
                    b64(&[h, body].concat())
                } else {
                    format!("{}{}", b64(&h), b64(&body))
                };
                format!("{head} format=\"binary\">\n  {text}\n</DataArray>\n")
            }
            Mode::Appended | Mode::AppendedB64 => {
                let off = self.appended.len();
                if self.mode == Mode::Appended {
                    self.appended.extend(h);
                    self.appended.extend(body);
                } else {
                    self.appended.extend(b64(&h).bytes());
                    self.appended.extend(b64(&body).bytes());
                }
                format!("{head} format=\"appended\" offset=\"{off}\"/>\n")
            }
        }
    }

    fn file(&self, kind: &str, body: &str) -> Vec<u8> {
        let mut v = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"{}\" header_type=\"{}\"{}>\n{body}",
            if self.big { "BigEndian" } else { "LittleEndian" },
            if self.word64 { "UInt64" } else { "UInt32" },
            if self.zlib { " compressor=\"vtkZLibDataCompressor\"" } else { "" }
        )
        .into_bytes();
        if !self.appended.is_empty() {
            let enc = if self.mode == Mode::Appended {
                "raw"
            } else {
                "base64"
            };
            v.extend(format!("<AppendedData encoding=\"{enc}\">\n   _").bytes());
            v.extend(&self.appended);
            v.extend(b"\n</AppendedData>\n");
        }
        v.extend(b"</VTKFile>\n");
        v
    }
}

fn vti(x: &mut Xml) -> Vec<u8> {
    let values: Vec<f64> = (0..24).map(|v| v as f64 * 0.5 - 3.0).collect();
    let a = x.array("temp", "Float32", 1, &values);
    let other = x.array("label", "UInt8", 1, &[7.0; 24]);
    let body = format!(
        "<ImageData WholeExtent=\"1 4 0 2 0 1\" Origin=\"10 20 30\" Spacing=\"0.5 1 2\">\n\
         <Piece Extent=\"1 4 0 2 0 1\">\n<PointData Scalars=\"temp\">\n{other}{a}</PointData>\n\
         <CellData>\n</CellData>\n</Piece>\n</ImageData>\n"
    );
    x.file("ImageData", &body)
}

fn all_modes() -> Vec<Xml> {
    let mut v = Vec::new();
    for mode in [
        Mode::Ascii,
        Mode::Binary,
        Mode::BinarySplit,
        Mode::Appended,
        Mode::AppendedB64,
    ] {
        for zlib in [false, true] {
            if mode == Mode::Ascii && zlib {
                continue;
            }
            v.push(Xml::new(mode, zlib, false, false));
        }
    }
    v.push(Xml::new(Mode::Binary, true, true, false));
    v.push(Xml::new(Mode::Appended, false, true, true));
    v.push(Xml::new(Mode::Appended, true, false, true));
    v
}

#[test]
fn vti_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    for mut x in all_modes() {
        let what = format!(
            "{:?} zlib={} u64={} big={}",
            x.mode, x.zlib, x.word64, x.big
        );
        let p = write(dir.path(), "t.vti", &vti(&mut x));
        let g = grid(vtk_xml::read(&p, None).unwrap_or_else(|e| panic!("{what}: {e}")));
        assert_eq!(g.dims(), [4, 3, 2], "{what}");
        assert_eq!(g.spacing().to_array(), [0.5, 1.0, 2.0], "{what}");
        assert_eq!(g.origin().to_array(), [10.5, 20.0, 30.0], "{what}");
        assert_eq!(g.range(), [-3.0, 8.5], "{what}");
        let l = grid(vtk_xml::read(&p, Some("label")).unwrap());
        assert_eq!(l.scalar_type(), volux_core::ScalarType::U8);
        assert_eq!(l.range(), [7.0, 7.0]);
    }
}

#[test]
fn vti_direction_is_applied() {
    let dir = tempfile::tempdir().unwrap();
    let mut x = Xml::new(Mode::Ascii, false, false, false);
    // Row by row: i along +y, j along -x, k along +z (90 degrees about z).
    let text = String::from_utf8(vti(&mut x))
        .unwrap()
        .replace("Spacing=", "Direction=\"0 -1 0 1 0 0 0 0 1\" Spacing=");
    let p = write(dir.path(), "d.vti", text.as_bytes());
    let g = grid(vtk_xml::read(&p, None).unwrap());
    assert_eq!(g.orientation_code(), "PRS");
    // Extent starts at i = 1: the first sample is 0.5 along +y from Origin.
    assert_eq!(g.origin().to_array(), [10.0, 20.5, 30.0]);
    assert!(
        !g.notes().iter().any(|n| n.contains("Direction")),
        "{:?}",
        g.notes()
    );
    let sheared = text.replace("0 -1 0 1 0 0", "0.3 -1 0 1 0 0");
    let p = write(dir.path(), "s.vti", sheared.as_bytes());
    let g = grid(vtk_xml::read(&p, None).unwrap());
    assert!(g.is_axis_aligned());
    assert!(g.notes().iter().any(|n| n.contains("Direction")));
}

fn vtu(x: &mut Xml, point_data: bool) -> Vec<u8> {
    let pts: Vec<f64> = [
        [0., 0., 0.],
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 0., 1.],
        [1., 1., 1.],
        [0., 1., 1.],
        [0.5, 0.5, 2.0],
    ]
    .concat();
    // A voxel (VTK voxel order), a pyramid on top, a triangle, a quadratic tet (corners only).
    let conn = [
        0., 1., 3., 2., 4., 5., 7., 6., 4., 5., 6., 7., 8., 0., 1., 2., 0., 1., 3., 4., 0., 0., 0.,
        0., 0., 0.,
    ];
    let off = [8., 13., 16., 26.];
    let types = [11., 14., 5., 24.];
    let points = x.array("Points", "Float64", 3, &pts);
    let c = x.array("connectivity", "Int64", 1, &conn);
    let o = x.array("offsets", "Int32", 1, &off);
    let t = x.array("types", "UInt8", 1, &types);
    let data = if point_data {
        let s: Vec<f64> = (0..9).map(|v| v as f64).collect();
        format!(
            "<PointData>\n{}</PointData>\n",
            x.array("s", "Int16", 1, &s)
        )
    } else {
        format!(
            "<CellData>\n{}</CellData>\n",
            x.array("stress", "Float32", 1, &[2.0, 4.0, 100.0, 6.0])
        )
    };
    let body = format!(
        "<UnstructuredGrid>\n<Piece NumberOfPoints=\"9\" NumberOfCells=\"4\">\n{data}\
         <Points>\n{points}</Points>\n<Cells>\n{c}{o}{t}</Cells>\n</Piece>\n</UnstructuredGrid>\n"
    );
    x.file("UnstructuredGrid", &body)
}

#[test]
fn vtu_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    for mut x in all_modes() {
        let what = format!(
            "{:?} zlib={} u64={} big={}",
            x.mode, x.zlib, x.word64, x.big
        );
        let p = write(dir.path(), "t.vtu", &vtu(&mut x, true));
        let m = mesh(vtk_xml::read(&p, None).unwrap_or_else(|e| panic!("{what}: {e}")));
        assert_eq!(m.positions().len(), 9, "{what}");
        assert_eq!(m.tets().len(), 6 + 2 + 1, "{what}");
        assert_eq!(m.range(), [0.0, 8.0], "{what}");
        assert_eq!(m.report().degenerate, 0, "{what}");
        let notes = m.notes().join("\n");
        assert!(notes.contains("1 quadratic"), "{what}: {notes}");
        assert!(notes.contains("1 0D/1D/2D"), "{what}: {notes}");
    }
}

#[test]
fn vtu_cell_data_is_averaged() {
    let dir = tempfile::tempdir().unwrap();
    let mut x = Xml::new(Mode::Binary, true, false, false);
    let p = write(dir.path(), "c.vtu", &vtu(&mut x, false));
    let m = mesh(vtk_xml::read(&p, None).unwrap());
    assert_eq!(m.scalars()[8], 4.0, "apex: pyramid only");
    assert_eq!(m.scalars()[7], 3.0, "voxel and pyramid");
    assert_eq!(m.scalars()[1], 4.0, "voxel and quadratic tet");
    assert!(m.notes().iter().any(|n| n.contains("averaged")));
}

fn xml_err(bytes: &[u8], name: &str) -> ReadError {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), name, bytes);
    vtk_xml::read(&p, None).unwrap_err()
}

#[test]
fn xml_malformed_inputs_are_errors() {
    let ok = vti(&mut Xml::new(Mode::Appended, false, false, false));
    let s = String::from_utf8(vti(&mut Xml::new(Mode::AppendedB64, true, false, false))).unwrap();
    // Truncated appended data.
    let e = xml_err(&ok[..ok.len() - 40], "t.vti");
    assert!(e.to_string().contains("truncated"), "{e}");
    // Extent/data size mismatch.
    let e = xml_err(s.replace("1 4 0 2 0 1", "1 5 0 2 0 1").as_bytes(), "t.vti");
    assert!(e.to_string().contains("values"), "{e}");
    // Extents whose product overflows, zero or negative extents.
    for ext in [
        "0 4000000000 0 4000000000 0 4000000000",
        "-1e300 1e300 0 1 0 1",
        "3 1 0 2 0 1",
    ] {
        let e = xml_err(s.replacen("1 4 0 2 0 1", ext, 1).as_bytes(), "t.vti");
        assert!(matches!(e.kind, ErrorKind::Data(_)), "{ext}: {e}");
    }
    // Unknown type.
    let e = xml_err(s.replace("Float32", "Float128").as_bytes(), "t.vti");
    assert!(e.to_string().contains("Float128"), "{e}");
    // A lying compressed header (huge block count / sizes).
    let mut x = Xml::new(Mode::Binary, true, false, false);
    let z = String::from_utf8_lossy(&vti(&mut x)).into_owned();
    let lie = b64(&[255u8, 255, 255, 255, 0, 0, 1, 0, 0, 0, 0, 0]);
    let z2 = z.replacen(
        "format=\"binary\">\n  ",
        &format!("format=\"binary\">\n  {lie}"),
        1,
    );
    assert!(xml_err(z2.as_bytes(), "t.vti")
        .to_string()
        .contains("array"));
    // NaN values are replaced and noted.
    let mut x = Xml::new(Mode::Ascii, false, false, false);
    let a = String::from_utf8_lossy(&vti(&mut x)).replacen("-3 ", "nan ", 1);
    let dir = tempfile::tempdir().unwrap();
    let g = grid(vtk_xml::read(&write(dir.path(), "n.vti", a.as_bytes()), None).unwrap());
    assert!(
        g.notes().iter().any(|n| n.contains("non-finite")),
        "{:?}",
        g.notes()
    );
    // Out-of-range node index and empty meshes.
    let mut x = Xml::new(Mode::Ascii, false, false, false);
    let u = String::from_utf8_lossy(&vtu(&mut x, true)).into_owned();
    let e = xml_err(
        u.replacen("0 1 3 2 4 5 7 6", "0 1 3 2 4 5 7 60", 1)
            .as_bytes(),
        "t.vtu",
    );
    assert!(e.to_string().contains("node 60"), "{e}");
    let e = xml_err(u.replacen("11 14 5 24", "5 5 5 5", 1).as_bytes(), "t.vtu");
    assert!(e.to_string().contains("no volume cells"), "{e}");
    let e = xml_err(
        u.replace("NumberOfPoints=\"9\"", "NumberOfPoints=\"10\"")
            .as_bytes(),
        "t.vtu",
    );
    assert!(e.to_string().contains("Points"), "{e}");
    // Garbage bytes.
    assert!(vtk_xml::read(&write(dir.path(), "g.vtu", b"<VTKFile \xff\x00<<>>"), None).is_err());
    assert!(vtk_xml::read(&write(dir.path(), "g2.vtu", b"\x00\x01garbage"), None).is_err());
}

#[test]
fn vtu_real_kiefer_quadratic_tets() {
    let Some(p) = shared("fea_kiefer_quadratic_tets/dataset.vtu") else {
        return;
    };
    let side = sidecar(&p);
    let m = mesh(vtk_xml::read(&p, None).unwrap_or_else(|e| panic!("{e}")));
    eprintln!("kiefer: notes {:?}, report {:?}", m.notes(), m.report());
    // Mid-edge nodes are dropped: used corner nodes + removed nodes = all nodes.
    let removed: u64 = m
        .notes()
        .iter()
        .find_map(|n| n.strip_suffix(" vertices used by no tet removed"))
        .and_then(|n| n.parse().ok())
        .expect("a note on removed vertices");
    let nodes = side["vertices"].as_u64().unwrap();
    assert_eq!(m.positions().len() as u64 + removed, nodes);
    assert_eq!(m.report().unused_vertices, 0);
    assert_eq!(m.tets().len() as u64, side["tets"].as_u64().unwrap());
    // Averages of the per-cell stress stay within the cell range given in the file.
    assert!(
        m.range()[0] >= 0.014034 && m.range()[1] <= 23.269,
        "{:?}",
        m.range()
    );
}

/// Deterministic byte mutations (flips, truncations) of valid files never panic.
#[test]
fn mutated_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut seeds: Vec<(&str, Vec<u8>)> = vec![
        ("m.vtk", SP_ASCII.as_bytes().to_vec()),
        (
            "m.vtk",
            ug_ascii("CELL_DATA 5\nSCALARS c float\n1 2 3 4 5\n").into_bytes(),
        ),
        ("m.vtk", sp_binary("short", &[0, 1, 0, 2, 0, 3], 3)),
    ];
    for mut x in all_modes() {
        seeds.push(("m.vtu", vtu(&mut x, true)));
        let mut x = Xml::new(x.mode, x.zlib, x.word64, x.big);
        seeds.push(("m.vti", vti(&mut x)));
    }
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for (name, seed) in &seeds {
        for _ in 0..60 {
            let mut b = seed.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % b.len() as u64) as usize;
                b[i] = match next() % 3 {
                    0 => next() as u8,
                    1 => b"0123456789 -.e\n"[(next() % 15) as usize],
                    _ => b[i] ^ 0x80,
                };
            }
            if next() % 4 == 0 {
                b.truncate((next() % b.len() as u64) as usize);
            }
            let p = write(dir.path(), name, &b);
            let _ = if name.ends_with(".vtk") {
                vtk_legacy::read(&p, None)
            } else {
                vtk_xml::read(&p, None)
            };
        }
    }
}

/// A zlib block that inflates to far more than the grid holds (a bomb within deflate's
/// 1032:1 ratio) is refused from its size header, before anything is inflated.
#[test]
fn a_compressed_array_larger_than_its_grid_is_refused_before_inflating() {
    let dir = tempfile::tempdir().unwrap();
    let declared: u64 = 64 << 20; // 64 MiB of zeros for a 5 x 4 x 6 = 120-point grid
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    let zeros = vec![0u8; 1 << 20];
    for _ in 0..(declared >> 20) {
        z.write_all(&zeros).unwrap();
    }
    let block = z.finish().unwrap();
    let mut appended = Vec::new();
    for w in [1u32, declared as u32, declared as u32, block.len() as u32] {
        appended.extend(w.to_le_bytes());
    }
    appended.extend(&block);
    let mut file = br#"<?xml version="1.0"?>
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt32" compressor="vtkZLibDataCompressor">
<ImageData WholeExtent="0 4 0 3 0 5" Origin="0 0 0" Spacing="1 1 1">
<Piece Extent="0 4 0 3 0 5"><PointData Scalars="v">
<DataArray type="Float32" Name="v" format="appended" offset="0"/>
</PointData></Piece></ImageData>
<AppendedData encoding="raw">_"#
        .to_vec();
    file.extend(&appended);
    file.extend(b"</AppendedData></VTKFile>\n");
    let p = write(dir.path(), "bomb.vti", &file);
    let t = std::time::Instant::now();
    let e = vtk_xml::read(&p, None).unwrap_err().to_string();
    assert!(e.contains(&format!("declares {declared} bytes")), "{e}");
    assert!(e.contains("asks for 480 bytes"), "{e}");
    assert!(
        t.elapsed().as_secs_f64() < 1.0,
        "refused in {:?}",
        t.elapsed()
    );
}
