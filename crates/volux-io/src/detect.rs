//! Format detection: magic bytes first, extension second.
use std::io::Read;
use std::path::Path;

use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;

/// The formats Volux reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Format {
    /// Headerless raw data with a JSON sidecar (`F.json`).
    RawJson,
    /// NRRD.
    Nrrd,
    /// MetaImage `.mhd` / `.mha`.
    MetaImage,
    /// NIfTI-1 or NIfTI-2.
    Nifti,
    /// Analyze 7.5 (and SPM's variant): a `.hdr` + `.img` pair without a NIfTI magic.
    Analyze,
    /// FreeSurfer MGH (`.mgh`) and its gzip-compressed form (`.mgz`).
    Mgh,
    /// VolVis SLC.
    Slc,
    /// DICOM (a folder of slices or one multi-frame file).
    Dicom,
    /// VTK legacy.
    VtkLegacy,
    /// VTK XML image data.
    Vti,
    /// VTK XML unstructured grid.
    Vtu,
    /// PLOT3D whole-grid xyz (+ q).
    Plot3d,
    /// OFF tetrahedral mesh.
    Off,
    /// Volux binary tet mesh.
    Vtet,
    /// An OME-Zarr store (a directory; NGFF 0.4 on Zarr v2, 0.5 on Zarr v3).
    OmeZarr,
    /// TIFF stacks: multi-page TIFF, ImageJ hyperstacks, OME-TIFF, folders of TIFF slices.
    Tiff,
}

impl Format {
    /// Human-readable name.
    pub fn name(self) -> &'static str {
        match self {
            Format::RawJson => "raw + JSON sidecar",
            Format::Nrrd => "NRRD",
            Format::MetaImage => "MetaImage",
            Format::Nifti => "NIfTI",
            Format::Analyze => "Analyze 7.5",
            Format::Mgh => "FreeSurfer MGH",
            Format::Slc => "SLC",
            Format::Dicom => "DICOM",
            Format::VtkLegacy => "VTK legacy",
            Format::Vti => "VTK XML image data (.vti)",
            Format::Vtu => "VTK XML unstructured grid (.vtu)",
            Format::Plot3d => "PLOT3D",
            Format::Off => "OFF tetrahedral mesh",
            Format::Vtet => "Volux binary tet mesh (.vtet)",
            Format::OmeZarr => "OME-Zarr",
            Format::Tiff => "TIFF",
        }
    }
}

/// The file name lowercased with a trailing `.gz` removed, and whether it was there.
fn stem_without_gz(path: &Path) -> (String, bool) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    match name.strip_suffix(".gz") {
        Some(s) => (s.to_string(), true),
        None => (name, false),
    }
}

/// Whether the folder `path` is a Zarr store: named `*.zarr`, or holding `zarr.json`,
/// `.zgroup`, `.zattrs` or `.zarray`.
pub fn is_zarr_dir(path: &Path) -> bool {
    path.is_dir()
        && (path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().to_lowercase().ends_with(".zarr"))
            || ["zarr.json", ".zgroup", ".zattrs", ".zarray"]
                .iter()
                .any(|f| path.join(f).is_file()))
}

/// Whether a file name ends in `.tif` or `.tiff` (any case).
pub fn is_tiff_name(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.ends_with(".tif") || n.ends_with(".tiff")
}

/// Whether the folder `path` is a folder of TIFF slices: more than half of its visible
/// entries are named `*.tif` / `*.tiff` (a DICOM folder's files are named otherwise).
pub fn is_tiff_dir(path: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(path) else {
        return false;
    };
    let (mut tiff, mut other) = (0usize, 0usize);
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        match (name.starts_with('.'), is_tiff_name(&name)) {
            (true, _) => {}
            (false, true) => tiff += 1,
            (false, false) => other += 1,
        }
    }
    tiff > other
}

