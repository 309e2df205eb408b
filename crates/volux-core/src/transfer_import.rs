//! Transfer functions written by other programs, read into a [`TransferFunction`]:
//!
//! - **ParaView presets** ("Save preset", `.json`): a JSON array of presets or one preset
//!   object, as ParaView's `vtkSMTransferFunctionPresets` writes them (and its
//!   `Remoting/Views/ColorMaps.json`): `RGBPoints` (flat `[x, r, g, b, ...]`), optional
//!   `Points` (flat `[x, opacity, midpoint, sharpness, ...]`, the scalar opacity), `ColorSpace`,
//!   `Name`, `NanColor`; other fields are ignored. [`from_paraview_json`].
//! - **3D Slicer volume properties** (`.vp`, `vtkMRMLVolumePropertyStorageNode`): nine text
//!   lines, read in the order of Slicer's `ReadDataInternal`: interpolation type, shade,
//!   diffuse, ambient, specular, specular power, then the scalar opacity, gradient opacity and
//!   colour transfer as `vtkMRMLVolumePropertyNode::DataToString` writes them: `N v1 ... vN`,
//!   `N` the count of numbers that follow (`x y` pairs, `x r g b` quadruples).
//!   [`from_slicer_vp`].
//!
//! # What the result means
//!
//! VTK interpolates the scalar opacity `alpha(x)` between nodes (`vtkPiecewiseFunction::
//! GetTable`: linear for midpoint 0.5 / sharpness 0, the midpoint-shifted Hermite curve
//! otherwise, a step for sharpness > 0.99) and reads it as the opacity of a slab one
//! `ScalarOpacityUnitDistance` thick: extinction `-ln(1 - alpha(x)) / unit`. Neither file stores
//! the unit distance, so the result uses 1 world unit (`unit_length = 1`, `opacity_step = 1`;
//! set another with [`TransferFunction::with_unit_length`]; ParaView's own default is the
//! data's approximate cell length). Volux interpolates *extinction* linearly between its
//! points, so the VTK curve is sampled: every VTK node is kept and points are added by
//! bisection until the opacity per unit distance of the result is within [`TOLERANCE`] of
//! VTK's at every check point (exact at the nodes; 1e-4 everywhere is what the tests check).
//!
//! Colours in VTK and ParaView are display values, interpolated as they are and written to
//! the screen without a transfer curve, i.e. sRGB-encoded. Volux's colours are linear RGB
//! (the PNG writer encodes to sRGB), so each colour is decoded with the sRGB curve, and the
//! colour curve is sampled the same way until the re-encoded colour is within [`TOLERANCE`]
//! of VTK's display value. `ColorSpace` is interpolated as `vtkColorTransferFunction::
//! GetTable` does ([`ColorSpace`], [`vtk_color_value`]; missing counts as `"RGB"`, with a
//! note): `"RGB"`; `"HSV"` with the hue the short way round (VTK's default `HSVWrap`);
//! `"Lab"` (and `"CIELAB"`) in CIE L*a*b* with `vtkMath`'s conversions (D65 white
//! 0.9505/1/1.089, out-of-gamut colours scaled and clamped); `"Diverging"`, Moreland's Msh
//! interpolation (white of magnitude 88 or more between two distinct saturated colours, the
//! hue of an unsaturated end adjusted, the hue along the signed shorter angle as current VTK
//! does); `"Step"`, where VTK gives each segment the colour of its *right* node (a step at
//! the left node, two points at one position). VTK's round trip through HSV or Lab is not
//! exact, so at interior nodes the result holds VTK's round-tripped colour and at the first
//! and last node a step of up to about 2e-4 to the node's own colour, as VTK has.
//! `"Lab/CIEDE2000"` (a shortest path through a grid of Lab colours) and other names are
//! refused with an error naming the field.
//!
//! Positions are used as written (ParaView's "use preset range"): ParaView rescales a preset
//! to the data range when it is applied, and its built-in presets span 0..1 or -1..1, so
//! those need `space` set to normalized (or their positions rescaled) to look as in ParaView.
//!
//! Not applied, recorded in [`Imported::notes`]: Slicer's gradient opacity when it is not the
//! constant 1 (Volux has no gradient opacity), Slicer's shading and interpolation settings,
//! ParaView's `NanColor`. Refused: ParaView's categorical presets (`IndexedColors` without
//! `RGBPoints`) and `UseLogScale: true`.
//!
//! Bad input is an [`Error::TfImport`] naming the field or line (`RGBPoints[6]`,
//! `line 7 (scalar opacity)`); files hold at most [`MAX_POINTS`] points per function.
use serde_json::{Map, Value};

