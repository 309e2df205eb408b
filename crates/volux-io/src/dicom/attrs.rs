//! Attribute access on a parsed DICOM data set, functional-group aware, and the per-file
//! summary ([`ImageInfo`]) the series logic works on.
use std::path::PathBuf;

use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_object::mem::InMemElement;
use dicom_object::InMemDicomObject;
use glam::DVec3;

/// A DICOM data set (or sequence item).
pub(super) type Obj = InMemDicomObject;

fn elem(obj: &Obj, tag: Tag) -> Option<&InMemElement> {
    obj.element_opt(tag).ok().flatten()
}

/// All values of a numeric (or DS / IS string) attribute; `None` if absent, unparsable or not
/// finite.
pub(super) fn f64s(obj: &Obj, tag: Tag) -> Option<Vec<f64>> {
    elem(obj, tag)?
        .to_multi_float64()
        .ok()
        .filter(|v| !v.is_empty() && v.iter().all(|x| x.is_finite()))
}

/// The first value of a numeric attribute.
pub(super) fn f64_1(obj: &Obj, tag: Tag) -> Option<f64> {
    f64s(obj, tag)?.first().copied()
}

/// An integer attribute.
pub(super) fn int(obj: &Obj, tag: Tag) -> Option<i64> {
    elem(obj, tag)?.to_int::<i64>().ok()
}

/// A string attribute, trimmed of padding.
pub(super) fn string(obj: &Obj, tag: Tag) -> Option<String> {
    let s = elem(obj, tag)?.to_str().ok()?;
    let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!s.is_empty()).then(|| s.to_string())
}

/// The value of a private attribute: element `element` (0x00..0xFF) of the block that
/// `creator` reserved in `group` (PS3.5 7.8.1).
pub(super) fn private<'a>(
    obj: &'a Obj,
    group: u16,
    creator: &str,
    element: u8,
) -> Option<&'a InMemElement> {
    obj.private_element(group, creator, element).ok()
}

/// The items of a sequence attribute.
pub(super) fn items(obj: &Obj, tag: Tag) -> Option<&[Obj]> {
    elem(obj, tag)?.items()
}

/// Looks `f` up in `seq` of the per-frame group, then of the shared group, then at the top
/// level of `obj` (enhanced multi-frame files keep most attributes in functional groups).
pub(super) fn grouped<T>(
    obj: &Obj,
    frame: Option<&Obj>,
    seq: Tag,
    f: impl Fn(&Obj) -> Option<T>,
) -> Option<T> {
    let shared = items(obj, tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|i| i.first());
    [frame, shared]
        .into_iter()
        .flatten()
        .filter_map(|g| items(g, seq).and_then(|i| i.first()))
        .find_map(&f)
        .or_else(|| f(obj))
}

/// The per-frame functional group of frame `i`, if the file has them.
pub(super) fn frame_group(obj: &Obj, i: usize) -> Option<&Obj> {
    items(obj, tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|g| g.get(i))
}

/// ImagePositionPatient of a data set or plane-position item.
pub(super) fn position(o: &Obj) -> Option<DVec3> {
    match f64s(o, tags::IMAGE_POSITION_PATIENT)?.as_slice() {
        [x, y, z, ..] => Some(DVec3::new(*x, *y, *z)),
        _ => None,
    }
}

/// `(RescaleSlope, RescaleIntercept)` of frame `i` (default (1, 0)).
pub(super) fn rescale(obj: &Obj, frame: Option<&Obj>) -> (f64, f64) {
    let seq = tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE;
    let slope = grouped(obj, frame, seq, |o| f64_1(o, tags::RESCALE_SLOPE));
    let inter = grouped(obj, frame, seq, |o| f64_1(o, tags::RESCALE_INTERCEPT));
    (slope.unwrap_or(1.0), inter.unwrap_or(0.0))
}

/// What tells a frame apart from others at the same position (module `volumes` reads it).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct VolumeKey {
    /// TemporalPositionIndex or TemporalPositionIdentifier.
    pub temporal: Option<i64>,
    /// DiffusionBValue (s/mm²).
    pub b_value: Option<f64>,
    /// DiffusionGradientOrientation.
    pub gradient: Option<[f64; 3]>,
    /// StackID.
    pub stack: Option<String>,
}

