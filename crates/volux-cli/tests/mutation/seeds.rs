//! Small valid files of every format Volux reads, written by hand (no shared data, except
//! the tiny DICOM file of `pydicom_emri_small` when it is present, and compressed DICOM
//! files from volux-io's committed test fixtures): the seeds of the mutation
//! harness. Grids are 6 x 5 x 4 with a smooth blob (one NRRD is 256^3); meshes are a unit cube split into five
//! tetrahedra.
use volux_testkit::mutate::{compress, gzip, Codec, InputFile, Layout};

/// A valid input: the file Volux is given first, then its companions.
#[derive(Clone, Debug)]
pub struct Seed {
    /// A short name of the format and variant (for reports and per-format counts).
    pub format: &'static str,
    /// The files; `files[0]` is the one Volux is given.
    pub files: Vec<InputFile>,
    /// A tetrahedral mesh (else a grid).
    pub mesh: bool,
}

impl Seed {
    fn grid(format: &'static str, files: Vec<InputFile>) -> Self {
        Self {
            format,
            files,
            mesh: false,
        }
    }

    fn mesh(format: &'static str, files: Vec<InputFile>) -> Self {
        Self {
            format,
            files,
            mesh: true,
        }
    }

    /// The name of the file Volux is given.
    pub fn target(&self) -> &str {
        &self.files[0].name
    }
}

/// Grid size.
const DIMS: [usize; 3] = [6, 5, 4];

/// The grid's values: a blob, 0..=200, x fastest.
fn values() -> Vec<f32> {
    let mut v = Vec::new();
    for z in 0..DIMS[2] {
        for y in 0..DIMS[1] {
            for x in 0..DIMS[0] {
                let d =
                    (x as f32 - 2.5).powi(2) + (y as f32 - 2.0).powi(2) + (z as f32 - 1.5).powi(2);
                v.push((200.0 - 20.0 * d).max(0.0).round());
            }
        }
    }
    v
}

fn u8s() -> Vec<u8> {
    values().iter().map(|&v| v as u8).collect()
}

fn i16s(big: bool) -> Vec<u8> {
    let to = |v: i16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    values().iter().flat_map(|&v| to(v as i16)).collect()
}

fn f32s(big: bool) -> Vec<u8> {
    let to = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    values().iter().flat_map(|&v| to(v)).collect()
}

fn text_values() -> String {
    let t: Vec<String> = values().iter().map(|v| v.to_string()).collect();
    t.join(" ")
}