use crate::error::{Error, Result};
use crate::transfer::{Space, TransferFunction};

mod blend;
mod color_space;

use blend::Blend;
pub use color_space::{vtk_color_value, ColorSpace, VtkColorNode};

/// The most control points one imported function may hold.
pub const MAX_POINTS: usize = 65_536;
/// The largest difference, at the bisection's check points, between the imported curve and
/// VTK's: opacity per unit distance, and display (sRGB-encoded) colour values.
pub const TOLERANCE: f64 = 5e-5;
/// The most points the sampled result may hold.
const MAX_SAMPLES: usize = 1 << 20;
/// The deepest bisection of one segment.
const MAX_DEPTH: u32 = 24;
/// Opacity at which `TransferFunction::resolved` clamps (it takes `-ln(1 - alpha)`).
const ALPHA_CLAMP: f64 = 0.999_999;

/// The formats [`import`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TfFormat {
    /// Volux's own JSON ([`TransferFunction::from_json`]).
    Volux,
    /// A ParaView colour-map / opacity preset.
    ParaView,
    /// A 3D Slicer volume property (`.vp`).
    SlicerVp,
}

/// An imported transfer function with what was not carried over.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The transfer function (value space, `unit_length` 1 for the imported formats).
    pub tf: TransferFunction,
    /// The format it was read from.
    pub format: TfFormat,
    /// The preset's name, where the file gives one.
    pub name: Option<String>,
    /// Settings of the file that the result does not apply, one sentence each.
    pub notes: Vec<String>,
}

/// A node of a `vtkPiecewiseFunction` (or one channel of a `vtkColorTransferFunction`): the
/// value `y` at `x`, and the shape of the curve from this node to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VtkNode {
    /// Position.
    pub x: f64,
    /// Value.
    pub y: f64,
    /// Where (as a fraction of the segment) the curve reaches the mean of the two values.
    pub midpoint: f64,
    /// 0 linear, up to 1 a step at the midpoint.
    pub sharpness: f64,
}

/// The format of a transfer-function file: `.vp` or text starting with a digit is Slicer's,
/// a JSON array or an object with `RGBPoints` is a ParaView preset, anything else Volux's.
pub fn detect_format(file_name: &str, text: &str) -> TfFormat {
    let lower = file_name.to_ascii_lowercase();
    let head = text.trim_start().chars().next();
    if lower.ends_with(".vp")
        || (!lower.ends_with(".json") && head.is_some_and(|c| c.is_ascii_digit()))
    {
        return TfFormat::SlicerVp;
    }
    match serde_json::from_str::<Value>(text) {
        Ok(Value::Array(_)) => TfFormat::ParaView,
        Ok(Value::Object(o)) if o.contains_key("RGBPoints") => TfFormat::ParaView,
        _ => TfFormat::Volux,
    }
}

/// Largest transfer-function file read ([`import_file`]): far more than any real TF, and
/// a bound on what a wrong path (a disk image, `/dev/zero`) can make us read.
pub const MAX_FILE_BYTES: u64 = 16 << 20;

/// Reads the transfer-function file at `path`, of any format ([`import`]): a regular file
/// of at most [`MAX_FILE_BYTES`], read no further than that.
pub fn import_file(path: &std::path::Path) -> Result<Imported> {
    use std::io::Read;
    let too_large = |bytes: u64| Error::TfImport {
        format: "file",
        field: path.display().to_string(),
        reason: format!("{bytes} bytes or more; a transfer function is at most {MAX_FILE_BYTES}"),
    };
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(Error::TfImport {
            format: "file",
            field: path.display().to_string(),
            reason: "not a regular file".into(),
        });
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_large(meta.len()));
    }
    let mut text = String::new();
    let read = file.take(MAX_FILE_BYTES + 1).read_to_string(&mut text)? as u64;
    if read > MAX_FILE_BYTES {
        return Err(too_large(read));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    import(&name, &text)
}

