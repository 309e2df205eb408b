//! DICOM folders as scanners and PACS export them: one series picked among several, files that
//! do not belong to it (damaged, unsupported, secondary captures, localizers, other series) set
//! aside with a note, and DICOMDIR media directories followed.
//!
//! - Every entry with the `DICM` marker is scanned (its header, up to the pixel data); other
//!   files (a JSON sidecar, a text file) pass quietly, empty files and folders are noted. A
//!   file that cannot be parsed is skipped and named in a note (count, first names, first
//!   reason); one whose header reads but whose pixel data does not (cut short) keeps its
//!   series and position, so that it is known where it was.
//! - Series: files are grouped by SeriesInstanceUID; the requested series (`--series`), else
//!   the one with the most readable slices, is loaded. Files of the other series are named in
//!   a note.
//! - Stacks: the series' readable single-frame slices are grouped by Rows, Columns,
//!   BitsAllocated, PixelRepresentation, SamplesPerPixel, PhotometricInterpretation and
//!   ImageOrientationPatient (a series may hold
//!   localizers in three planes, or a secondary capture); the largest group is loaded, the
//!   others are named in a note by orientation (patient-axis letters), size and position
//!   range. Unsupported files, and multi-frame files among single-frame
//!   slices, are set aside the same way.
//! - Gaps: a stack whose slice gaps exceed 1.5 times the median, or with a file of the same
//!   orientation set aside inside its position range (a truncated slice, one of other Rows),
//!   is refused ([`ErrorKind::Invalid`]): the message names the sub-series it splits into by
//!   position range and files, and what is missing.
//! - DICOMDIR (PS3.10 media storage directory, SOP class 1.2.840.10008.1.3.10): opening the
//!   DICOMDIR file, or a folder holding one, reads the files its directory records reference
//!   (ReferencedFileID, relative to the DICOMDIR's folder; a component that is empty, `.`,
//!   `..` or holds a separator is refused), then proceeds as for a folder.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use dicom_dictionary_std::tags;
use dicom_object::OpenFileOptions;
use glam::{DMat3, DVec3};

use super::attrs::{self, ImageInfo};
use super::files::{has_dicm, invalid, parse_error, skipped_note};
use super::{bounds, pixels, ts, un, volumes};
use crate::error::{ErrorKind, ReadError, Result};

/// The Media Storage Directory SOP class (a DICOMDIR).
const DICOMDIR_CLASS: &str = "1.2.840.10008.1.3.10";
/// How many file names (or stacks) a note lists before "and N more".
const NAMES: usize = 3;
/// How many series the note on the other series lists.
const SERIES_LISTED: usize = 5;
/// Orientation cosines closer than this are the same orientation.
const SAME_ORIENTATION: f64 = 1e-4;
/// Positions closer than this (mm) along the normal are the same.
const SAME_POSITION_MM: f64 = 1e-3;
/// A gap larger than this many median gaps means a missing slice.
const MISSING_GAP_RATIO: f64 = 1.5;

/// What a folder or DICOMDIR reading chose to load, with the notes on what it set aside.
pub(super) enum Picked {
    /// One multi-frame file (an enhanced image).
    File { path: PathBuf, notes: Vec<String> },
    /// A stack of single-frame slices of one series (`dir`: the folder or DICOMDIR).
    Slices {
        dir: PathBuf,
        slices: Vec<ImageInfo>,
        notes: Vec<String>,
    },
}

/// One DICOM file of a folder: its header summary when readable, and why it cannot be read
/// when it cannot (a file cut inside its pixel data has both).
struct Scanned {
    path: PathBuf,
    info: Option<ImageInfo>,
    error: Option<ReadError>,
}

/// The file name of `p`, for messages.
fn name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The first names of `paths` and how many more there are: `a.dcm, b.dcm, c.dcm and 4 more`.
fn names<'a>(paths: impl IntoIterator<Item = &'a Path>) -> String {
    let all: Vec<String> = paths.into_iter().map(name).collect();
    let mut s = all
        .iter()
        .take(NAMES)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if all.len() > NAMES {
        s.push_str(&format!(" and {} more", all.len() - NAMES));
    }
    s
}

fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

