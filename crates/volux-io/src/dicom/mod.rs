//! DICOM (PS3.10 files with the 128-byte preamble and `DICM` marker): a folder of single-frame
//! slices, one series picked by SeriesInstanceUID, a DICOMDIR, or one file (enhanced
//! multi-frame or a single slice). Parsing uses `dicom-object` 0.10 (a maintained, pure-Rust
//! DICOM parser). Uncompressed transfer syntaxes (implicit and explicit VR little endian,
//! explicit VR big endian, and deflated explicit VR little endian, inflated by `flate2` after
//! a bounded inflation in module `bounds`) are read directly; compressed pixel data is decoded
//! in module `codec`, with pure-Rust codecs only: RLE Lossless (Volux's own decoder, 8, 16
//! and 32 bits), JPEG baseline (8-bit) and lossless (`jpeg-decoder`), 12-bit lossy JPEG
//! (Volux's own decoder, module `jpeg12`), JPEG-LS lossless and
//! near-lossless (`pure_jpegls`, single-component), JPEG 2000 and High-Throughput JPEG 2000
//! (`openjp2`, the Rust port of OpenJPEG). The grid of a compressed file gets a note naming
//! its transfer syntax. No C or C++ codec is linked: CharLS (JPEG-LS through
//! `dicom-pixeldata`'s `charls` feature) needs CMake to build. 12-bit progressive or colour
//! JPEG, multi-component JPEG-LS, JPEG XL, video, JPIP and the retired JPEG processes are
//! [`ErrorKind::Unsupported`], one line naming the transfer syntax's UID and name and why.
//! Decoding gives the stored values, which then take the same path as uncompressed ones
//! (below).
//!
//! - Folder (module `folder`): every file with the `DICM` marker is scanned (others, e.g.
//!   `series.json`, and non-image DICOM objects pass quietly; files that cannot be parsed
//!   are skipped and named in a note); a DICOMDIR in the folder, or opened itself, is
//!   followed to the files it references. Slices are grouped by SeriesInstanceUID and the
//!   requested series, else the one with the most readable slices, is loaded (the others are
//!   named in a note). A series is split into stacks by Rows / Columns / BitsAllocated /
//!   SamplesPerPixel / PhotometricInterpretation / orientation: the largest is loaded, the others named in a note; a stack with a gap (a
//!   missing or unreadable slice) is [`ErrorKind::Invalid`], naming the sub-series it splits
//!   into. Slices are ordered by ImagePositionPatient projected on the slice normal (row x
//!   column direction cosines), or by InstanceNumber when positions are missing (noted).
//!   Duplicate positions are [`ErrorKind::Invalid`].
//! - Multi-frame file: frames are the z slices; spacing, orientation, positions and rescale
//!   come from the shared / per-frame functional groups (PixelMeasures, PlaneOrientation,
//!   PlanePosition, PixelValueTransformation sequences), falling back to top-level attributes;
//!   an RT Dose's frames are placed by its GridFrameOffsetVector (PS3.3 C.8.8.3.2, module
//!   `frames`).
//! - Several volumes at the same positions (module `volumes`): slices or frames told apart by
//!   DiffusionBValue / gradient (standard or Siemens' private), TemporalPosition Index /
//!   Identifier or StackID are volumes; [`VolumeChoice::timepoint`] picks one and the grid
//!   records the axis (an [`volux_core::volume_axes::ExtraAxis`] of kind Time for temporal
//!   positions, Volume with the b-values otherwise). Duplicate positions no key explains
//!   remain an error.
//! - Spacing: PixelSpacing is (row spacing = y, column spacing = x); z is the median gap of the
//!   sorted positions, else SpacingBetweenSlices, else SliceThickness (noted).
//! - Pixels (PS3.5 8, PS3.3 C.7.6.3): PixelData with BitsAllocated 1 (unpacked to uint8 0 / 1,
//!   noted), 8 -> uint8, 16 -> uint16 / int16 (PixelRepresentation), 32 -> float32 (noted);
//!   FloatPixelData (float32) and DoubleFloatPixelData (converted to float32, noted). Big-endian
//!   files' samples are brought to little endian as pydicom reads them (module `pixels`).
//!   Attributes stored as `UN` are decoded by the dictionary's VR (module `un`). Signed values
//!   are sign-extended from BitsStored. The Modality LUT transformation (PS3.3 C.11.1) of each
//!   slice or frame is applied (module `values`): RescaleSlope / RescaleIntercept (slope 1
//!   with values that still fit int16 gives int16, CT Hounsfield units, anything else
//!   float32) or the Modality LUT Sequence (its entries, noted); then an RT Dose's
//!   DoseGridScaling (Gy, float32, noted).
//! - Colour (module `color`): three samples a pixel (RGB, YBR_FULL and YBR_FULL_422 converted
//!   to RGB as pydicom converts them, planar configuration 0 or 1; YBR_RCT / YBR_ICT come out
//!   of the JPEG 2000 decoder as RGB, JPEG as module `jpeg_color` decides) and PALETTE COLOR
//!   (the red, green and blue Palette Color LUTs, plain or segmented, module `lut`) give an
//!   RGB grid ([`Grid::from_rgb`], its luminance as the scalar), or the one channel
//!   [`VolumeChoice::component`] asks for (recorded as a Color axis).
//! - Lengths: the pixel data length is checked against Rows x Columns x SamplesPerPixel x
//!   frames x bytes before use; a file that ends inside its pixel data is
//!   [`ErrorKind::Truncated`]. Compressed data: the decoded size is checked against the
//!   memory budget before decoding, each frame's codestream header against Rows, Columns,
//!   SamplesPerPixel and BitsAllocated (a mismatch is [`ErrorKind::Invalid`]: the decoders
//!   would overrun their buffers), and each decoded frame's length before use.
//!
//! Placement (LPS, the DICOM patient coordinate system, PS3.3 C.7.6.2.1.1): the grid is in
//! (column, row, slice) order with its origin at the first slice's ImagePositionPatient, and
//! its direction matrix has as columns the ImageOrientationPatient row cosines, its column
//! cosines and the slice normal (row x column), the direction in which slices are ordered. `dicom-parser` allocates each element's declared length (at most 4 GiB, a `u32`)
//! before reading it, so every element length is first checked against the bytes left in
//! the file (module `bounds`); Volux's own buffers are checked with `check_alloc`. Only regular
//! files are opened ([`crate::util::open_regular`]); in a folder, anything else (a FIFO, a
//! device, a link to one) is skipped.
use std::path::Path;