/// The cube's corners (index = x + 2y + 4z) and a scalar per corner.
fn cube() -> Vec<([f32; 3], f32)> {
    (0..8)
        .map(|i| {
            let p = [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
            (p, 1.0 + i as f32)
        })
        .collect()
}

/// Five tetrahedra filling the cube.
const TETS: [[u32; 4]; 5] = [
    [0, 1, 2, 4],
    [3, 1, 7, 2],
    [5, 1, 4, 7],
    [6, 2, 7, 4],
    [1, 2, 4, 7],
];

/// Every seed (DICOM only when the shared file is present).
pub fn all() -> Vec<Seed> {
    let mut v = raw_seeds();
    v.extend(nrrd_seeds());
    v.extend(metaimage_seeds());
    v.extend(nifti_seeds());
    v.extend(several_volume_seeds());
    v.extend(vtk_legacy_seeds());
    v.extend(vtk_xml_seeds());
    v.extend([
        plot3d(),
        slc(false),
        slc(true),
        off(false),
        off(true),
        vtet(),
    ]);
    v.extend(dicom());
    v.extend(dicom_compressed());
    v.extend(dicom_values());
    v.extend(tiff_seeds());
    v
}

// ------------------------------------------------------------------ raw + JSON sidecar

fn sidecar(name: &str, dtype: &str, big: bool, extra: &str) -> InputFile {
    let json = format!(
        "{{\"dims_xyz\": [6, 5, 4], \"dtype\": \"{dtype}\", \"endianness\": \"{}\", \
         \"spacing\": [1, 0.5, 2], \"origin\": [0, 0, 0]{extra}}}",
        if big { "big" } else { "little" }
    );
    InputFile::new(&format!("{name}.json"), json.into_bytes(), Layout::Json)
}

fn raw_seeds() -> Vec<Seed> {
    let u16s: Vec<u8> = values()
        .iter()
        .flat_map(|&v| (v as u16).to_le_bytes())
        .collect();
    vec![
        Seed::grid(
            "raw-uint8",
            vec![
                InputFile::new("t.raw", u8s(), Layout::Binary(0)),
                sidecar("t.raw", "uint8", false, ""),
            ],
        ),
        Seed::grid(
            "raw-int16-be",
            vec![
                InputFile::new("t.raw", i16s(true), Layout::Binary(0)),
                sidecar("t.raw", "int16", true, ""),
            ],
        ),
        Seed::grid(
            "raw-float32",
            vec![
                InputFile::new("t.raw", f32s(false), Layout::Binary(0)),
                sidecar("t.raw", "float32", false, ""),
            ],
        ),
        Seed::grid(
            "raw.gz-uint16",
            vec![
                InputFile::new("t.raw.gz", gzip(&u16s), Layout::Binary(0)).gzipped(),
                sidecar("t.raw.gz", "uint16", false, ", \"compression\": \"gzip\""),
            ],
        ),
    ]
}

// ------------------------------------------------------------------ NRRD

fn nrrd_head(encoding: &str, extra: &str) -> String {
    format!(
        "NRRD0004\n# seed\ntype: short\ndimension: 3\nsizes: 6 5 4\nspacings: 1 0.5 2\n\
         endian: little\nencoding: {encoding}\n{extra}"
    )
}

fn with_header(head: &str, data: &[u8]) -> Vec<u8> {
    [head.as_bytes(), data].concat()
}

fn nrrd_seeds() -> Vec<Seed> {
    let raw = nrrd_head("raw", "\n");
    let gz = nrrd_head("gzip", "\n");
    let ascii = nrrd_head("ascii", "\n") + &text_values() + "\n";
    let nhdr = nrrd_head("raw", "data file: t.data\n");
    vec![
        big_nrrd(),
        Seed::grid(
            "nrrd-raw",
            vec![InputFile::new(
                "t.nrrd",
                with_header(&raw, &i16s(false)),
                Layout::Text(raw.len()),
            )],
        ),
        Seed::grid(
            "nrrd-gzip",
            vec![InputFile::new(
                "t.nrrd",
                with_header(&gz, &gzip(&i16s(false))),
                Layout::Text(gz.len()),
            )
            .with_data_codec(Codec::Gzip)],
        ),
        Seed::grid(
            "nrrd-ascii",
            vec![InputFile::new(
                "t.nrrd",
                ascii.clone().into_bytes(),
                Layout::Text(ascii.len()),
            )],
        ),
        Seed::grid(
            "nhdr-detached",
            vec![
                InputFile::new(
                    "t.nhdr",
                    nhdr.clone().into_bytes(),
                    Layout::Text(nhdr.len()),
                ),
                InputFile::new("t.data", i16s(false), Layout::Binary(0)),
            ],
        ),
    ]
}

/// Edge of the big seed.
const BIG: usize = 256;

/// A 256^3 8-bit NRRD (16 MiB, gzip: a few kilobytes on disk) holding a cube: big enough
/// that tetrahedra, gradients and bombs built from it meet the memory limit.
fn big_nrrd() -> Seed {
    let head = format!(
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: {BIG} {BIG} {BIG}\nencoding: gzip\n\n"
    );
    let mut data = vec![0u8; BIG * BIG * BIG];
    for z in BIG / 4..3 * BIG / 4 {
        for y in BIG / 4..3 * BIG / 4 {
            let row = (z * BIG + y) * BIG;
            data[row + BIG / 4..row + 3 * BIG / 4].fill(200);
        }
    }
    Seed::grid(
        "nrrd-gzip-big",
        vec![InputFile::new(
            "t.nrrd",
            with_header(&head, &gzip(&data)),
            Layout::Text(head.len()),
        )
        .with_data_codec(Codec::Gzip)],
    )
}

// ------------------------------------------------------------------ MetaImage

fn mha_head(extra: &str, data_file: &str) -> String {
    format!(
        "ObjectType = Image\nNDims = 3\nDimSize = 6 5 4\nElementType = MET_SHORT\n\
         ElementSpacing = 1 0.5 2\nOffset = 0 0 0\nBinaryDataByteOrderMSB = False\n{extra}\
         ElementDataFile = {data_file}\n"
    )
}

fn metaimage_seeds() -> Vec<Seed> {
    let local = mha_head("", "LOCAL");
    let z = compress(Codec::Zlib, &i16s(false));
    let zhead = mha_head(
        &format!("CompressedData = True\nCompressedDataSize = {}\n", z.len()),
        "LOCAL",
    );
    let mhd = mha_head("", "t.img");
    vec![
        Seed::grid(
            "mha",
            vec![InputFile::new(
                "t.mha",
                with_header(&local, &i16s(false)),
                Layout::Text(local.len()),
            )],
        ),
        Seed::grid(
            "mha-zlib",
            vec![
                InputFile::new("t.mha", with_header(&zhead, &z), Layout::Text(zhead.len()))
                    .with_data_codec(Codec::Zlib),
            ],
        ),
        Seed::grid(
            "mhd",
            vec![
                InputFile::new("t.mhd", mhd.clone().into_bytes(), Layout::Text(mhd.len())),
                InputFile::new("t.img", i16s(false), Layout::Binary(0)),
            ],
        ),
    ]
}

// ------------------------------------------------------------------ NIfTI-1 and NIfTI-2

/// A little-endian NIfTI-1 header (348 bytes) and the 4-byte extension flag, int16 data.
fn nifti_header() -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let mut put = |at: usize, b: &[u8]| h[at..at + b.len()].copy_from_slice(b);
    put(0, &348i32.to_le_bytes());
    let dim = [3i16, 6, 5, 4, 1, 1, 1, 1];
    for (i, d) in dim.iter().enumerate() {
        put(40 + 2 * i, &d.to_le_bytes());
    }
    put(70, &4i16.to_le_bytes()); // datatype: int16
    put(72, &16i16.to_le_bytes()); // bitpix
    let pixdim = [1f32, 1.0, 0.5, 2.0, 0.0, 0.0, 0.0, 0.0];
    for (i, p) in pixdim.iter().enumerate() {
        put(76 + 4 * i, &p.to_le_bytes());
    }
    put(108, &352f32.to_le_bytes()); // vox_offset
    put(344, b"n+1\0");
    h
}