/// Reads a transfer-function file of any format ([`detect_format`]).
pub fn import(file_name: &str, text: &str) -> Result<Imported> {
    match detect_format(file_name, text) {
        TfFormat::Volux => Ok(Imported {
            tf: TransferFunction::from_json(text)?,
            format: TfFormat::Volux,
            name: None,
            notes: Vec::new(),
        }),
        TfFormat::ParaView => from_paraview_json(text),
        TfFormat::SlicerVp => from_slicer_vp(text),
    }
}

/// The value of a `vtkPiecewiseFunction` at `x` with clamping on (VTK's default), following
/// `vtkPiecewiseFunction::GetTable` (VTK `Common/DataModel/vtkPiecewiseFunction.cxx`): the
/// first node's value up to it, the last one's after it; between nodes `a` and `b` the
/// position `s` in the segment is moved so that `a.midpoint` maps to 0.5, then a step at 0.5
/// (`a.sharpness > 0.99`), linear (`< 0.01`), or a Hermite curve with both slopes
/// `(1 - sharpness) (b.y - a.y)` after `s` is sharpened by the power `1 + 10 sharpness`,
/// clamped to the two values. Nodes must be sorted by `x`; none give 0.
pub fn vtk_piecewise_value(nodes: &[VtkNode], x: f64) -> f64 {
    let i = nodes.partition_point(|n| n.x < x);
    match (nodes.first(), nodes.last()) {
        (None, _) | (_, None) => 0.0,
        (Some(first), _) if i == 0 => first.y,
        (_, Some(last)) if i == nodes.len() => last.y,
        _ => segment_value(&nodes[i - 1], &nodes[i], x),
    }
}

/// The VTK curve between nodes `a` and `b` at `x` (see [`vtk_piecewise_value`]).
fn segment_value(a: &VtkNode, b: &VtkNode, x: f64) -> f64 {
    let blend = Blend::new(midpoint_position(a, b, x), a.sharpness);
    let v = blend.mix(a.y, b.y);
    match blend {
        Blend::Hermite { .. } => v.clamp(a.y.min(b.y), a.y.max(b.y)),
        _ => v,
    }
}

/// The position in segment `a`-`b`, moved so that the midpoint (kept in [1e-5, 1 - 1e-5]
/// as VTK does) maps to 0.5.
fn midpoint_position(a: &VtkNode, b: &VtkNode, x: f64) -> f64 {
    let m = a.midpoint.clamp(0.00001, 0.99999);
    let s = if b.x > a.x {
        (x - a.x) / (b.x - a.x)
    } else {
        1.0
    };
    if s < m {
        0.5 * s / m
    } else {
        0.5 + 0.5 * (s - m) / (1.0 - m)
    }
}

// ---------------------------------------------------------------------------------------
// Sampling VTK curves into Volux points.

/// The sRGB transfer curve, decoding (IEC 61966-2-1).
fn srgb_to_linear(x: f64) -> f64 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer curve, encoding.
fn linear_to_srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Extinction per unit distance of opacity `alpha`, clamped as `TransferFunction::resolved`
/// clamps it.
fn tau_of(alpha: f64) -> f64 {
    -(1.0 - alpha.min(ALPHA_CLAMP)).ln()
}

/// How a curve is represented between two samples and compared with the original.
trait Representation<const N: usize> {
    /// The represented value at fraction `t` between samples `a` and `b` (original values).
    fn between(a: &[f64; N], b: &[f64; N], t: f64) -> [f64; N];
}

/// Opacity per unit distance, stored as opacity and interpolated as extinction.
struct Opacity;
impl Representation<1> for Opacity {
    fn between(a: &[f64; 1], b: &[f64; 1], t: f64) -> [f64; 1] {
        let tau = (1.0 - t) * tau_of(a[0]) + t * tau_of(b[0]);
        [1.0 - (-tau).exp()]
    }
}

/// Display colour, stored linear and interpolated linearly, compared re-encoded.
struct DisplayColor;
impl Representation<3> for DisplayColor {
    fn between(a: &[f64; 3], b: &[f64; 3], t: f64) -> [f64; 3] {
        [0, 1, 2].map(|k| {
            let (p, q) = (srgb_to_linear(a[k]), srgb_to_linear(b[k]));
            linear_to_srgb((1.0 - t) * p + t * q)
        })
    }
}