use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, OpenFileOptions};
use volux_core::Grid;

use crate::dataset::VolumeChoice;
use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;

mod attrs;
mod bounds;
mod codec;
mod color;
mod files;
mod folder;
mod frames;
mod geometry;
mod image;
mod jpeg12;
mod jpeg_color;
mod lut;
mod pixels;
mod ts;
mod un;
mod values;
mod volumes;

use attrs::ImageInfo;
use files::{has_dicm, invalid, parse_error};
use folder::Picked;
use geometry::{Stack, StackInput};

/// Reads a DICOM folder (one series) or file. `series_uid` picks the series in a folder
/// holding several (default: the one with the most slices); `choice` the volume of a series
/// or file holding several at the same positions, and the channel of a colour image.
pub fn read(path: &Path, series_uid: Option<&str>, choice: VolumeChoice) -> Result<Grid> {
    let meta = crate::util::data_metadata(path)?;
    let picked = if meta.is_dir() {
        folder::read_folder(path, series_uid)?
    } else if folder::is_dicomdir(path) {
        folder::read_dicomdir(path, series_uid)?
    } else {
        return read_file(path, Vec::new(), choice);
    };
    match picked {
        Picked::File { path, notes } => read_file(&path, notes, choice),
        Picked::Slices { dir, slices, notes } => load_series(&dir, &slices, notes, choice),
    }
}