/// A big-endian NIfTI-2 header (540 bytes, nibabel's layout) and the extension flag: the
/// same 6 x 5 x 4 int16 grid with an sform.
fn nifti2_header() -> Vec<u8> {
    let mut h = vec![0u8; 544];
    let mut put = |at: usize, b: &[u8]| {
        let mut b = b.to_vec();
        b.reverse();
        h[at..at + b.len()].copy_from_slice(&b);
    };
    put(0, &540i32.to_le_bytes());
    put(12, &4i16.to_le_bytes()); // datatype: int16
    put(14, &16i16.to_le_bytes()); // bitpix
    let dim = [3i64, 6, 5, 4, 1, 1, 1, 1];
    for (i, d) in dim.iter().enumerate() {
        put(16 + 8 * i, &d.to_le_bytes());
    }
    let pixdim = [1f64, 1.0, 0.5, 2.0, 0.0, 0.0, 0.0, 0.0];
    for (i, p) in pixdim.iter().enumerate() {
        put(104 + 8 * i, &p.to_le_bytes());
    }
    put(168, &544i64.to_le_bytes()); // vox_offset
    put(348, &1i32.to_le_bytes()); // sform_code
    let srow = [
        [1f64, 0.0, 0.0, -3.0],
        [0.0, 0.5, 0.0, 2.0],
        [0.0, 0.0, 2.0, 1.0],
    ];
    for (r, row) in srow.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(400 + 32 * r + 8 * c, &v.to_le_bytes());
        }
    }
    h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
    h
}

fn nifti_seeds() -> Vec<Seed> {
    let nii = [nifti_header(), i16s(false)].concat();
    let nii2 = [nifti2_header(), i16s(true)].concat();
    vec![
        Seed::grid(
            "nii2",
            vec![InputFile::new("t2.nii", nii2, Layout::Binary(544))],
        ),
        Seed::grid(
            "nii",
            vec![InputFile::new("t.nii", nii.clone(), Layout::Binary(352))],
        ),
        Seed::grid(
            "nii.gz",
            vec![InputFile::new("t.nii.gz", gzip(&nii), Layout::Binary(352)).gzipped()],
        ),
    ]
}

// ------------------------------------------------------- several volumes, Analyze, MGH

/// The grid's values twice, the second time plus 1000 (two volumes of a series), int16.
fn two_volumes(big: bool) -> Vec<u8> {
    let second: Vec<u8> = values()
        .iter()
        .flat_map(|&v| {
            let v = v as i16 + 1000;
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        })
        .collect();
    [i16s(big), second].concat()
}