/// A VTK curve with `N` values per position, to be sampled: the nodes' positions and
/// shapes, their values, and the curve of each segment.
struct Curves<'a, const N: usize> {
    /// Positions, midpoints and sharpnesses of the nodes (`y` unused).
    shape: &'a [VtkNode],
    /// The value at each node.
    values: Vec<[f64; N]>,
    /// The curve of segment `i` (nodes `i` and `i + 1`) at a position in it, ends included.
    segment: &'a dyn Fn(usize, f64) -> [f64; N],
    /// Every segment (but one with sharpness > 0.99) holds its right node's value (VTK's
    /// `Step` colour space).
    step_right: bool,
}

impl<const N: usize> Curves<'_, N> {
    /// Samples of the curves, `[x, values...]`, close to the original within [`TOLERANCE`]
    /// when represented by `R`; `what` names the function in errors. At each node the value
    /// VTK gives there (the end of the segment before it; the node's own value at the first
    /// node), then, where it differs, the start of the segment after it (VTK's colour-space
    /// round trips are not exact) and after the last node its own value (VTK's clamping).
    fn sample<R: Representation<N>>(&self, what: &'static str) -> Result<Vec<(f64, [f64; N])>> {
        let nodes = self.shape;
        let n = nodes.len();
        let live = |j: usize| j + 1 < n && nodes[j + 1].x > nodes[j].x;
        let mut out: Vec<(f64, [f64; N])> = Vec::new();
        let push = |out: &mut Vec<(f64, [f64; N])>, x: f64, y: [f64; N]| {
            if out.last() != Some(&(x, y)) {
                out.push((x, y));
            }
        };
        for (i, a) in nodes.iter().enumerate() {
            if i == 0 {
                push(&mut out, a.x, self.values[0]);
            } else if live(i - 1) {
                push(&mut out, a.x, (self.segment)(i - 1, a.x));
            }
            if live(i) {
                let start = (self.segment)(i, a.x);
                push(&mut out, a.x, start);
                self.sample_segment::<R>(i, start, &mut out, what)?;
            } else if i + 1 == n {
                push(&mut out, a.x, self.values[i]);
            }
        }
        Ok(out)
    }

    /// The inner samples of segment `i` starting at value `ya`: none for `step_right`, else
    /// split at the midpoint (a step there for sharpness > 0.99), then bisected.
    fn sample_segment<R: Representation<N>>(
        &self,
        i: usize,
        ya: [f64; N],
        out: &mut Vec<(f64, [f64; N])>,
        what: &'static str,
    ) -> Result<()> {
        let (a, b) = (self.shape[i], self.shape[i + 1]);
        let xm = a.x + a.midpoint.clamp(0.00001, 0.99999) * (b.x - a.x);
        if a.sharpness > 0.99 {
            out.extend([(xm, ya), (xm, self.values[i + 1])]);
            return Ok(());
        }
        if self.step_right {
            return Ok(());
        }
        let at = |x| (self.segment)(i, x);
        let (ym, yb) = (at(xm), at(b.x));
        self.bisect::<R>(i, (a.x, ya), (xm, ym), 0, out, what)?;
        out.push((xm, ym));
        self.bisect::<R>(i, (xm, ym), (b.x, yb), 0, out, what)
    }

    /// Adds the samples strictly inside `(p, q)` that the representation needs.
    #[allow(clippy::too_many_arguments)]
    fn bisect<R: Representation<N>>(
        &self,
        i: usize,
        p: (f64, [f64; N]),
        q: (f64, [f64; N]),
        depth: u32,
        out: &mut Vec<(f64, [f64; N])>,
        what: &'static str,
    ) -> Result<()> {
        let close = [0.25, 0.5, 0.75].iter().all(|&t| {
            let want = (self.segment)(i, p.0 + t * (q.0 - p.0));
            let got = R::between(&p.1, &q.1, t);
            (0..N).all(|k| (want[k] - got[k]).abs() <= TOLERANCE)
        });
        if close || depth >= MAX_DEPTH {
            return Ok(());
        }
        if out.len() >= MAX_SAMPLES {
            return Err(Error::InvalidTransferFunction(format!(
                "the {what} needs more than {MAX_SAMPLES} points to follow VTK's curve"
            )));
        }
        let xm = 0.5 * (p.0 + q.0);
        let m = (xm, (self.segment)(i, xm));
        self.bisect::<R>(i, p, m, depth + 1, out, what)?;
        out.push(m);
        self.bisect::<R>(i, m, q, depth + 1, out, what)
    }
}