/// Whether `head` starts with the TIFF magic bytes: `II*\0` / `MM\0*`, or BigTIFF's
/// `II+\0` / `MM\0+`.
pub fn is_tiff_magic(head: &[u8]) -> bool {
    [b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"]
        .iter()
        .any(|m| head.starts_with(*m))
}

/// Whether `head` starts an Analyze 7.5 header: `sizeof_hdr` 348 in either byte order and no
/// NIfTI-1 magic at byte 344.
pub fn is_analyze_header(head: &[u8]) -> bool {
    let Some(&[a, b, c, d]) = head.get(..4) else {
        return false;
    };
    let size = [a, b, c, d];
    let sized = i32::from_le_bytes(size) == 348 || i32::from_be_bytes(size) == 348;
    let magic = head.get(344..348);
    sized && head.len() >= 348 && magic != Some(b"n+1\0") && magic != Some(b"ni1\0")
}

/// The format of the pair whose image file is `path` (`x.img`, `x.img.gz`), told by the
/// header beside it (`x.hdr`): NIfTI by its magic, else Analyze 7.5; `None` without one.
fn pair_header(path: &Path) -> Option<Format> {
    let name = path.file_name()?.to_string_lossy().into_owned();
    let lower = name.to_ascii_lowercase();
    let stem_len = [".img.gz", ".img"]
        .iter()
        .find(|s| lower.ends_with(*s))
        .map(|s| name.len() - s.len())?;
    let hdr = path.with_file_name(format!("{}.hdr", name.get(..stem_len)?));
    let mut head = Vec::with_capacity(348);
    crate::util::open_regular(&hdr)
        .ok()?
        .take(348)
        .read_to_end(&mut head)
        .ok()?;
    let nifti1 = head
        .get(344..348)
        .is_some_and(|m| m == b"ni1\0" || m == b"n+1\0");
    let nifti2 = head
        .get(4..8)
        .is_some_and(|m| m == b"ni2\0" || m == b"n+2\0");
    if nifti1 || nifti2 {
        Some(Format::Nifti)
    } else if is_analyze_header(&head) {
        Some(Format::Analyze)
    } else {
        None
    }
}

/// Why a `.mnc` file is not read, by its magic bytes: MINC-2 is HDF5, MINC-1 netCDF.
fn minc_message(head: &[u8]) -> String {
    if head.starts_with(b"\x89HDF\r\n\x1a\n") {
        "MINC-2 (HDF5) is not read: Volux has no HDF5 reader (the hdf5 crates need the HDF5 C \
         library; the pure-Rust ones are too young to trust); convert with mnc2nii or nibabel"
            .into()
    } else if head.starts_with(b"CDF") {
        "MINC-1 (netCDF) is not read (convert with mnc2nii or nibabel)".into()
    } else {
        "a .mnc file that is neither MINC-2 (HDF5) nor MINC-1 (netCDF)".into()
    }
}

/// Detects the format of `path` (a file, or a folder of DICOM slices). Only regular files
/// are opened to sniff their magic bytes: a FIFO, a device or a socket is refused by type
/// ([`ErrorKind::NotRegular`]).
pub fn detect(path: &Path) -> Result<Format> {
    let meta = crate::util::data_metadata(path)?;
    if meta.is_dir() {
        if is_zarr_dir(path) {
            return Ok(Format::OmeZarr);
        }
        if is_tiff_dir(path) {
            return Ok(Format::Tiff);
        }
        return Ok(Format::Dicom);
    }
    let mut head = [0u8; 512];
    let n = {
        let mut f = crate::util::open_regular(path)?;
        let mut n = 0;
        while n < head.len() {
            match f
                .read(&mut head[n..])
                .map_err(|e| ReadError::new(path, e))?
            {
                0 => break,
                k => n += k,
            }
        }
        n
    };
    let head = &head[..n];
    let (name, _gz) = stem_without_gz(path);
    let ext = |e: &str| name.ends_with(e);
    // The image file of a pair holds data only: its header beside it tells the format.
    if ext(".img") {
        if let Some(format) = pair_header(path) {
            return Ok(format);
        }
    }
    // Magic bytes.
    if head.starts_with(b"NRRD") {
        return Ok(Format::Nrrd);
    }
    if head.starts_with(crate::vtet::MAGIC) {
        return Ok(Format::Vtet);
    }
    if head.len() >= 132 && &head[128..132] == b"DICM" {
        return Ok(Format::Dicom);
    }
    // After DICOM: a DICOM file's preamble may hold a TIFF header (dual-format files).
    if is_tiff_magic(head) && !ext(".raw") {
        return Ok(Format::Tiff);
    }
    if head.starts_with(b"# vtk DataFile") {
        return Ok(Format::VtkLegacy);
    }
    if head.len() >= 348 && (&head[344..348] == b"n+1\0" || &head[344..348] == b"ni1\0") {
        return Ok(Format::Nifti);
    }
    if head.len() >= 8 && (&head[4..8] == b"n+2\0" || &head[4..8] == b"ni2\0") {
        return Ok(Format::Nifti);
    }
    if ext(".hdr") && is_analyze_header(head) {
        return Ok(Format::Analyze);
    }
    if ext(".mnc") {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(minc_message(head)),
        ));
    }
    // A `.raw` file is headerless: its first bytes are data, whatever they spell.
    if crate::slc::is_slc(head) && !ext(".raw") {
        return Ok(Format::Slc);
    }
    let text = String::from_utf8_lossy(head);
    if text.contains("<VTKFile") {
        if text.contains("UnstructuredGrid") {
            return Ok(Format::Vtu);
        }
        if text.contains("ImageData") {
            return Ok(Format::Vti);
        }
    }
    // Extensions (gzip-compressed files cannot be sniffed cheaply).
    let sidecar = path.with_file_name(format!(
        "{}.json",
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    ));
    let by_ext = if ext(".nrrd") || ext(".nhdr") {
        Format::Nrrd
    } else if ext(".mhd") || ext(".mha") {
        Format::MetaImage
    } else if ext(".nii") {
        Format::Nifti
    } else if ext(".mgh") || ext(".mgz") {
        Format::Mgh
    } else if ext(".slc") {
        Format::Slc
    } else if ext(".dcm") {
        Format::Dicom
    } else if ext(".vtk") {
        Format::VtkLegacy
    } else if ext(".vti") {
        Format::Vti
    } else if ext(".vtu") {
        Format::Vtu
    } else if ext(".off") {
        Format::Off
    } else if ext(".vtet") {
        Format::Vtet
    } else if ext(".tif") || ext(".tiff") {
        Format::Tiff
    } else if name.contains("xyz") && (ext(".bin") || ext(".x") || ext(".xyz")) {
        Format::Plot3d
    } else if ext(".raw") || sidecar.exists() {
        Format::RawJson
    } else {
        return Err(ReadError::new(path, ErrorKind::UnknownFormat));
    };
    Ok(by_ext)
}