/// A 4-D NIfTI-1 time series (2 volumes, TR 2 s), an Analyze 7.5 pair (big-endian, SPM
/// originator), an MGZ with two frames, a 4-D NRRD with a time axis and an RGB MetaImage.
fn several_volume_seeds() -> Vec<Seed> {
    let mut fmri = nifti_header();
    fmri[40..42].copy_from_slice(&4i16.to_le_bytes());
    fmri[48..50].copy_from_slice(&2i16.to_le_bytes()); // dim[4]
    fmri[92..96].copy_from_slice(&2f32.to_le_bytes()); // pixdim[4]
    fmri[123] = 2 | 8; // mm, s
    let fmri = [fmri, two_volumes(false)].concat();
    let mut analyze = vec![0u8; 348];
    let mut put = |at: usize, b: &[u8]| {
        let mut b = b.to_vec();
        b.reverse();
        analyze[at..at + b.len()].copy_from_slice(&b);
    };
    put(0, &348i32.to_le_bytes());
    for (i, d) in [3i16, 6, 5, 4, 1, 1, 1, 1].iter().enumerate() {
        put(40 + 2 * i, &d.to_le_bytes());
    }
    put(70, &4i16.to_le_bytes());
    put(72, &16i16.to_le_bytes());
    for (i, p) in [0f32, 1.0, 0.5, 2.0].iter().enumerate() {
        put(76 + 4 * i, &p.to_le_bytes());
    }
    for (i, o) in [3i16, 3, 2].iter().enumerate() {
        put(253 + 2 * i, &o.to_le_bytes());
    }
    let mut mgh = Vec::new();
    for v in [1i32, 6, 5, 4, 2, 4, 0] {
        mgh.extend(v.to_be_bytes());
    }
    mgh.extend(1i16.to_be_bytes());
    let mdc = [
        1f32, 0.5, 2.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 1.0, 2.0, 3.0,
    ];
    for v in mdc {
        mgh.extend(v.to_be_bytes());
    }
    mgh.resize(284, 0);
    mgh.extend(two_volumes(true));
    mgh.extend(2000f32.to_be_bytes());
    let nrrd4 = "NRRD0004\n# seed\ntype: short\ndimension: 4\nsizes: 6 5 4 2\n\
        kinds: domain domain domain time\nspacings: 1 0.5 2 2\nendian: little\nencoding: raw\n\n";
    let rgb_head = "ObjectType = Image\nNDims = 3\nDimSize = 6 5 4\nElementNumberOfChannels = 3\n\
        ElementType = MET_UCHAR\nElementSpacing = 1 0.5 2\nElementDataFile = LOCAL\n";
    let rgb: Vec<u8> = u8s().iter().flat_map(|&v| [v, 255 - v, v / 2]).collect();
    vec![
        Seed::grid(
            "nii-4d.gz",
            vec![InputFile::new("t.nii.gz", gzip(&fmri), Layout::Binary(352)).gzipped()],
        ),
        Seed::grid(
            "analyze",
            vec![
                InputFile::new("t.hdr", analyze, Layout::Binary(348)),
                InputFile::new("t.img", i16s(true), Layout::Binary(0)),
            ],
        ),
        Seed::grid(
            "mgz",
            vec![InputFile::new("t.mgz", gzip(&mgh), Layout::Binary(284)).gzipped()],
        ),
        Seed::grid(
            "nrrd-4d",
            vec![InputFile::new(
                "t.nrrd",
                with_header(nrrd4, &two_volumes(false)),
                Layout::Text(nrrd4.len()),
            )],
        ),
        Seed::grid(
            "mha-rgb",
            vec![InputFile::new(
                "t.mha",
                with_header(rgb_head, &rgb),
                Layout::Text(rgb_head.len()),
            )],
        ),
    ]
}

// ------------------------------------------------------------------ VTK legacy

fn sp_head(mode: &str, ty: &str) -> String {
    format!(
        "# vtk DataFile Version 3.0\nseed\n{mode}\nDATASET STRUCTURED_POINTS\nDIMENSIONS 6 5 4\n\
         SPACING 1 0.5 2\nORIGIN 0 0 0\nPOINT_DATA 120\nSCALARS v {ty}\nLOOKUP_TABLE default\n"
    )
}

fn ug_points(binary: bool) -> Vec<u8> {
    let mut v = b"POINTS 8 float\n".to_vec();
    for (p, _) in cube() {
        if binary {
            v.extend(p.iter().flat_map(|c| c.to_be_bytes()));
        } else {
            v.extend(format!("{} {} {}\n", p[0], p[1], p[2]).bytes());
        }
    }
    v
}

fn ug_cells(binary: bool) -> Vec<u8> {
    let mut v = b"\nCELLS 5 25\n".to_vec();
    for t in TETS {
        if binary {
            v.extend(
                [4, t[0], t[1], t[2], t[3]]
                    .iter()
                    .flat_map(|i| i.to_be_bytes()),
            );
        } else {
            v.extend(format!("4 {} {} {} {}\n", t[0], t[1], t[2], t[3]).bytes());
        }
    }
    v.extend(b"\nCELL_TYPES 5\n");
    for _ in TETS {
        if binary {
            v.extend(10i32.to_be_bytes());
        } else {
            v.extend(b"10\n");
        }
    }
    v
}