/// Whether `path` is a DICOMDIR: named so, or of the Media Storage Directory SOP class.
pub(super) fn is_dicomdir(path: &Path) -> bool {
    if path
        .file_name()
        .is_some_and(|n| n.eq_ignore_ascii_case("DICOMDIR"))
    {
        return true;
    }
    let Ok(f) = crate::util::open_regular(path) else {
        return false;
    };
    let mut r = std::io::BufReader::new(f);
    use std::io::{Seek, SeekFrom};
    if r.seek(SeekFrom::Start(128)).is_err() {
        return false;
    }
    dicom_object::meta::FileMetaTable::from_reader(r)
        .is_ok_and(|m| m.media_storage_sop_class_uid().trim_end_matches('\0') == DICOMDIR_CLASS)
}

/// Reads a folder: through its DICOMDIR when it has one, else its entries.
pub(super) fn read_folder(dir: &Path, series_uid: Option<&str>) -> Result<Picked> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| ReadError::new(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let mut notes = Vec::new();
    if let Some(dd) = entries.iter().find(|p| {
        p.is_file()
            && p.file_name()
                .is_some_and(|n| n.eq_ignore_ascii_case("DICOMDIR"))
    }) {
        // A DICOMDIR that cannot be followed does not hide the folder's own files.
        match dicomdir_listing(dd) {
            Ok((files, dd_notes)) => return read_files(dd, &files, series_uid, dd_notes),
            Err(e) => notes.push(format!(
                "the DICOMDIR cannot be followed ({}); the folder's files were scanned instead",
                e.kind
            )),
        }
    }
    read_files(dir, &entries, series_uid, notes)
}

/// Reads the series a DICOMDIR references.
pub(super) fn read_dicomdir(path: &Path, series_uid: Option<&str>) -> Result<Picked> {
    let (files, notes) = dicomdir_listing(path)?;
    read_files(path, &files, series_uid, notes)
}

/// The files a DICOMDIR references that exist, and the notes saying so; an error when it
/// cannot be read or references no existing file.
fn dicomdir_listing(path: &Path) -> Result<(Vec<PathBuf>, Vec<String>)> {
    let base = path.parent().unwrap_or(Path::new("."));
    let (files, missing) = dicomdir_files(path, base)?;
    let mut notes = vec![format!(
        "read through the DICOMDIR {:?} ({} referenced)",
        name(path),
        plural(files.len() + missing.len(), "file")
    )];
    if !missing.is_empty() {
        notes.push(format!(
            "skipped {} the DICOMDIR references but the folder lacks: {}",
            plural(missing.len(), "file"),
            names(missing.iter().map(PathBuf::as_path))
        ));
    }
    if files.is_empty() {
        return Err(invalid(
            path,
            format!(
                "the DICOMDIR references no file that exists ({} listed)",
                missing.len()
            ),
        ));
    }
    Ok((files, notes))
}

/// The files a DICOMDIR's directory records reference (ReferencedFileID under `base`): those
/// present, and those missing.
fn dicomdir_files(path: &Path, base: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>)> {
    if !has_dicm(path)? {
        return Err(invalid(
            path,
            "a DICOMDIR without the \"DICM\" marker at byte 128",
        ));
    }
    bounds::check(path)?;
    let obj = OpenFileOptions::new()
        .open_file(path)
        .map_err(|e| parse_error(path, &e))?;
    let records = attrs::items(&obj, tags::DIRECTORY_RECORD_SEQUENCE).ok_or_else(|| {
        invalid(
            path,
            "a DICOMDIR without a DirectoryRecordSequence (0004,1220)",
        )
    })?;
    let (mut found, mut missing) = (Vec::new(), Vec::new());
    for r in records {
        let Some(id) = r
            .element_opt(tags::REFERENCED_FILE_ID)
            .ok()
            .flatten()
            .and_then(|e| e.to_multi_str().ok())
        else {
            continue;
        };
        let mut p = base.to_path_buf();
        for c in id.iter() {
            let c = c.trim_matches(|ch: char| ch == '\0' || ch == ' ');
            if c.is_empty() || c == "." || c == ".." || c.contains(['/', '\\']) {
                return Err(invalid(
                    path,
                    format!(
                        "ReferencedFileID {:?} has a component {c:?} that is not a plain name",
                        id.join("\\")
                    ),
                ));
            }
            p.push(c);
        }
        if found.contains(&p) || missing.contains(&p) {
            continue;
        }
        if p.is_file() {
            found.push(p);
        } else {
            missing.push(p);
        }
    }
    Ok((found, missing))
}