/// Volux opacity points following VTK's scalar opacity `nodes` (opacity per unit distance).
pub fn opacity_points(nodes: &[VtkNode]) -> Result<Vec<[f64; 2]>> {
    let segment = |i: usize, x| [segment_value(&nodes[i], &nodes[i + 1], x)];
    let curves = Curves {
        shape: nodes,
        values: nodes.iter().map(|n| [n.y]).collect(),
        segment: &segment,
        step_right: false,
    };
    let samples = curves.sample::<Opacity>("scalar opacity")?;
    Ok(samples.into_iter().map(|(x, [a])| [x, a]).collect())
}

/// Volux (linear RGB) colour points following VTK's colour transfer function `nodes`
/// (display, i.e. sRGB-encoded, values) interpolated in `space`.
pub fn color_points(nodes: &[VtkColorNode], space: ColorSpace) -> Result<Vec<[f64; 4]>> {
    let shape: Vec<VtkNode> = nodes
        .iter()
        .map(|n| VtkNode {
            x: n.x,
            y: 0.0,
            midpoint: n.midpoint,
            sharpness: n.sharpness,
        })
        .collect();
    let segment = |i: usize, x| color_space::segment_color(&nodes[i], &nodes[i + 1], space, x);
    let curves = Curves {
        shape: &shape,
        values: nodes.iter().map(|n| n.rgb).collect(),
        segment: &segment,
        step_right: space == ColorSpace::Step,
    };
    let samples = curves.sample::<DisplayColor>("colour transfer function")?;
    Ok(samples
        .into_iter()
        // VTK's linear branch does not clamp: HSV rounding can give 1 + 1e-15.
        .map(|(x, c)| {
            let [r, g, b] = c.map(|v| srgb_to_linear(v.clamp(0.0, 1.0)));
            [x, r, g, b]
        })
        .collect())
}

/// A value-space TF with `color` and `opacity` per 1 world unit, validated.
fn build(color: Vec<[f64; 4]>, opacity: Vec<[f64; 2]>) -> Result<TransferFunction> {
    let tf = TransferFunction {
        space: Space::Value,
        color,
        extinction: Vec::new(),
        opacity,
        opacity_step: 1.0,
        opacity_scale: 1.0,
        unit_length: 1.0,
    };
    tf.validate()?;
    Ok(tf)
}

// ---------------------------------------------------------------------------------------
// Shared checks of flat number lists.

/// Checks a flat list of `width`-tuples: not empty, a whole number of tuples, at most
/// [`MAX_POINTS`] tuples, finite, positions sorted, the components in `ranges` (per
/// component after the position: inclusive bounds and a name). `err` builds the error from
/// a field suffix (`[7]`, "") and a reason.
fn check_flat(
    v: &[f64],
    width: usize,
    ranges: &[(f64, f64, &str)],
    err: &dyn Fn(String, String) -> Error,
) -> Result<()> {
    if v.is_empty() {
        return Err(err(String::new(), "no points".into()));
    }
    if !v.len().is_multiple_of(width) {
        return Err(err(
            String::new(),
            format!("{} numbers, not a multiple of {width}", v.len()),
        ));
    }
    if v.len() / width > MAX_POINTS {
        return Err(err(
            String::new(),
            format!("{} points, more than {MAX_POINTS}", v.len() / width),
        ));
    }
    for (i, x) in v.iter().enumerate() {
        check_component(v, i, *x, width, ranges, err)?;
    }
    Ok(())
}

/// Checks number `i` of a flat list (see [`check_flat`]).
fn check_component(
    v: &[f64],
    i: usize,
    x: f64,
    width: usize,
    ranges: &[(f64, f64, &str)],
    err: &dyn Fn(String, String) -> Error,
) -> Result<()> {
    let at = format!("[{i}]");
    if !x.is_finite() {
        return Err(err(at, format!("{x} is not a finite number")));
    }
    let k = i % width;
    if k == 0 {
        if i >= width && x < v[i - width] {
            return Err(err(
                at,
                format!(
                    "position {x} is below the previous point's {} (points must be sorted)",
                    v[i - width]
                ),
            ));
        }
        return Ok(());
    }
    match ranges.get(k - 1) {
        Some(&(lo, hi, name)) if !(lo..=hi).contains(&x) => {
            Err(err(at, format!("{name} {x} is outside {lo}..{hi}")))
        }
        _ => Ok(()),
    }
}