fn ug_data(binary: bool) -> Vec<u8> {
    let mut v = b"\nPOINT_DATA 8\nSCALARS s float\nLOOKUP_TABLE default\n".to_vec();
    for (_, s) in cube() {
        if binary {
            v.extend(s.to_be_bytes());
        } else {
            v.extend(format!("{s}\n").bytes());
        }
    }
    v.push(b'\n');
    v
}

fn ug(binary: bool) -> Vec<u8> {
    let mode = if binary { "BINARY" } else { "ASCII" };
    let mut v = format!("# vtk DataFile Version 3.0\nseed\n{mode}\nDATASET UNSTRUCTURED_GRID\n")
        .into_bytes();
    v.extend(ug_points(binary));
    v.extend(ug_cells(binary));
    v.extend(ug_data(binary));
    v
}

fn vtk_legacy_seeds() -> Vec<Seed> {
    let ascii = sp_head("ASCII", "short") + &text_values() + "\n";
    let bin_head = sp_head("BINARY", "float");
    let ug_ascii = ug(false);
    let ug_bin = ug(true);
    vec![
        Seed::grid(
            "vtk-sp-ascii",
            vec![InputFile::new(
                "t.vtk",
                ascii.clone().into_bytes(),
                Layout::Text(ascii.len()),
            )],
        ),
        Seed::grid(
            "vtk-sp-binary",
            vec![InputFile::new(
                "t.vtk",
                [with_header(&bin_head, &f32s(true)), b"\n".to_vec()].concat(),
                Layout::Text(bin_head.len()),
            )],
        ),
        Seed::mesh(
            "vtk-ug-ascii",
            vec![InputFile::new(
                "t.vtk",
                ug_ascii.clone(),
                Layout::Text(ug_ascii.len()),
            )],
        ),
        Seed::mesh(
            "vtk-ug-binary",
            vec![InputFile::new(
                "t.vtk",
                ug_bin.clone(),
                Layout::Text(ug_bin.len()),
            )],
        ),
    ]
}