/// The header of one file of a folder: `None` when it is not a DICOM image.
fn scan(path: &Path) -> Result<Option<ImageInfo>> {
    if !path.is_file() || !has_dicm(path)? {
        return Ok(None);
    }
    bounds::check(path)?;
    let mut obj = OpenFileOptions::new()
        .read_until(tags::PIXEL_DATA)
        .open_file(path)
        .map_err(|e| parse_error(path, &e))?;
    let ts = obj.meta().transfer_syntax().to_string();
    un::resolve(&mut obj, ts != ts::EXPLICIT_BE);
    let key = volumes::key(&obj, attrs::frame_group(&obj, 0));
    Ok(ImageInfo::from_obj(path.to_path_buf(), ts, &obj, key))
}

/// Parses a whole file (with its pixel data), its element lengths checked first, its
/// standard attributes stored as `UN` decoded (module `un`).
fn open_full(path: &Path) -> Result<DefaultDicomObject> {
    bounds::check(path)?;
    let mut obj = OpenFileOptions::new()
        .open_file(path)
        .map_err(|e| parse_error(path, &e))?;
    let big = obj.meta().transfer_syntax() == ts::EXPLICIT_BE;
    un::resolve(&mut obj, !big);
    Ok(obj)
}

/// Reads one file: a multi-frame volume (or one volume of several, `choice.timepoint`) or a
/// single slice (z = 1).
fn read_file(path: &Path, mut notes: Vec<String>, choice: VolumeChoice) -> Result<Grid> {
    if !has_dicm(path)? {
        return Err(invalid(
            path,
            "not a DICOM file (no \"DICM\" marker at byte 128)",
        ));
    }
    let info = scan(path)?.ok_or_else(|| invalid(path, "not a DICOM image (no Rows / Columns)"))?;
    pixels::check_format(&info).map_err(|k| ReadError::new(path, k))?;
    let obj = open_full(path)?;
    if let Some(n) = info.frames_stated.filter(|&n| n < 1) {
        return Err(invalid(
            path,
            format!("NumberOfFrames is {n}: a multi-frame image has at least one frame"),
        ));
    }
    if info.frames_stated.is_none() {
        if let Some(text) = attrs::string(&obj, tags::NUMBER_OF_FRAMES) {
            return Err(invalid(
                path,
                format!("NumberOfFrames {text:?} is not a number"),
            ));
        }
    }
    let frames = info.frames.max(1) as usize;
    // The pixel data must hold every frame before per-frame tables are built.
    let frame = frame_len(path, &info)?;
    let total = frame
        .checked_mul(frames as u64)
        .ok_or_else(|| invalid(path, "the pixel data size overflows"))?;
    let (bytes, fmt) = pixel_bytes(path, &obj, &info, (frames, frame), &mut notes)?;
    let described = frames::of_file(&obj, &info, frames, &mut notes);
    let positions: Vec<_> = described.iter().map(|f| f.position).collect();
    let keys: Vec<_> = described.iter().map(|f| f.key.clone()).collect();
    let rank: Vec<usize> = (0..frames).collect();
    let picked = volumes::pick(&keys, &positions, &rank, choice.timepoint)
        .map_err(|e| ReadError::new(path, e))?;
    let labels = picked
        .frames
        .iter()
        .map(|i| format!("frame {}", i + 1))
        .collect();
    let stack = order(
        path,
        &info,
        (
            picked.frames.iter().map(|&i| positions[i]).collect(),
            labels,
        ),
        vec![None; picked.frames.len()],
        "frame",
    )?;
    let chosen: Vec<usize> = stack.order.iter().map(|&k| picked.frames[k]).collect();
    let mut data = Vec::new();
    reserve(path, &mut data, total.min(frame * chosen.len() as u64))?;
    for &i in &chosen {
        let start = i as u64 * frame;
        data.extend_from_slice(
            bytes
                .get(start as usize..(start + frame) as usize)
                .unwrap_or(&[]),
        );
    }
    let rescale: Vec<_> = chosen.iter().map(|&i| described[i].rescale).collect();
    let model = image::model(path, &obj, &info, &rescale)?;
    notes.extend(picked.notes);
    notes.extend(stack.notes.iter().cloned());
    image::build(
        path,
        &info,
        &stack,
        (&data, fmt),
        &model,
        choice.component,
        picked.axis,
        notes,
    )
}