/// Nodes from a flat list of `[x, y, (midpoint, sharpness)]` tuples of `width` numbers,
/// taking component `k` as `y`.
fn nodes_of(v: &[f64], width: usize, k: usize) -> Vec<VtkNode> {
    v.chunks_exact(width)
        .map(|c| VtkNode {
            x: c[0],
            y: c[k],
            midpoint: if width == 4 && k == 1 { c[2] } else { 0.5 },
            sharpness: if width == 4 && k == 1 { c[3] } else { 0.0 },
        })
        .collect()
}

/// Colour points of a flat `[x, r, g, b, ...]` list of display values (checked),
/// interpolated in `space`. Colour nodes are linear (midpoint 0.5, sharpness 0) in both
/// formats.
fn color_from_flat(v: &[f64], space: ColorSpace) -> Result<Vec<[f64; 4]>> {
    let nodes: Vec<VtkColorNode> = v
        .chunks_exact(4)
        .map(|c| VtkColorNode {
            x: c[0],
            rgb: [c[1], c[2], c[3]],
            midpoint: 0.5,
            sharpness: 0.0,
        })
        .collect();
    color_points(&nodes, space)
}

// ---------------------------------------------------------------------------------------
// ParaView presets.

const PARAVIEW: &str = "ParaView preset";

fn pv_err(field: impl Into<String>, reason: impl Into<String>) -> Error {
    Error::TfImport {
        format: PARAVIEW,
        field: field.into(),
        reason: reason.into(),
    }
}

/// Reads a ParaView preset file: a JSON array of presets (the first is used; a note names
/// the others' count) or one preset object. See the module documentation for what is read.
pub fn from_paraview_json(text: &str) -> Result<Imported> {
    let value: Value = serde_json::from_str(text)?;
    let mut notes = Vec::new();
    let preset = match &value {
        Value::Array(list) => {
            let first = list
                .first()
                .ok_or_else(|| pv_err("presets", "the list of presets is empty"))?;
            if list.len() > 1 {
                notes.push(format!(
                    "the file holds {} presets; the first is used",
                    list.len()
                ));
            }
            first
        }
        other => other,
    };
    let Value::Object(obj) = preset else {
        return Err(pv_err(
            "presets",
            format!(
                "expected a preset object, got {}",
                crate::json_shape::describe(preset)
            ),
        ));
    };
    paraview_preset(obj, notes)
}

/// One ParaView preset object.
fn paraview_preset(obj: &Map<String, Value>, mut notes: Vec<String>) -> Result<Imported> {
    let name = match obj.get("Name") {
        None => None,
        Some(Value::String(s)) => Some(s.clone()),
        Some(other) => {
            return Err(pv_err(
                "Name",
                format!(
                    "expected a string, got {}",
                    crate::json_shape::describe(other)
                ),
            ))
        }
    };
    let space = color_space(obj, &mut notes)?;
    if obj.get("UseLogScale").and_then(Value::as_bool) == Some(true) {
        return Err(pv_err(
            "UseLogScale",
            "logarithmic colour maps are not supported",
        ));
    }
    check_nan_color(obj, &mut notes)?;
    let rgb =
        pv_numbers(obj, "RGBPoints")?.ok_or_else(|| match obj.contains_key("IndexedColors") {
            true => pv_err(
                "RGBPoints",
                "missing: categorical presets (IndexedColors) are not supported",
            ),
            false => pv_err("RGBPoints", "missing (a flat list [x, r, g, b, ...])"),
        })?;
    let err = |at: String, why: String| pv_err(format!("RGBPoints{at}"), why);
    let unit = (0.0, 1.0, "colour component");
    check_flat(&rgb, 4, &[unit, unit, unit], &err)?;
    let color = color_from_flat(&rgb, space)?;
    let opacity = match pv_numbers(obj, "Points")? {
        Some(points) => paraview_opacity(&points)?,
        None => {
            notes.push("no opacity (Points): ParaView's default ramp from 0 to 1 over the colour points is used".into());
            default_ramp(&rgb)?
        }
    };
    Ok(Imported {
        tf: build(color, opacity)?,
        format: TfFormat::ParaView,
        name,
        notes,
    })
}

/// ParaView's default scalar opacity: 0 at the first colour point, 1 at the last.
fn default_ramp(rgb: &[f64]) -> Result<Vec<[f64; 2]>> {
    let (lo, hi) = (rgb[0], rgb[rgb.len() - 4]);
    let node = |x, y| VtkNode {
        x,
        y,
        midpoint: 0.5,
        sharpness: 0.0,
    };
    opacity_points(&[node(lo, 0.0), node(hi, 1.0)])
}