/// Scans one entry: `None` for what is not a DICOM image (another file, a folder, a
/// non-image DICOM object); otherwise its header and, if it cannot be read whole, why.
fn scan(path: &Path) -> Option<Scanned> {
    if !path.is_file() {
        return None;
    }
    let fail = |e| {
        Some(Scanned {
            path: path.to_path_buf(),
            info: None,
            error: Some(e),
        })
    };
    match has_dicm(path) {
        Ok(false) => return None,
        Err(e) => return fail(e),
        Ok(true) => {}
    }
    let whole = bounds::check(path).err();
    if whole.is_some() {
        if let Err(e) = bounds::check_header(path) {
            return fail(e);
        }
    }
    let mut obj = match OpenFileOptions::new()
        .read_until(tags::PIXEL_DATA)
        .open_file(path)
    {
        Ok(o) => o,
        Err(e) => return fail(whole.unwrap_or_else(|| parse_error(path, &e))),
    };
    let ts = obj.meta().transfer_syntax().to_string();
    un::resolve(&mut obj, ts != ts::EXPLICIT_BE);
    let key = volumes::key(&obj, attrs::frame_group(&obj, 0));
    let info = ImageInfo::from_obj(path.to_path_buf(), ts, &obj, key)?;
    Some(Scanned {
        path: path.to_path_buf(),
        info: Some(info),
        error: whole,
    })
}

/// Why a scanned file of the chosen series is not a slice of the stack; `None` when it is
/// one.
fn set_aside(s: &Scanned) -> Option<String> {
    if let Some(e) = &s.error {
        return Some(format!("cannot be read: {}", e.kind));
    }
    let info = s.info.as_ref()?;
    if let Err(k) = pixels::check_format(info) {
        return Some(k.to_string());
    }
    (info.frames > 1).then(|| format!("a multi-frame file of {} frames", info.frames))
}

/// The stack key of a slice: size, type and orientation (compared with a tolerance).
fn same_stack(a: &ImageInfo, b: &ImageInfo) -> bool {
    let shape = |s: &ImageInfo| (s.rows, s.cols, s.bits, s.signed, s.samples_per_pixel);
    shape(a) == shape(b)
        && a.photometric == b.photometric
        && same_orientation(a.orientation, b.orientation)
}

fn same_orientation(a: Option<[f64; 6]>, b: Option<[f64; 6]>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => a
            .iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() < SAME_ORIENTATION),
        (a, b) => a.is_none() == b.is_none(),
    }
}

/// The unit slice normal of an orientation (`None` without one, or degenerate).
fn normal(o: Option<[f64; 6]>) -> Option<DVec3> {
    let o = o?;
    let n = DVec3::new(o[0], o[1], o[2]).cross(DVec3::new(o[3], o[4], o[5]));
    (n.length() > 1e-6).then(|| n.normalize())
}

/// `AXIAL`-like words for an orientation: its patient-axis letters (LPS, PIR...), or "no
/// orientation".
fn orientation_name(o: Option<[f64; 6]>) -> String {
    match (o, normal(o)) {
        (Some(o), Some(n)) => {
            let d = DMat3::from_cols(
                DVec3::new(o[0], o[1], o[2]),
                DVec3::new(o[3], o[4], o[5]),
                n,
            );
            format!(
                "orientation {}",
                volux_core::orientation::orientation_code(&d)
            )
        }
        _ => "no orientation".into(),
    }
}