/// The samples of `frames` frames of `frame` bytes each, little-endian, and their format:
/// the pixel data itself for an uncompressed transfer syntax, else decoded (module `codec`),
/// with a note naming the transfer syntax (once per syntax); colour brought to interleaved
/// RGB (module `image`).
fn pixel_bytes<'a>(
    path: &Path,
    obj: &'a DefaultDicomObject,
    info: &ImageInfo,
    (frames, frame): (usize, u64),
    notes: &mut Vec<String>,
) -> Result<(std::borrow::Cow<'a, [u8]>, pixels::Fmt)> {
    let ts = info.transfer_syntax.as_str();
    let (bytes, fmt) = if ts::is_native(ts) {
        pixels::native(path, obj, info, frames as u64, notes)?
    } else {
        let note = ts::note(ts);
        if !notes.contains(&note) {
            notes.push(note);
        }
        let fmt = pixels::Fmt::integer(info.bits, info.signed).ok_or_else(|| {
            invalid(
                path,
                format!("BitsAllocated {} in compressed data", info.bits),
            )
        })?;
        let jpeg_color = (info.samples_per_pixel == 3 && ts::family(ts) == Some(ts::Family::Jpeg))
            .then(|| jpeg_color::needs(obj, &info.photometric))
            .transpose()
            .map_err(|m| ReadError::new(path, ErrorKind::Unsupported(m)))?;
        let mut b = codec::decode(path, obj, info, frames, frame)?;
        if jpeg_color == Some(jpeg_color::Needs::YbrToRgb) {
            color::ybr_to_rgb(&mut b);
            notes.push(format!("{} converted to RGB", info.photometric));
        }
        (std::borrow::Cow::Owned(b), fmt)
    };
    Ok((image::to_rgb(info, bytes, fmt, notes), fmt))
}

/// Orders slices or frames, mapping geometry errors to [`ErrorKind::Invalid`].
fn order(
    path: &Path,
    info: &ImageInfo,
    (positions, labels): (Vec<Option<glam::DVec3>>, Vec<String>),
    instances: Vec<Option<i64>>,
    what: &str,
) -> Result<Stack> {
    geometry::stack(&StackInput {
        what,
        labels,
        positions,
        instances,
        fallback_order: if what == "frame" {
            "frame order"
        } else {
            "InstanceNumber"
        },
        orientation: info.orientation,
        spacing_between: info.spacing_between,
        thickness: info.thickness,
    })
    .map_err(|m| invalid(path, m))
}

/// Bytes of one frame, checked.
fn frame_len(path: &Path, info: &ImageInfo) -> Result<u64> {
    match pixels::frame_bytes(info) {
        Some(0) => Err(invalid(path, "Rows or Columns is 0")),
        Some(n) => Ok(n),
        None => Err(invalid(path, "the frame size overflows")),
    }
}

/// Reserves `bytes` after checking they fit in memory.
fn reserve(path: &Path, v: &mut Vec<u8>, bytes: u64) -> Result<()> {
    volux_core::limits::check_alloc("pixel data", bytes, 1).map_err(|e| ReadError::new(path, e))?;
    v.reserve_exact(bytes as usize);
    Ok(())
}

/// Checks that every slice matches the first: size, type, format, orientation (the folder
/// module groups slices so; this guards the stack it hands over).
fn check_slices(dir: &Path, slices: &[ImageInfo]) -> Result<()> {
    let Some(first) = slices.first() else {
        return Err(invalid(dir, "the series has no slices"));
    };
    let name = |s: &ImageInfo| {
        s.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    for s in slices {
        pixels::check_format(s).map_err(|k| ReadError::new(&s.path, k))?;
        if s.frames > 1 {
            return Err(invalid(
                dir,
                format!(
                    "{:?} is a multi-frame file ({} frames) among the single-frame slices of \
                     {:?}",
                    name(s),
                    s.frames,
                    name(first)
                ),
            ));
        }
        let fields = [
            ("Rows", s.rows, first.rows),
            ("Columns", s.cols, first.cols),
            ("BitsAllocated", s.bits, first.bits),
            (
                "PixelRepresentation",
                u32::from(s.signed),
                u32::from(first.signed),
            ),
            (
                "SamplesPerPixel",
                s.samples_per_pixel,
                first.samples_per_pixel,
            ),
        ];
        let differ: Vec<String> = fields
            .iter()
            .filter(|(_, a, b)| a != b)
            .map(|(f, a, b)| format!("{f} {a} where {:?} has {b}", name(first)))
            .collect();
        if !differ.is_empty() {
            return Err(invalid(
                dir,
                format!("slices differ: {:?} has {}", name(s), differ.join(", ")),
            ));
        }
        if s.photometric != first.photometric {
            return Err(invalid(
                dir,
                format!(
                    "slices differ: {:?} has PhotometricInterpretation {} where {:?} has {}",
                    name(s),
                    s.photometric,
                    name(first),
                    first.photometric
                ),
            ));
        }
        let same_orientation = match (s.orientation, first.orientation) {
            (Some(a), Some(b)) => a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4),
            (a, b) => a.is_none() == b.is_none(),
        };
        if !same_orientation {
            return Err(invalid(
                dir,
                format!(
                    "{:?} has a different ImageOrientationPatient than {:?}",
                    name(s),
                    name(first)
                ),
            ));
        }
    }
    Ok(())
}