/// The opacity points of ParaView's flat `Points` `[x, opacity, midpoint, sharpness, ...]`.
fn paraview_opacity(points: &[f64]) -> Result<Vec<[f64; 2]>> {
    let err = |at: String, why: String| pv_err(format!("Points{at}"), why);
    let ranges = [
        (0.0, 1.0, "opacity"),
        (0.0, 1.0, "midpoint"),
        (0.0, 1.0, "sharpness"),
    ];
    check_flat(points, 4, &ranges, &err)?;
    opacity_points(&nodes_of(points, 4, 1))
}

/// `ColorSpace`: see [`ColorSpace::from_paraview`]; missing counts as RGB (noted).
fn color_space(obj: &Map<String, Value>, notes: &mut Vec<String>) -> Result<ColorSpace> {
    match obj.get("ColorSpace") {
        None => {
            notes.push("no ColorSpace: colours are interpolated in RGB".into());
            Ok(ColorSpace::Rgb)
        }
        Some(Value::String(s)) => ColorSpace::from_paraview(s).ok_or_else(|| {
            let why = match s.as_str() {
                "Lab/CIEDE2000" => {
                    " (VTK interpolates it along a shortest path through a grid of Lab colours)"
                }
                _ => "",
            };
            pv_err(
                "ColorSpace",
                format!(
                    "{s:?} is not supported{why}; supported: \"RGB\", \"HSV\", \"Lab\" \
                     (or \"CIELAB\"), \"Diverging\", \"Step\""
                ),
            )
        }),
        Some(other) => Err(pv_err(
            "ColorSpace",
            format!(
                "expected a string, got {}",
                crate::json_shape::describe(other)
            ),
        )),
    }
}

/// `NanColor`: three numbers in 0..1 (ParaView writes `[r, g, b]`), not applied (noted).
fn check_nan_color(obj: &Map<String, Value>, notes: &mut Vec<String>) -> Result<()> {
    let Some(v) = pv_numbers(obj, "NanColor")? else {
        return Ok(());
    };
    if v.len() != 3 || v.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(pv_err(
            "NanColor",
            format!("expected [r, g, b] in 0..1, got {v:?}"),
        ));
    }
    notes.push("NanColor is not applied (Volux has no colour for NaN values)".into());
    Ok(())
}

/// The optional field `field` as a list of numbers.
fn pv_numbers(obj: &Map<String, Value>, field: &str) -> Result<Option<Vec<f64>>> {
    let Some(v) = obj.get(field) else {
        return Ok(None);
    };
    let Value::Array(items) = v else {
        return Err(pv_err(
            field,
            format!(
                "expected a flat list of numbers, got {}",
                crate::json_shape::describe(v)
            ),
        ));
    };
    items
        .iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64().ok_or_else(|| {
                pv_err(
                    format!("{field}[{i}]"),
                    format!("expected a number, got {}", crate::json_shape::describe(x)),
                )
            })
        })
        .collect::<Result<Vec<f64>>>()
        .map(Some)
}

// ---------------------------------------------------------------------------------------
// Slicer volume properties.

const SLICER: &str = "Slicer .vp";

/// The nine lines of a `.vp` file, in the order Slicer reads them.
const VP_LINES: [&str; 9] = [
    "interpolation type",
    "shade",
    "diffuse",
    "ambient",
    "specular",
    "specular power",
    "scalar opacity",
    "gradient opacity",
    "colour transfer",
];

fn vp_err(line: usize, reason: impl Into<String>) -> Error {
    Error::TfImport {
        format: SLICER,
        field: format!("line {} ({})", line + 1, VP_LINES[line]),
        reason: reason.into(),
    }
}