// ------------------------------------------------------------------ VTK XML

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(char::from(ABC[(n >> (18 - 6 * i)) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The three VTK XML encodings the seeds use.
#[derive(Clone, Copy, PartialEq, Eq)]
enum XmlMode {
    Ascii,
    Base64,
    Appended,
}

/// Writes DataArrays in one mode, gathering appended data.
struct XmlWriter {
    mode: XmlMode,
    appended: Vec<u8>,
}

impl XmlWriter {
    /// A DataArray of `ty` (`Float32`, `Int32` or `UInt8`).
    fn array(&mut self, name: &str, ty: &str, ncomp: usize, values: &[f64]) -> String {
        let head =
            format!("<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{ncomp}\"");
        let bytes: Vec<u8> = values
            .iter()
            .flat_map(|&v| match ty {
                "Float32" => (v as f32).to_le_bytes().to_vec(),
                "Int32" => (v as i32).to_le_bytes().to_vec(),
                _ => vec![v as u8],
            })
            .collect();
        let framed = [(bytes.len() as u32).to_le_bytes().to_vec(), bytes].concat();
        match self.mode {
            XmlMode::Ascii => {
                let t: Vec<String> = values.iter().map(|v| v.to_string()).collect();
                format!("{head} format=\"ascii\">\n{}\n</DataArray>\n", t.join(" "))
            }
            XmlMode::Base64 => {
                format!(
                    "{head} format=\"binary\">\n{}\n</DataArray>\n",
                    base64(&framed)
                )
            }
            XmlMode::Appended => {
                let off = self.appended.len();
                self.appended.extend(framed);
                format!("{head} format=\"appended\" offset=\"{off}\"/>\n")
            }
        }
    }

    /// The whole file around `body`.
    fn file(&self, kind: &str, body: &str) -> Vec<u8> {
        let mut v = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt32\">\n{body}"
        )
        .into_bytes();
        if self.mode == XmlMode::Appended {
            v.extend(b"<AppendedData encoding=\"raw\">\n   _");
            v.extend(&self.appended);
            v.extend(b"\n</AppendedData>\n");
        }
        v.extend(b"</VTKFile>\n");
        v
    }
}

fn vti(mode: XmlMode) -> Vec<u8> {
    let mut w = XmlWriter {
        mode,
        appended: Vec::new(),
    };
    let vals: Vec<f64> = values().iter().map(|&v| f64::from(v)).collect();
    let a = w.array("s", "Float32", 1, &vals);
    let body = format!(
        "<ImageData WholeExtent=\"0 5 0 4 0 3\" Origin=\"0 0 0\" Spacing=\"1 0.5 2\">\n\
         <Piece Extent=\"0 5 0 4 0 3\">\n<PointData Scalars=\"s\">\n{a}</PointData>\n\
         </Piece>\n</ImageData>\n"
    );
    w.file("ImageData", &body)
}

fn vtu(mode: XmlMode) -> Vec<u8> {
    let mut w = XmlWriter {
        mode,
        appended: Vec::new(),
    };
    let pts: Vec<f64> = cube().iter().flat_map(|(p, _)| p.map(f64::from)).collect();
    let scalars: Vec<f64> = cube().iter().map(|(_, s)| f64::from(*s)).collect();
    let conn: Vec<f64> = TETS.iter().flatten().map(|&i| f64::from(i)).collect();
    let s = w.array("s", "Float32", 1, &scalars);
    let points = w.array("Points", "Float32", 3, &pts);
    let c = w.array("connectivity", "Int32", 1, &conn);
    let o = w.array("offsets", "Int32", 1, &[4.0, 8.0, 12.0, 16.0, 20.0]);
    let t = w.array("types", "UInt8", 1, &[10.0; 5]);
    let body = format!(
        "<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" NumberOfCells=\"5\">\n\
         <PointData Scalars=\"s\">\n{s}</PointData>\n<Points>\n{points}</Points>\n\
         <Cells>\n{c}{o}{t}</Cells>\n</Piece>\n</UnstructuredGrid>\n"
    );
    w.file("UnstructuredGrid", &body)
}

fn vtk_xml_seeds() -> Vec<Seed> {
    let modes = [
        (XmlMode::Ascii, "ascii"),
        (XmlMode::Base64, "base64"),
        (XmlMode::Appended, "appended"),
    ];
    let names_vti = ["vti-ascii", "vti-base64", "vti-appended"];
    let names_vtu = ["vtu-ascii", "vtu-base64", "vtu-appended"];
    let mut v = Vec::new();
    for (i, (mode, _)) in modes.iter().enumerate() {
        v.push(Seed::grid(
            names_vti[i],
            vec![InputFile::new("t.vti", vti(*mode), Layout::Xml)],
        ));
        v.push(Seed::mesh(
            names_vtu[i],
            vec![InputFile::new("t.vtu", vtu(*mode), Layout::Xml)],
        ));
    }
    v
}

// ------------------------------------------------------------------ PLOT3D, SLC, OFF, .vtet

/// A big-endian whole-grid PLOT3D xyz + q pair on a 6 x 5 x 4 grid.
fn plot3d() -> Seed {
    let dims = [6i32, 5, 4];
    let n = 120;
    let mut xyz: Vec<u8> = dims.iter().flat_map(|d| d.to_be_bytes()).collect();
    let mut q = xyz.clone();
    let ijk = |p: usize| [p % 6, (p / 6) % 5, p / 30].map(|c| c as f32);
    for c in 0..3 {
        xyz.extend((0..n).flat_map(|p| ijk(p)[c].to_be_bytes()));
    }
    q.extend(
        [0.5f32, 10.0, 1e5, 0.0]
            .iter()
            .flat_map(|h| h.to_be_bytes()),
    );
    let vals = values();
    for var in 0..5 {
        q.extend((0..n).flat_map(|p| (1.0 + vals[p] * (var as f32 + 1.0) / 100.0).to_be_bytes()));
    }
    Seed::grid(
        "plot3d",
        vec![
            InputFile::new("txyz.bin", xyz, Layout::Binary(12)),
            InputFile::new("tq.bin", q, Layout::Binary(28)),
        ],
    )
}

/// Run-length encodes one slice: repeated runs of up to 127 equal bytes.
fn rle(slice: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < slice.len() {
        let mut n = 1;
        while i + n < slice.len() && n < 127 && slice[i + n] == slice[i] {
            n += 1;
        }
        out.extend([n as u8, slice[i]]);
        i += n;
    }
    out.push(0);
    out
}

/// An SLC volume (8-bit), its slices raw or run-length encoded.
fn slc(compressed: bool) -> Seed {
    let head = format!(
        "11111\n6 5 4 8\n1.0 0.5 2.0\n1 6 0 {}\n2 1 X",
        u8::from(compressed)
    );
    let mut bytes = head.clone().into_bytes();
    bytes.extend([9u8; 6]);
    for slice in u8s().chunks(30) {
        if compressed {
            let r = rle(slice);
            bytes.extend(format!("{} X", r.len()).bytes());
            bytes.extend(r);
        } else {
            bytes.extend(slice);
        }
    }
    let format = if compressed { "slc-rle" } else { "slc-raw" };
    Seed::grid(
        format,
        vec![InputFile::new("t.slc", bytes, Layout::Text(head.len()))],
    )
}

fn off_text() -> String {
    let mut s = String::from("OFF\n# seed\n8 5\n");
    for (p, v) in cube() {
        s += &format!("{} {} {} {v}\n", p[0], p[1], p[2]);
    }
    for t in TETS {
        s += &format!("{} {} {} {}\n", t[0], t[1], t[2], t[3]);
    }
    s
}

fn off(gz: bool) -> Seed {
    let text = off_text();
    let len = text.len();
    if gz {
        Seed::mesh(
            "off.gz",
            vec![InputFile::new("t.off.gz", gzip(text.as_bytes()), Layout::Text(len)).gzipped()],
        )
    } else {
        Seed::mesh(
            "off",
            vec![InputFile::new(
                "t.off",
                text.into_bytes(),
                Layout::Text(len),
            )],
        )
    }
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A `.vtet` file: magic, version 1, point and tet counts, positions, scalars, tets and an
/// FNV-1a checksum of the payload.
fn vtet() -> Seed {
    let mut out = b"VOLUXTET".to_vec();
    out.extend(1u32.to_le_bytes());
    out.extend(8u64.to_le_bytes());
    out.extend(5u64.to_le_bytes());
    let corners = cube();
    let mut payload: Vec<u8> = corners
        .iter()
        .flat_map(|(p, _)| p.iter().flat_map(|c| c.to_le_bytes()))
        .collect();
    payload.extend(corners.iter().flat_map(|(_, s)| s.to_le_bytes()));
    payload.extend(TETS.iter().flatten().flat_map(|i| i.to_le_bytes()));
    out.extend(&payload);
    out.extend(fnv1a(&payload).to_le_bytes());
    Seed::mesh(
        "vtet",
        vec![InputFile::new("t.vtet", out, Layout::Binary(28))],
    )
}

// ------------------------------------------------------------------ DICOM

/// The tiny multi-frame DICOM file of the shared data, when present.
fn dicom() -> Option<Seed> {
    let p = volux_testkit::data::shared("pydicom_emri_small/emri_small.dcm")?;
    let bytes = std::fs::read(p).ok()?;
    Some(Seed::grid(
        "dicom",
        vec![InputFile::new("t.dcm", bytes, Layout::Binary(1024))],
    ))
}

/// Compressed DICOM: the 10-frame 32 x 32 crops of `emri_small` committed as volux-io's
/// fixtures (`tests/fixtures/dicom_compressed`), in RLE Lossless, JPEG Lossless and JPEG 2000
/// Lossless; the header is the bytes before the PixelData element.
fn dicom_compressed() -> Vec<Seed> {
    let files: [(&'static str, &[u8]); 3] = [
        (
            "dicom-rle",
            include_bytes!("../../../volux-io/tests/fixtures/dicom_compressed/emri_rle.dcm"),
        ),
        (
            "dicom-jpeg-lossless",
            include_bytes!("../../../volux-io/tests/fixtures/dicom_compressed/emri_jpll70.dcm"),
        ),
        (
            "dicom-j2k",
            include_bytes!("../../../volux-io/tests/fixtures/dicom_compressed/emri_j2k90.dcm"),
        ),
    ];
    files
        .into_iter()
        .map(|(format, bytes)| {
            let header = bytes
                .windows(4)
                .position(|w| w == [0xE0, 0x7F, 0x10, 0x00])
                .unwrap_or(bytes.len() / 2);
            Seed::grid(
                format,
                vec![InputFile::new(
                    "t.dcm",
                    bytes.to_vec(),
                    Layout::Binary(header),
                )],
            )
        })
        .collect()
}

/// DICOM values, colour and volumes: volux-io's committed fixtures
/// (`tests/fixtures/dicom_values`): palettes (big endian, segmented), planar RGB, YBR_FULL_422,
/// RLE YBR_FULL, a big-endian 32-bit RT Dose, a Modality LUT, single bits, double floats,
/// attributes stored as UN, an enhanced multi-frame of two b-values; the header is the bytes
/// before the pixel data element.
fn dicom_values() -> Vec<Seed> {
    macro_rules! fixture {
        ($name:literal) => {
            include_bytes!(concat!(
                "../../../volux-io/tests/fixtures/dicom_values/",
                $name,
                ".dcm"
            ))
        };
    }
    let files: [(&'static str, &[u8]); 11] = [
        ("dicom-palette-be", fixture!("palette8_expb")),
        ("dicom-palette-segmented", fixture!("palette_segmented")),
        ("dicom-rgb-planar", fixture!("rgb8_planar1_2frame")),
        ("dicom-ybr422", fixture!("ybr_full_422")),
        ("dicom-ybr-rle", fixture!("ybr_full_rle")),
        ("dicom-rtdose-be", fixture!("rtdose_expb")),
        ("dicom-modality-lut", fixture!("mlut")),
        ("dicom-bits1", fixture!("bits1_2frame")),
        ("dicom-float64", fixture!("float64")),
        ("dicom-un", fixture!("un_explicit")),
        ("dicom-enhanced-dwi", fixture!("enhanced_dwi")),
    ];
    // PixelData, FloatPixelData, DoubleFloatPixelData, little or big endian.
    let tags: [[u8; 4]; 6] = [
        [0xE0, 0x7F, 0x10, 0x00],
        [0xE0, 0x7F, 0x08, 0x00],
        [0xE0, 0x7F, 0x09, 0x00],
        [0x7F, 0xE0, 0x00, 0x10],
        [0x7F, 0xE0, 0x00, 0x08],
        [0x7F, 0xE0, 0x00, 0x09],
    ];
    files
        .into_iter()
        .map(|(format, bytes)| {
            let header = bytes
                .windows(4)
                .position(|w| tags.iter().any(|t| w == t))
                .unwrap_or(bytes.len() / 2);
            Seed::grid(
                format,
                vec![InputFile::new(
                    "t.dcm",
                    bytes.to_vec(),
                    Layout::Binary(header),
                )],
            )
        })
        .collect()
}

// ------------------------------------------------------------------ TIFF

/// Pages of `C` (one per z slice, 6 x 5 each) as one TIFF file, the first page described by
/// `description`.
fn tiff_file<C: tiff::encoder::colortype::ColorType>(
    pages: &[Vec<C::Inner>],
    compression: tiff::encoder::Compression,
    description: Option<&str>,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut out = std::io::Cursor::new(Vec::new());
    let mut enc = tiff::encoder::TiffEncoder::new(&mut out)
        .expect("TIFF header")
        .with_compression(compression);
    for (i, p) in pages.iter().enumerate() {
        let mut img = enc
            .new_image::<C>(DIMS[0] as u32, DIMS[1] as u32)
            .expect("TIFF page");
        if let (0, Some(d)) = (i, description) {
            img.encoder()
                .write_tag(tiff::tags::Tag::ImageDescription, d)
                .expect("TIFF description");
        }
        img.write_data(p).expect("TIFF data");
    }
    out.into_inner()
}

/// A multi-page 16-bit LZW stack, and a two-channel OME-TIFF (Deflate, 8-bit, XYZCT).
fn tiff_seeds() -> Vec<Seed> {
    use tiff::encoder::{colortype, Compression, DeflateLevel};
    let plane = DIMS[0] * DIMS[1];
    let u16_pages: Vec<Vec<u16>> = values()
        .chunks(plane)
        .map(|p| p.iter().map(|&v| v as u16).collect())
        .collect();
    let lzw = tiff_file::<colortype::Gray16>(&u16_pages, Compression::Lzw, None);
    let u8_pages: Vec<Vec<u8>> = u8s().chunks(plane).map(<[u8]>::to_vec).collect();
    let both: Vec<Vec<u8>> = u8_pages.iter().chain(&u8_pages).cloned().collect();
    let xml = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?><OME xmlns="http://www.openmicroscopy.org/Schemas/OME/2016-06"><Image ID="Image:0"><Pixels ID="Pixels:0" DimensionOrder="XYZCT" Type="uint8" SizeX="{}" SizeY="{}" SizeZ="{}" SizeC="2" SizeT="1" PhysicalSizeX="1" PhysicalSizeY="0.5" PhysicalSizeZ="2"><Channel ID="Channel:0:0"/><Channel ID="Channel:0:1"/><TiffData IFD="0" PlaneCount="{}"/></Pixels></Image></OME>"#,
        DIMS[0],
        DIMS[1],
        DIMS[2],
        2 * DIMS[2]
    );
    let ome = tiff_file::<colortype::Gray8>(
        &both,
        Compression::Deflate(DeflateLevel::Balanced),
        Some(&xml),
    );
    vec![
        Seed::grid(
            "tiff-lzw",
            vec![InputFile::new(
                "t.tif",
                lzw.clone(),
                Layout::Binary(lzw.len()),
            )],
        ),
        Seed::grid(
            "ome-tiff",
            vec![InputFile::new(
                "t.ome.tif",
                ome.clone(),
                Layout::Binary(ome.len()),
            )],
        ),
    ]
}