/// Describes a group of slices: count, size, orientation, position range and first / last
/// files (in position order where positions are known).
fn describe(slices: &[&ImageInfo]) -> String {
    let Some(first) = slices.first() else {
        return "no slices".into();
    };
    let n = normal(first.orientation).unwrap_or(DVec3::Z);
    let mut at: Vec<(Option<f64>, &Path)> = slices
        .iter()
        .map(|s| (s.position.map(|p| p.dot(n)), s.path.as_path()))
        .collect();
    at.sort_by(|a, b| a.0.unwrap_or(0.0).total_cmp(&b.0.unwrap_or(0.0)));
    let range = match (at.first(), at.last()) {
        (Some((Some(lo), _)), Some((Some(hi), _))) if at.iter().all(|a| a.0.is_some()) => {
            if (hi - lo).abs() < SAME_POSITION_MM {
                format!(" at {lo:.4} mm")
            } else {
                format!(" at {lo:.4}..{hi:.4} mm")
            }
        }
        _ => String::new(),
    };
    let files = match (at.first(), at.last()) {
        (Some(a), Some(b)) if at.len() > 1 => format!("{}..{}", name(a.1), name(b.1)),
        (Some(a), _) => name(a.1),
        _ => String::new(),
    };
    format!(
        "{} of {} x {}, {}{range} ({files})",
        plural(slices.len(), "slice"),
        first.cols,
        first.rows,
        orientation_name(first.orientation)
    )
}

/// Reads the DICOM images among `files` (the entries of `dir`, or the files a DICOMDIR
/// references), groups them by series and loads one stack.
fn read_files(
    dir: &Path,
    files: &[PathBuf],
    series_uid: Option<&str>,
    mut notes: Vec<String>,
) -> Result<Picked> {
    let mut scanned = Vec::new();
    let mut quiet = Vec::new();
    for p in files {
        match scan(p) {
            Some(s) => scanned.push(s),
            None => quiet.push(p.as_path()),
        }
    }
    // Files whose header cannot be read: no series, no position.
    let (broken, scanned): (Vec<Scanned>, Vec<Scanned>) =
        scanned.into_iter().partition(|s| s.info.is_none());
    let broken_note = (!broken.is_empty()).then(|| {
        let first = broken
            .first()
            .and_then(|b| b.error.as_ref())
            .map(|e| format!("; {}: {}", name(&e.path), e.kind))
            .unwrap_or_default();
        format!(
            "skipped {} that cannot be read as DICOM: {}{first}",
            plural(broken.len(), "file"),
            names(broken.iter().map(|b| b.path.as_path()))
        )
    });
    let mut series: BTreeMap<String, Vec<Scanned>> = BTreeMap::new();
    for s in scanned {
        let uid = s
            .info
            .as_ref()
            .map(|i| i.series_uid.clone())
            .unwrap_or_default();
        series.entry(uid).or_default().push(s);
    }
    if series.is_empty() {
        return Err(match broken.into_iter().next().and_then(|b| b.error) {
            // One damaged file and nothing else: its own error.
            Some(e) if files.len() == 1 => e,
            Some(e) => invalid(
                dir,
                format!(
                    "no readable DICOM image files in this folder ({} entries looked at); {}: \
                     {}",
                    files.len(),
                    name(&e.path),
                    e.kind
                ),
            ),
            None => invalid(
                dir,
                format!(
                    "no DICOM image files in this folder ({} entries looked at)",
                    files.len()
                ),
            ),
        });
    }
    let list = |with_names: bool| {
        let shown = if with_names {
            SERIES_LISTED
        } else {
            usize::MAX
        };
        let mut l = series
            .iter()
            .take(shown)
            .map(|(k, v)| {
                if with_names {
                    format!(
                        "{k} ({}: {})",
                        plural(v.len(), "file"),
                        names(v.iter().map(|s| s.path.as_path()))
                    )
                } else {
                    format!("{k} ({})", plural(v.len(), "file"))
                }
            })
            .collect::<Vec<_>>()
            .join(", ");
        if series.len() > shown {
            l.push_str(&format!(" and {} more", series.len() - shown));
        }
        l
    };
    let usable = |v: &[Scanned]| v.iter().filter(|s| set_aside(s).is_none()).count();
    let chosen = match series_uid {
        Some(u) => u.to_string(),
        None => series
            .iter()
            .max_by_key(|(k, v)| (usable(v), v.len(), std::cmp::Reverse((*k).clone())))
            .map(|(k, _)| k.clone())
            .unwrap_or_default(),
    };
    if !series.contains_key(&chosen) {
        let extra = broken_note
            .as_ref()
            .map(|n| format!(" ({n})"))
            .unwrap_or_default();
        return Err(invalid(
            dir,
            format!(
                "series {chosen} is not in this folder; available: {}{extra}",
                list(false)
            ),
        ));
    }
    if series.len() > 1 {
        let others = list(true);
        notes.push(if series_uid.is_none() {
            format!(
                "{} series in this folder ({others}); loaded {chosen}, the one with the most \
                 readable files",
                series.len()
            )
        } else {
            format!(
                "{} series in this folder ({others}); loaded {chosen}",
                series.len()
            )
        });
    }
    notes.extend(broken_note);
    notes.extend(skipped_note(&quiet));
    let members = series.remove(&chosen).unwrap_or_default();
    load_stack(dir, &chosen, members, notes)
}