/// Reads a Slicer volume property file (see the module documentation). Empty lines keep
/// Slicer's defaults, except the scalar opacity and colour lines, which are required.
/// Positions must not decrease (Slicer nudges equal ones apart by one ulp; Volux keeps them
/// equal, a step).
pub fn from_slicer_vp(text: &str) -> Result<Imported> {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    if let Some(missing) = (lines.len()..VP_LINES.len()).next() {
        return Err(vp_err(
            missing,
            format!("missing: the file ends after {} lines of 9", lines.len()),
        ));
    }
    let mut notes = Vec::new();
    vp_settings(&lines, &mut notes)?;
    let opacity = vp_function(lines[6], 6, 2)?.ok_or_else(|| vp_err(6, "empty"))?;
    let err = |at: String, why: String| vp_err(6, format!("number {at}: {why}"));
    check_flat(&opacity, 2, &[(0.0, 1.0, "opacity")], &err)?;
    vp_gradient(lines[7], &mut notes)?;
    let rgb = vp_function(lines[8], 8, 4)?.ok_or_else(|| vp_err(8, "empty"))?;
    let err = |at: String, why: String| vp_err(8, format!("number {at}: {why}"));
    let unit = (0.0, 1.0, "colour component");
    check_flat(&rgb, 4, &[unit, unit, unit], &err)?;
    let tf = build(
        color_from_flat(&rgb, ColorSpace::Rgb)?,
        opacity_points(&nodes_of(&opacity, 2, 1))?,
    )?;
    Ok(Imported {
        tf,
        format: TfFormat::SlicerVp,
        name: None,
        notes,
    })
}

/// Lines 1-6: checked numbers; shading and nearest interpolation are noted, not applied.
fn vp_settings(lines: &[&str], notes: &mut Vec<String>) -> Result<()> {
    let mut values = [None; 6];
    for (i, value) in values.iter_mut().enumerate() {
        if lines[i].is_empty() {
            continue;
        }
        let x: f64 = lines[i]
            .parse()
            .map_err(|_| vp_err(i, format!("expected a number, got {:?}", short(lines[i]))))?;
        let allowed: &[f64] = match i {
            0 => &[0.0, 1.0, 2.0], // VTK_NEAREST, VTK_LINEAR, VTK_CUBIC_INTERPOLATION
            1 => &[0.0, 1.0],
            _ => &[],
        };
        if !x.is_finite() || (i < 2 && !allowed.contains(&x)) {
            return Err(vp_err(i, format!("{x} is not a valid value")));
        }
        *value = Some(x);
    }
    if values[0] == Some(0.0) {
        notes.push("Slicer's nearest-neighbour interpolation is not applied".into());
    }
    if values[1] == Some(1.0) {
        notes.push(
            "Slicer's shading (shade 1, ambient/diffuse/specular) is not applied; turn on the renderer's shading to light the volume"
                .into(),
        );
    }
    Ok(())
}

/// The gradient opacity line: checked; anything but the constant 1 is noted, not applied.
fn vp_gradient(line: &str, notes: &mut Vec<String>) -> Result<()> {
    let Some(v) = vp_function(line, 7, 2)? else {
        return Ok(());
    };
    let err = |at: String, why: String| vp_err(7, format!("number {at}: {why}"));
    check_flat(&v, 2, &[(0.0, 1.0, "opacity")], &err)?;
    if v.chunks_exact(2).any(|p| p[1] != 1.0) {
        notes.push("the gradient opacity is not applied (Volux has none)".into());
    }
    Ok(())
}

/// A function line `N v1 ... vN` (`vtkMRMLVolumePropertyNode::DataFromString`), `N` a
/// multiple of `width`; `None` for an empty line or `N` = 0.
fn vp_function(line: &str, index: usize, width: usize) -> Result<Option<Vec<f64>>> {
    let mut tokens = line.split_ascii_whitespace();
    let Some(head) = tokens.next() else {
        return Ok(None);
    };
    let count: usize = head.parse().map_err(|_| {
        vp_err(
            index,
            format!("expected the count of numbers first, got {:?}", short(head)),
        )
    })?;
    if count == 0 {
        return Ok(None);
    }
    if !count.is_multiple_of(width) || count / width > MAX_POINTS {
        return Err(vp_err(
            index,
            format!(
                "count {count} is not a multiple of {width} up to {}",
                width * MAX_POINTS
            ),
        ));
    }
    let values = tokens
        .enumerate()
        .map(|(i, t)| {
            t.parse::<f64>().map_err(|_| {
                vp_err(
                    index,
                    format!("number {i}: expected a number, got {:?}", short(t)),
                )
            })
        })
        .collect::<Result<Vec<f64>>>()?;
    if values.len() != count {
        return Err(vp_err(
            index,
            format!("declares {count} numbers, holds {}", values.len()),
        ));
    }
    Ok(Some(values))
}

/// At most 20 characters of `s`, for messages.
fn short(s: &str) -> String {
    s.chars().take(20).collect()
}

#[cfg(test)]
mod tests;