/// What the reader needs from one DICOM image file (of its first frame for multi-frame files).
#[derive(Clone, Debug)]
pub(super) struct ImageInfo {
    pub path: PathBuf,
    pub transfer_syntax: String,
    pub series_uid: String,
    pub rows: u32,
    pub cols: u32,
    pub bits: u32,
    /// BitsStored (0 when absent: all of BitsAllocated).
    pub bits_stored: u32,
    pub signed: bool,
    pub samples_per_pixel: u32,
    pub photometric: String,
    pub frames: u32,
    /// NumberOfFrames as the file states it (`None`: absent), to tell a missing count from
    /// an invalid one.
    pub frames_stated: Option<i64>,
    pub position: Option<DVec3>,
    pub orientation: Option<[f64; 6]>,
    pub instance: Option<i64>,
    /// PixelSpacing: `[row spacing (y), column spacing (x)]`.
    pub pixel_spacing: Option<[f64; 2]>,
    pub spacing_between: Option<f64>,
    pub thickness: Option<f64>,
    pub rescale: (f64, f64),
    /// PlanarConfiguration 1: each colour plane of a frame after the other (PS3.3
    /// C.7.6.3.1.3); 0 (default): the samples of each pixel together.
    pub planar: bool,
    /// DoseGridScaling of an RT Dose (PS3.3 C.8.8.3): the factor giving Gy.
    pub dose_scaling: Option<f64>,
    /// What tells this image (its first frame) apart from others at the same position.
    pub key: VolumeKey,
}

impl ImageInfo {
    /// Summarises `obj`, whose first frame `key` tells apart from others at its position;
    /// `None` when it is not an image (no Rows / Columns), e.g. a DICOMDIR.
    pub fn from_obj(
        path: PathBuf,
        transfer_syntax: String,
        obj: &Obj,
        key: VolumeKey,
    ) -> Option<Self> {
        let u32_of = |tag| int(obj, tag).and_then(|v| u32::try_from(v).ok());
        let frame0 = frame_group(obj, 0);
        let measures = tags::PIXEL_MEASURES_SEQUENCE;
        Some(Self {
            path,
            transfer_syntax,
            series_uid: string(obj, tags::SERIES_INSTANCE_UID).unwrap_or_default(),
            rows: u32_of(tags::ROWS)?,
            cols: u32_of(tags::COLUMNS)?,
            bits: u32_of(tags::BITS_ALLOCATED).unwrap_or(0),
            bits_stored: u32_of(tags::BITS_STORED).unwrap_or(0),
            signed: int(obj, tags::PIXEL_REPRESENTATION) == Some(1),
            samples_per_pixel: u32_of(tags::SAMPLES_PER_PIXEL).unwrap_or(1),
            photometric: string(obj, tags::PHOTOMETRIC_INTERPRETATION).unwrap_or_default(),
            frames: u32_of(tags::NUMBER_OF_FRAMES).unwrap_or(1),
            frames_stated: int(obj, tags::NUMBER_OF_FRAMES),
            position: grouped(obj, frame0, tags::PLANE_POSITION_SEQUENCE, position),
            orientation: grouped(obj, frame0, tags::PLANE_ORIENTATION_SEQUENCE, |o| {
                f64s(o, tags::IMAGE_ORIENTATION_PATIENT)?.try_into().ok()
            }),
            instance: int(obj, tags::INSTANCE_NUMBER),
            pixel_spacing: grouped(obj, frame0, measures, |o| {
                match f64s(o, tags::PIXEL_SPACING)?.as_slice() {
                    [r, c, ..] if *r > 0.0 && *c > 0.0 => Some([*r, *c]),
                    _ => None,
                }
            }),
            spacing_between: grouped(obj, frame0, measures, |o| {
                f64_1(o, tags::SPACING_BETWEEN_SLICES).filter(|v| *v > 0.0)
            }),
            thickness: grouped(obj, frame0, measures, |o| {
                f64_1(o, tags::SLICE_THICKNESS).filter(|v| *v > 0.0)
            }),
            rescale: rescale(obj, frame0),
            planar: int(obj, tags::PLANAR_CONFIGURATION) == Some(1),
            dose_scaling: f64_1(obj, tags::DOSE_GRID_SCALING),
            key,
        })
    }
}