/// Splits the files of one series into stacks, loads the largest and notes the rest.
fn load_stack(
    dir: &Path,
    uid: &str,
    members: Vec<Scanned>,
    mut notes: Vec<String>,
) -> Result<Picked> {
    let (good, aside): (Vec<&Scanned>, Vec<&Scanned>) =
        members.iter().partition(|s| set_aside(s).is_none());
    // A series of one multi-frame file (an enhanced image) is that file's frames.
    let multi: Vec<&Scanned> = members
        .iter()
        .filter(|s| s.error.is_none() && s.info.as_ref().is_some_and(|i| i.frames > 1))
        .collect();
    if good.is_empty() {
        if let Some(m) = multi
            .iter()
            .filter(|m| {
                m.info
                    .as_ref()
                    .is_some_and(|i| pixels::check_format(i).is_ok())
            })
            .max_by_key(|m| m.info.as_ref().map_or(0, |i| i.frames))
        {
            let rest: Vec<&Path> = members
                .iter()
                .filter(|s| s.path != m.path)
                .map(|s| s.path.as_path())
                .collect();
            if !rest.is_empty() {
                notes.push(format!(
                    "series {uid}: loaded the multi-frame file {:?}; not loaded: {}",
                    name(&m.path),
                    names(rest)
                ));
            }
            return Ok(Picked::File {
                path: m.path.clone(),
                notes,
            });
        }
        // Nothing readable: the first file's own error (a colour image, a truncated file).
        let first = members.first();
        return Err(match first {
            Some(s) => match (&s.error, &s.info) {
                (Some(e), _) => ReadError::new(&e.path, clone_kind(&e.kind)),
                (None, Some(i)) => match pixels::check_format(i) {
                    Err(k) => ReadError::new(&s.path, k),
                    Ok(()) => invalid(&s.path, "not a readable slice"),
                },
                (None, None) => invalid(&s.path, "not a readable slice"),
            },
            None => invalid(dir, format!("series {uid} has no files")),
        });
    }
    // Stacks: slices of the same size, type and orientation.
    let mut stacks: Vec<Vec<&ImageInfo>> = Vec::new();
    for s in &good {
        let Some(info) = s.info.as_ref() else {
            continue;
        };
        match stacks.iter_mut().find(|g| same_stack(g[0], info)) {
            Some(g) => g.push(info),
            None => stacks.push(vec![info]),
        }
    }
    let best = (0..stacks.len())
        .max_by_key(|&i| (stacks[i].len(), std::cmp::Reverse(i)))
        .unwrap_or(0);
    let stack = stacks.remove(best);
    stacks.sort_by_key(|g| std::cmp::Reverse(g.len()));
    let first = stack[0];
    // Everything else of the series, and why.
    let mut left: Vec<(&Scanned, String)> = aside
        .iter()
        .map(|s| (*s, set_aside(s).unwrap_or_default()))
        .collect();
    for other in &stacks {
        for i in other {
            if let Some(s) = members.iter().find(|s| s.path == i.path) {
                let why = if i.photometric != first.photometric {
                    format!(
                        "is {} where the stack's slices are {}",
                        i.photometric, first.photometric
                    )
                } else if same_orientation(i.orientation, first.orientation) {
                    format!(
                        "has Rows {} Columns {} BitsAllocated {}{} where the stack's slices \
                         have Rows {} Columns {} BitsAllocated {}{}",
                        i.rows,
                        i.cols,
                        i.bits,
                        if i.signed { " (signed)" } else { "" },
                        first.rows,
                        first.cols,
                        first.bits,
                        if first.signed { " (signed)" } else { "" },
                    )
                } else {
                    format!(
                        "is in another plane ({}; the stack's is {})",
                        orientation_name(i.orientation),
                        orientation_name(first.orientation)
                    )
                };
                left.push((s, why));
            }
        }
    }
    check_holes(dir, uid, &stack, &left)?;
    check_gaps(dir, uid, &stack)?;
    if !stacks.is_empty() {
        let mut d: Vec<String> = stacks.iter().take(NAMES).map(|g| describe(g)).collect();
        if stacks.len() > NAMES {
            d.push(format!("{} more", stacks.len() - NAMES));
        }
        notes.push(format!(
            "series {uid} also holds {} of another orientation or size, not loaded: {}",
            plural(stacks.len(), "stack"),
            d.join("; ")
        ));
    }
    let aside_named: Vec<&(&Scanned, String)> = left
        .iter()
        .filter(|(s, _)| !stacks.iter().flatten().any(|i| i.path == s.path))
        .collect();
    if let Some((s, why)) = aside_named.first() {
        notes.push(format!(
            "series {uid}: {} not loaded: {} ({}: {why})",
            plural(aside_named.len(), "file"),
            names(aside_named.iter().map(|(s, _)| s.path.as_path())),
            name(&s.path)
        ));
    }
    let slices: Vec<ImageInfo> = stack.into_iter().cloned().collect();
    Ok(Picked::Slices {
        dir: dir.to_path_buf(),
        slices,
        notes,
    })
}