/// Loads the slices of one series (of one of its volumes, `choice.timepoint`) in position
/// order.
fn load_series(
    dir: &Path,
    slices: &[ImageInfo],
    mut notes: Vec<String>,
    choice: VolumeChoice,
) -> Result<Grid> {
    check_slices(dir, slices)?;
    let first = slices
        .first()
        .ok_or_else(|| invalid(dir, "the series has no slices"))?;
    let positions: Vec<_> = slices.iter().map(|s| s.position).collect();
    let keys: Vec<_> = slices.iter().map(|s| s.key.clone()).collect();
    let mut rank: Vec<usize> = (0..slices.len()).collect();
    rank.sort_by_key(|&i| (slices[i].instance.is_none(), slices[i].instance, i));
    let picked = volumes::pick(&keys, &positions, &rank, choice.timepoint)
        .map_err(|e| ReadError::new(dir, e))?;
    let part: Vec<&ImageInfo> = picked.frames.iter().map(|&i| &slices[i]).collect();
    let labels = part
        .iter()
        .map(|s| format!("{:?}", s.path.file_name().unwrap_or_default()))
        .collect();
    let stack = order(
        dir,
        first,
        (part.iter().map(|s| s.position).collect(), labels),
        part.iter().map(|s| s.instance).collect(),
        "slice",
    )?;
    let frame = frame_len(dir, first)?;
    let total = frame
        .checked_mul(part.len() as u64)
        .ok_or_else(|| invalid(dir, "the series size overflows"))?;
    let mut data = Vec::new();
    reserve(dir, &mut data, total)?;
    let mut model: Option<image::Model> = None;
    let mut values = Vec::with_capacity(part.len());
    let mut format = None;
    for s in stack.order.iter().filter_map(|&i| part.get(i)) {
        let obj = open_full(&s.path)?;
        let (bytes, fmt) = pixel_bytes(&s.path, &obj, s, (1, frame), &mut notes)?;
        if format.is_some_and(|f| f != fmt) {
            return Err(invalid(
                &s.path,
                format!("its samples are {fmt:?} where the series' first slice's are {format:?}"),
            ));
        }
        format = Some(fmt);
        data.extend_from_slice(&bytes);
        match image::model(&s.path, &obj, s, &[attrs::rescale(&obj, None)])? {
            image::Model::Mono(v) => values.extend(v),
            m => {
                if let (Some(image::Model::Palette(a)), image::Model::Palette(b)) = (&model, &m) {
                    if a != b {
                        return Err(invalid(
                            &s.path,
                            "its Palette Color LUTs differ from the series' first slice's",
                        ));
                    }
                }
                model.get_or_insert(m);
            }
        }
    }
    let model = model.unwrap_or(image::Model::Mono(values));
    notes.extend(picked.notes);
    notes.extend(stack.notes.iter().cloned());
    let fmt = format.unwrap_or(pixels::Fmt::U8);
    image::build(
        dir,
        first,
        &stack,
        (&data, fmt),
        &model,
        choice.component,
        picked.axis,
        notes,
    )
}