/// A copy of an error kind (the kinds the scan records; an I/O error keeps its message).
fn clone_kind(k: &ErrorKind) -> ErrorKind {
    match k {
        ErrorKind::Truncated { expected, found } => ErrorKind::Truncated {
            expected: *expected,
            found: *found,
        },
        ErrorKind::Unsupported(m) => ErrorKind::Unsupported(m.clone()),
        ErrorKind::Invalid(m) => ErrorKind::Invalid(m.clone()),
        other => ErrorKind::Invalid(other.to_string()),
    }
}

/// Position of each slice along `n`, when all have one.
fn along(stack: &[&ImageInfo], n: DVec3) -> Option<Vec<f64>> {
    stack.iter().map(|s| s.position.map(|p| p.dot(n))).collect()
}

/// Refuses a stack with a file of its plane set aside inside its position range (a slice
/// that cannot be read, or of other Rows / Columns): the stack would have a hole there.
fn check_holes(
    dir: &Path,
    uid: &str,
    stack: &[&ImageInfo],
    left: &[(&Scanned, String)],
) -> Result<()> {
    let first = stack[0];
    let Some(n) = normal(first.orientation) else {
        return Ok(());
    };
    let Some(z) = along(stack, n) else {
        return Ok(());
    };
    let lo = z.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    for (s, why) in left {
        let Some(info) = &s.info else { continue };
        if !same_orientation(info.orientation, first.orientation) {
            continue;
        }
        let Some(at) = info.position.map(|p| p.dot(n)) else {
            continue;
        };
        if at > lo + SAME_POSITION_MM && at < hi - SAME_POSITION_MM {
            let below: Vec<&ImageInfo> = stack
                .iter()
                .zip(&z)
                .filter(|(_, &v)| v < at)
                .map(|(s, _)| *s)
                .collect();
            let above: Vec<&ImageInfo> = stack
                .iter()
                .zip(&z)
                .filter(|(_, &v)| v > at)
                .map(|(s, _)| *s)
                .collect();
            return Err(invalid(
                dir,
                format!(
                    "series {uid}: {:?} {why}, and lies inside the stack at {at:.4} mm: without \
                     it a slice is missing; the series splits into {} and {}",
                    name(&s.path),
                    describe(&below),
                    describe(&above)
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a stack with a gap over [`MISSING_GAP_RATIO`] times the median gap, naming the
/// sub-series the gaps split it into.
fn check_gaps(dir: &Path, uid: &str, stack: &[&ImageInfo]) -> Result<()> {
    let n = normal(stack[0].orientation).unwrap_or(DVec3::Z);
    let Some(z) = along(stack, n) else {
        return Ok(());
    };
    let mut order: Vec<usize> = (0..stack.len()).collect();
    order.sort_by(|&a, &b| z[a].total_cmp(&z[b]));
    let gaps: Vec<f64> = order.windows(2).map(|w| z[w[1]] - z[w[0]]).collect();
    let mut sorted = gaps.clone();
    sorted.sort_by(f64::total_cmp);
    let m = sorted.len() / 2;
    // The median as the stack ordering computes it (the mean of the middle two).
    let median = match sorted.len() {
        0 => return Ok(()),
        l if l % 2 == 1 => sorted[m],
        _ => (sorted[m - 1] + sorted[m]) / 2.0,
    };
    if sorted.first().is_some_and(|&g| g < SAME_POSITION_MM) {
        return Ok(()); // duplicates: the stack ordering names them
    }
    let cuts: Vec<usize> = gaps
        .iter()
        .enumerate()
        .filter(|(_, &g)| g > MISSING_GAP_RATIO * median)
        .map(|(i, _)| i)
        .collect();
    let Some(&c) = cuts.first() else {
        return Ok(());
    };
    let mut parts = Vec::new();
    let mut start = 0;
    for &cut in cuts.iter().chain(std::iter::once(&(order.len() - 1))) {
        let part: Vec<&ImageInfo> = order[start..=cut].iter().map(|&i| stack[i]).collect();
        parts.push(describe(&part));
        start = cut + 1;
    }
    Err(invalid(
        dir,
        format!(
            "series {uid}: a slice is missing: the gap of {:.4} mm between {:?} and {:?} is \
             {:.2} times the median gap {median:.4} mm; the series splits into {}",
            gaps[c],
            name(&stack[order[c]].path),
            name(&stack[order[c + 1]].path),
            gaps[c] / median,
            parts.join(" and ")
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(name: &str, rows: u32, z: f64) -> ImageInfo {
        ImageInfo {
            path: name.into(),
            transfer_syntax: super::super::ts::EXPLICIT_LE.into(),
            series_uid: "1.2".into(),
            rows,
            cols: 32,
            bits: 16,
            bits_stored: 12,
            signed: false,
            samples_per_pixel: 1,
            photometric: "MONOCHROME2".into(),
            frames: 1,
            frames_stated: None,
            position: Some(DVec3::new(0.0, 0.0, z)),
            orientation: Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            instance: None,
            pixel_spacing: None,
            spacing_between: None,
            thickness: None,
            rescale: (1.0, 0.0),
            planar: false,
            dose_scaling: None,
            key: Default::default(),
        }
    }

    /// The stack check names two different files and the field that differs (it once named
    /// the first file twice, with the same values).
    #[test]
    fn differing_slices_name_two_files_and_the_field() {
        let s = [slice("a.dcm", 32, 0.0), slice("b.dcm", 16, 1.0)];
        let e = super::super::check_slices(Path::new("dir"), &s).unwrap_err();
        assert_eq!(
            e.to_string(),
            "dir: slices differ: \"b.dcm\" has Rows 16 where \"a.dcm\" has 32"
        );
        let mut m = slice("m.dcm", 32, 2.0);
        m.frames = 4;
        let e = super::super::check_slices(Path::new("dir"), &[s[0].clone(), m]).unwrap_err();
        assert!(
            e.to_string()
                .contains("\"m.dcm\" is a multi-frame file (4 frames)"),
            "{e}"
        );
    }

    #[test]
    fn describe_names_count_size_orientation_range_and_files() {
        let (a, b, c) = (
            slice("a.dcm", 32, 4.0),
            slice("b.dcm", 32, -2.0),
            slice("c.dcm", 32, 1.0),
        );
        assert_eq!(
            describe(&[&a, &b, &c]),
            "3 slices of 32 x 32, orientation LPS at -2.0000..4.0000 mm (b.dcm..a.dcm)"
        );
        let mut n = slice("n.dcm", 16, 0.0);
        n.orientation = None;
        n.position = None;
        assert_eq!(
            describe(&[&n]),
            "1 slice of 32 x 16, no orientation (n.dcm)"
        );
        assert_eq!(
            names(["a", "b", "c", "d", "e"].iter().map(Path::new)),
            "a, b, c and 2 more"
        );
    }
}
