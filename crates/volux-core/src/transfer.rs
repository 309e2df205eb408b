//! Transfer functions: piecewise-linear colour (RGB) and extinction coefficient.
//!
//! The optical model is emission-absorption (`001_...txt` ch. 2): a sample of value `s` emits
//! colour `c(s)` and absorbs with extinction `tau(s)` per unit length. `tau` is given per
//! [`TransferFunction::unit_length`] world units (presets use the voxel size, so a preset looks
//! alike on data of any physical size); renderers call [`TransferFunction::tau_per_world`].
//! Opacity per reference step is accepted too and converted: `tau = -ln(1 - a) / step`.
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::histogram::Histogram;
use crate::json_shape;

/// Whether control-point positions are data values or fractions of the data range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// Positions are data values (e.g. Hounsfield units).
    #[default]
    Value,
    /// Positions are in [0, 1] over the data's value range.
    Normalized,
}

/// A piecewise-linear transfer function (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransferFunction {
    /// Whether positions are values or normalized; JSON `"value"` or `"normalized"`, missing
    /// means `"value"`.
    #[serde(default)]
    pub space: Space,
    /// Colour control points `[s, r, g, b]` (linear RGB in 0..1), sorted by `s`.
    pub color: Vec<[f64; 4]>,
    /// Extinction control points `[s, tau]`, sorted by `s`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extinction: Vec<[f64; 2]>,
    /// Alternative to `extinction`: opacity per `opacity_step` as `[s, alpha]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub opacity: Vec<[f64; 2]>,
    /// Length (in units of `unit_length`) that `opacity` refers to; missing means 1 (one
    /// `unit_length`).
    #[serde(default = "one")]
    pub opacity_step: f64,
    /// Global multiplier of the extinction; missing means 1.
    #[serde(default = "one")]
    pub opacity_scale: f64,
    /// World length that `tau` refers to; missing means 1 world unit. Presets are set to the
    /// volume's unit length instead (the renderer's `Volume::preset` calls
    /// [`TransferFunction::with_unit_length`]; a grid's unit is its smallest voxel spacing).
    #[serde(default = "one")]
    pub unit_length: f64,
}

/// A finite number as JSON: the shortest text that reads back the same value.
fn number(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".into()
    }
}

fn one() -> f64 {
    1.0
}

/// The fields of the JSON form, in documentation order.
const FIELDS: [&str; 7] = [
    "space",
    "color",
    "extinction",
    "opacity",
    "opacity_step",
    "opacity_scale",
    "unit_length",
];

/// Checks the shape of every field of the JSON form, naming the field in the message.
fn check_shape(obj: &json_shape::Object) -> std::result::Result<(), String> {
    use json_shape::{check_number, check_points, NumberKind};
    json_shape::check_known(obj, &FIELDS)?;
    json_shape::check_choice(obj, "space", &["value", "normalized"])?;
    json_shape::check_required(obj, "color", "a list of [value, r, g, b] points")?;
    check_points(obj, "color", 4, "[value, r, g, b]")?;
    check_points(obj, "extinction", 2, "[value, tau]")?;
    check_points(obj, "opacity", 2, "[value, alpha]")?;
    check_number(obj, "opacity_step", NumberKind::Positive)?;
    check_number(obj, "opacity_scale", NumberKind::NonNegative)?;
    check_number(obj, "unit_length", NumberKind::Positive)
}

/// The preset names accepted by [`TransferFunction::preset`].
pub const PRESETS: [&str; 9] = [
    "auto",
    "grayscale",
    "ct-bone",
    "ct-skin",
    "ct-soft-tissue",
    "mr-default",
    "viridis",
    "inferno",
    "cool-warm",
];

/// Stops of the viridis colour scale (sRGB-encoded, evenly spaced from 0 to 1), for
/// [`colormap_at`].
pub const VIRIDIS: [[f64; 3]; 5] = [
    [0.267, 0.005, 0.329],
    [0.229, 0.322, 0.546],
    [0.128, 0.567, 0.551],
    [0.369, 0.789, 0.383],
    [0.993, 0.906, 0.144],
];
/// Stops of the inferno colour scale (sRGB-encoded, evenly spaced from 0 to 1; near black to
/// pale yellow), for [`colormap_at`].
pub const INFERNO: [[f64; 3]; 5] = [
    [0.001, 0.000, 0.014],
    [0.341, 0.062, 0.429],
    [0.735, 0.216, 0.330],
    [0.978, 0.557, 0.035],
    [0.988, 0.998, 0.645],
];
const COOL_WARM: [[f64; 3]; 3] = [
    [0.230, 0.299, 0.754],
    [0.865, 0.865, 0.865],
    [0.706, 0.016, 0.150],
];

fn lerp_points(points: &[[f64; 2]], s: f64) -> f64 {
    match points.iter().position(|p| p[0] > s) {
        None => points.last().map_or(0.0, |p| p[1]),
        Some(0) => points[0][1],
        Some(i) => {
            let (a, b) = (points[i - 1], points[i]);
            let t = (s - a[0]) / (b[0] - a[0]);
            a[1] + (b[1] - a[1]) * t
        }
    }
}

fn colormap(stops: &[[f64; 3]]) -> Vec<[f64; 4]> {
    let n = (stops.len() - 1) as f64;
    stops
        .iter()
        .enumerate()
        .map(|(i, c)| [i as f64 / n, srgb(c[0]), srgb(c[1]), srgb(c[2])])
        .collect()
}

/// The linear RGB colour at `t` of a colour scale given by evenly spaced sRGB-encoded
/// `stops` (such as [`VIRIDIS`] or [`INFERNO`]): the stops are interpolated in sRGB (evenly
/// perceived steps), then converted to linear. `t` is clamped to 0..1 (NaN counts as 0); no
/// stops give black.
pub fn colormap_at(stops: &[[f64; 3]], t: f64) -> [f64; 3] {
    let Some(last) = stops.len().checked_sub(1) else {
        return [0.0; 3];
    };
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * last as f64;
    let i = (x.floor() as usize).min(last.saturating_sub(1));
    let (a, b) = (stops[i], stops[(i + 1).min(last)]);
    let f = x - i as f64;
    [0, 1, 2].map(|k| srgb(a[k] + (b[k] - a[k]) * f))
}

/// sRGB-encoded colormap entries to linear.
fn srgb(x: f64) -> f64 {
    crate::image::srgb_to_linear(x as f32) as f64
}

impl TransferFunction {
    /// Parses the JSON form and validates it.
    ///
    /// A wrong shape is an [`Error::InvalidTransferFunction`] naming the field and the
    /// expected shape (e.g. `color[0]: expected [value, r, g, b] (4 numbers), got 5 numbers`,
    /// `unknown field "colour" (...)`); malformed JSON is an [`Error::Json`] with serde's
    /// line and column. Missing optional fields take the defaults documented on the fields.
    pub fn from_json(text: &str) -> Result<Self> {
        let obj = json_shape::parse_object(text, &FIELDS, Error::InvalidTransferFunction)?;
        check_shape(&obj).map_err(Error::InvalidTransferFunction)?;
        let tf: Self = serde_json::from_value(serde_json::Value::Object(obj))?;
        tf.validate()?;
        Ok(tf)
    }

    /// The JSON form, one control point per line (for people to edit).
    pub fn to_json(&self) -> String {
        fn points<const N: usize>(name: &str, pts: &[[f64; N]]) -> Option<String> {
            (!pts.is_empty()).then(|| {
                let rows: Vec<String> = pts
                    .iter()
                    .map(|p| {
                        let v: Vec<String> = p.iter().map(|x| number(*x)).collect();
                        format!("    [{}]", v.join(", "))
                    })
                    .collect();
                format!("  \"{name}\": [\n{}\n  ]", rows.join(",\n"))
            })
        }
        let space = match self.space {
            Space::Value => "value",
            Space::Normalized => "normalized",
        };
        let fields: Vec<String> = [
            Some(format!("  \"space\": \"{space}\"")),
            points("color", &self.color),
            points("extinction", &self.extinction),
            points("opacity", &self.opacity),
            (!self.opacity.is_empty())
                .then(|| format!("  \"opacity_step\": {}", number(self.opacity_step))),
            Some(format!(
                "  \"opacity_scale\": {}",
                number(self.opacity_scale)
            )),
            Some(format!("  \"unit_length\": {}", number(self.unit_length))),
        ]
        .into_iter()
        .flatten()
        .collect();
        format!("{{\n{}\n}}", fields.join(",\n"))
    }

    /// Checks control points: present, finite, sorted, colours in 0..1, tau >= 0, alpha in 0..1.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidTransferFunction(m));
        if self.color.is_empty() {
            return bad("no colour control points".into());
        }
        if self.extinction.is_empty() == self.opacity.is_empty() {
            return bad("give exactly one of 'extinction' or 'opacity'".into());
        }
        let sorted = |v: &[f64]| v.windows(2).all(|w| w[0] <= w[1]);
        if !sorted(&self.color.iter().map(|p| p[0]).collect::<Vec<_>>())
            || !sorted(
                &self
                    .extinction
                    .iter()
                    .chain(&self.opacity)
                    .map(|p| p[0])
                    .collect::<Vec<_>>(),
            )
        {
            return bad("control points must be sorted by value".into());
        }
        let all = self
            .color
            .iter()
            .flatten()
            .chain(self.extinction.iter().chain(&self.opacity).flatten());
        if all.clone().any(|v| !v.is_finite()) {
            return bad("non-finite control point".into());
        }
        if self
            .color
            .iter()
            .any(|p| p[1..].iter().any(|c| !(0.0..=1.0).contains(c)))
        {
            return bad("colour components must be in 0..1".into());
        }
        if self.extinction.iter().any(|p| p[1] < 0.0) {
            return bad("extinction must be >= 0".into());
        }
        if self.opacity.iter().any(|p| !(0.0..=1.0).contains(&p[1])) {
            return bad("opacity must be in 0..1".into());
        }
        for (name, v) in [
            ("opacity_step", self.opacity_step),
            ("unit_length", self.unit_length),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} must be > 0"));
            }
        }
        if !(self.opacity_scale.is_finite() && self.opacity_scale >= 0.0) {
            return bad("opacity_scale must be >= 0".into());
        }
        Ok(())
    }

    /// A TF in value space, extinction given, with `opacity` converted to extinction and
    /// normalized positions mapped onto `range`.
    pub fn resolved(&self, range: [f64; 2]) -> Self {
        let map = |s: f64| match self.space {
            Space::Value => s,
            Space::Normalized => range[0] + s * (range[1] - range[0]),
        };
        let extinction = if self.opacity.is_empty() {
            self.extinction.iter().map(|p| [map(p[0]), p[1]]).collect()
        } else {
            self.opacity
                .iter()
                .map(|p| {
                    [
                        map(p[0]),
                        -(1.0 - p[1].min(0.999_999)).ln() / self.opacity_step,
                    ]
                })
                .collect()
        };
        Self {
            space: Space::Value,
            color: self
                .color
                .iter()
                .map(|p| [map(p[0]), p[1], p[2], p[3]])
                .collect(),
            extinction,
            opacity: Vec::new(),
            opacity_step: 1.0,
            opacity_scale: self.opacity_scale,
            unit_length: self.unit_length,
        }
    }

    /// Linear RGB at value `s` (a resolved TF is expected).
    pub fn color_at(&self, s: f64) -> [f64; 3] {
        let pts = &self.color;
        let i = pts.partition_point(|p| p[0] <= s);
        let (a, b) = match i {
            0 => (pts[0], pts[0]),
            i if i == pts.len() => (pts[i - 1], pts[i - 1]),
            i => (pts[i - 1], pts[i]),
        };
        let t = if b[0] > a[0] {
            (s - a[0]) / (b[0] - a[0])
        } else {
            0.0
        };
        [1, 2, 3].map(|c| a[c] + (b[c] - a[c]) * t)
    }

    /// Extinction per world unit at value `s`, opacity scale applied (a resolved TF is expected).
    pub fn tau_per_world(&self, s: f64) -> f64 {
        lerp_points(&self.extinction, s) * self.opacity_scale / self.unit_length
    }

    /// All control-point positions (colour and extinction), sorted and deduplicated: the TF is
    /// linear between consecutive ones.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .color
            .iter()
            .map(|p| p[0])
            .chain(self.extinction.iter().map(|p| p[0]))
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }

    /// Several value-space TFs combined into one: each layer is a TF (space [`Space::Value`],
    /// e.g. the result of [`TransferFunction::resolved`]; `opacity` points are converted as
    /// `resolved` does) with a weight multiplying its extinction.
    ///
    /// The result is in value space with the first layer's `unit_length` and an
    /// `opacity_scale` of 1. Its extinction per world unit is `sum_i w_i * tau_i(s)` (each layer's
    /// [`TransferFunction::tau_per_world`]), its colour the extinction-weighted mix
    /// `sum_i w_i tau_i(s) c_i(s) / sum_i w_i tau_i(s)`, or the plain average of the layers'
    /// colours where that sum is 0. The mix is not piecewise linear, so it is sampled at every
    /// layer's breakpoints and at 8 evenly spaced points inside each interval between them;
    /// colours are clamped to 0..1.
    ///
    /// Errors: no layers, a weight that is negative or not finite, a layer not in value space
    /// or not valid ([`TransferFunction::validate`]).
    pub fn layered(layers: &[(TransferFunction, f64)]) -> Result<TransferFunction> {
        let layers = resolve_layers(layers)?;
        let unit = layers[0].0.unit_length;
        let mut color = Vec::new();
        let mut extinction = Vec::new();
        for s in layer_samples(&layers) {
            let (tau, c) = mix_at(&layers, s);
            color.push([s, c[0], c[1], c[2]]);
            extinction.push([s, tau * unit]);
        }
        let tf = Self::values(color, extinction).with_unit_length(unit);
        tf.validate()?;
        Ok(tf)
    }

    /// Sets the world length that `tau` refers to (presets use the voxel size).
    pub fn with_unit_length(mut self, unit_length: f64) -> Self {
        self.unit_length = unit_length;
        self
    }

    /// Multiplies the extinction by `scale`.
    pub fn with_opacity_scale(mut self, scale: f64) -> Self {
        self.opacity_scale = scale;
        self
    }

    fn normalized(color: Vec<[f64; 4]>, extinction: Vec<[f64; 2]>) -> Self {
        Self {
            space: Space::Normalized,
            color,
            extinction,
            opacity: Vec::new(),
            opacity_step: 1.0,
            opacity_scale: 1.0,
            unit_length: 1.0,
        }
    }

    fn values(color: Vec<[f64; 4]>, extinction: Vec<[f64; 2]>) -> Self {
        Self {
            space: Space::Value,
            ..Self::normalized(color, extinction)
        }
    }

    /// A named preset, resolved on a histogram of the data (`auto` needs it; the others use
    /// only its range). CT presets are in Hounsfield units.
    pub fn preset(name: &str, hist: &Histogram) -> Result<Self> {
        let ramp = vec![[0.0, 0.0], [0.1, 0.0], [1.0, 0.25]];
        let tf = match name {
            "auto" => Self::automatic(hist),
            "grayscale" => Self::normalized(vec![[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]], ramp),
            "viridis" => Self::normalized(colormap(&VIRIDIS), ramp),
            "inferno" => Self::normalized(colormap(&INFERNO), ramp),
            "cool-warm" => Self::normalized(colormap(&COOL_WARM), ramp),
            "ct-bone" => Self::values(
                vec![
                    [150.0, 0.55, 0.25, 0.15],
                    [400.0, 0.9, 0.8, 0.65],
                    [1500.0, 1.0, 1.0, 0.95],
                ],
                vec![[150.0, 0.0], [300.0, 0.05], [700.0, 0.6], [3000.0, 1.0]],
            ),
            "ct-skin" => Self::values(
                vec![
                    [-600.0, 0.6, 0.35, 0.25],
                    [-100.0, 0.9, 0.65, 0.5],
                    [300.0, 1.0, 0.9, 0.8],
                    [1500.0, 1.0, 1.0, 1.0],
                ],
                vec![
                    [-600.0, 0.0],
                    [-300.0, 0.15],
                    [100.0, 0.15],
                    [300.0, 0.3],
                    [1500.0, 1.0],
                ],
            ),
            "ct-soft-tissue" => Self::values(
                vec![
                    [-200.0, 0.5, 0.1, 0.05],
                    [40.0, 0.85, 0.35, 0.25],
                    [300.0, 1.0, 0.85, 0.7],
                    [1500.0, 1.0, 1.0, 1.0],
                ],
                vec![
                    [-200.0, 0.0],
                    [-50.0, 0.02],
                    [80.0, 0.06],
                    [300.0, 0.3],
                    [1500.0, 0.8],
                ],
            ),
            "mr-default" => Self::normalized(
                vec![
                    [0.0, 0.0, 0.0, 0.0],
                    [0.3, 0.55, 0.35, 0.3],
                    [0.7, 0.95, 0.85, 0.75],
                    [1.0, 1.0, 1.0, 1.0],
                ],
                vec![[0.0, 0.0], [0.12, 0.0], [0.35, 0.08], [1.0, 0.3]],
            ),
            _ => {
                return Err(Error::UnknownName {
                    kind: "transfer-function preset",
                    name: name.into(),
                    known: PRESETS.join(", "),
                })
            }
        };
        Ok(tf.resolved([hist.min, hist.max]))
    }

    /// The automatic default: transparent up to the end of the dominant (background) peak of
    /// the histogram, then an extinction ramp to the 99.9th percentile, grey-warm colours, so a
    /// first render of unknown data shows its structure.
    pub fn automatic(hist: &Histogram) -> Self {
        let (lo, hi) = (hist.min, hist.max);
        let span = (hi - lo).max(f64::MIN_POSITIVE);
        let bins = hist.counts.len();
        let mode_bin = ((hist.mode() - lo) / span * bins as f64) as usize;
        // End of the background peak: first bin after the mode that falls below 1/8 of it.
        let peak = hist.counts[mode_bin.min(bins - 1)];
        let end_bin = (mode_bin..bins)
            .find(|&b| hist.counts[b] * 8 < peak)
            .unwrap_or(mode_bin);
        let mut start = lo + span * (end_bin as f64 / bins as f64);
        let top = hist.quantile(0.999).max(start + span * 0.05);
        if start >= top - span * 0.02 || mode_bin > bins / 2 {
            // No clear low background peak (e.g. dense data): ramp over the upper half.
            start = hist.quantile(0.5).min(lo + 0.5 * span);
        }
        let top = top
            .max(start + span * 0.05)
            .min(hi.max(start + span * 0.05));
        let mid = start + 0.35 * (top - start);
        let color = vec![
            [start, 0.35, 0.2, 0.15],
            [mid, 0.8, 0.6, 0.45],
            [top, 1.0, 0.97, 0.92],
        ];
        let extinction = vec![[start, 0.0], [mid, 0.04], [top, 0.35]];
        Self::values(color, extinction)
    }
}

/// Interior points sampled between consecutive breakpoints by [`TransferFunction::layered`].
const LAYER_SUBSAMPLES: usize = 8;

/// Checks the layers of [`TransferFunction::layered`] and resolves their opacity points to
/// extinction.
fn resolve_layers(layers: &[(TransferFunction, f64)]) -> Result<Vec<(TransferFunction, f64)>> {
    let bad = |m: String| Error::InvalidTransferFunction(m);
    if layers.is_empty() {
        return Err(bad(
            "a layered transfer function needs at least one layer".into()
        ));
    }
    layers
        .iter()
        .enumerate()
        .map(|(i, (tf, w))| {
            if !(w.is_finite() && *w >= 0.0) {
                return Err(bad(format!(
                    "layer {i}: weight {w} must be finite and >= 0"
                )));
            }
            if tf.space != Space::Value {
                return Err(bad(format!(
                    "layer {i}: not in value space (resolve it on the data range first)"
                )));
            }
            tf.validate().map_err(|e| match e {
                Error::InvalidTransferFunction(m) => bad(format!("layer {i}: {m}")),
                other => other,
            })?;
            // In value space the range is not used: this only converts opacity points.
            Ok((tf.resolved([0.0, 1.0]), *w))
        })
        .collect()
}

/// The positions [`TransferFunction::layered`] samples: the union of the layers'
/// breakpoints plus [`LAYER_SUBSAMPLES`] evenly spaced points inside each interval.
fn layer_samples(layers: &[(TransferFunction, f64)]) -> Vec<f64> {
    let mut knots: Vec<f64> = layers.iter().flat_map(|(tf, _)| tf.breakpoints()).collect();
    knots.sort_by(f64::total_cmp);
    knots.dedup();
    let mut out = Vec::with_capacity(knots.len() * (LAYER_SUBSAMPLES + 1));
    for pair in knots.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        out.push(a);
        let n = (LAYER_SUBSAMPLES + 1) as f64;
        out.extend((1..=LAYER_SUBSAMPLES).map(|k| a + (b - a) * k as f64 / n));
    }
    out.extend(knots.last());
    out
}

/// The summed extinction per world unit and the extinction-weighted colour of the layers
/// at `s` (the plain average colour where the extinction is 0), clamped to 0..1.
fn mix_at(layers: &[(TransferFunction, f64)], s: f64) -> (f64, [f64; 3]) {
    let mut tau = 0.0;
    let mut weighted = [0.0; 3];
    let mut plain = [0.0; 3];
    for (tf, w) in layers {
        let t = w * tf.tau_per_world(s);
        let c = tf.color_at(s);
        tau += t;
        for k in 0..3 {
            weighted[k] += t * c[k];
            plain[k] += c[k] / layers.len() as f64;
        }
    }
    let color = if tau > 0.0 {
        weighted.map(|v| v / tau)
    } else {
        plain
    };
    (tau, color.map(|v| v.clamp(0.0, 1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hist() -> Histogram {
        let v: Vec<u8> = (0..=255).collect();
        Histogram::from_values(&v, [0.0, 255.0], 256)
    }

    #[test]
    fn all_presets_resolve_and_validate() {
        for p in PRESETS {
            let tf = TransferFunction::preset(p, &hist()).unwrap();
            tf.validate().unwrap();
            assert!(tf.breakpoints().len() >= 2, "{p}");
        }
        assert!(TransferFunction::preset("nope", &hist()).is_err());
    }

    #[test]
    fn opacity_converts_to_extinction() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0, 1, 1, 1]], "opacity": [[0, 0.5], [10, 0.5]], "opacity_step": 2.0}"#,
        )
        .unwrap()
        .resolved([0.0, 10.0]);
        let tau = tf.tau_per_world(5.0);
        assert!((1.0 - (-tau * 2.0).exp() - 0.5).abs() < 1e-9);
    }

    #[test]
    fn json_round_trip_and_errors() {
        let tf = TransferFunction::preset("viridis", &hist()).unwrap();
        assert_eq!(TransferFunction::from_json(&tf.to_json()).unwrap(), tf);
        for bad in [
            r#"{"color": []}"#,
            r#"{"color": [[0,1,1,1]], "extinction": [[1, 1], [0, 1]]}"#,
            r#"{"color": [[0,2,1,1]], "extinction": [[0, 1]]}"#,
            r#"{"color": [[0,1,1,1]], "extinction": [[0, -1]]}"#,
            r#"{"color": [[0,1,1,1]]}"#,
        ] {
            assert!(TransferFunction::from_json(bad).is_err(), "{bad}");
        }
    }

    fn json_err(text: &str) -> String {
        TransferFunction::from_json(text).unwrap_err().to_string()
    }

    #[test]
    fn json_shape_errors_name_the_field() {
        let cases = [
            (
                r#"{"color": [[0, 1, 1, 1, 1]], "extinction": [[0, 1]]}"#,
                "color[0]: expected [value, r, g, b] (4 numbers), got 5 numbers",
            ),
            (
                r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1], [1, 1], "abc"]}"#,
                r#"extinction[2]: expected [value, tau] (2 numbers), got "abc""#,
            ),
            (
                r#"{"color": [[0, 1, 1, 1]], "opacity": [[0, 1, 2]]}"#,
                "opacity[0]: expected [value, alpha] (2 numbers), got 3 numbers",
            ),
            (
                r#"{"space": "hu", "color": [[0, 1, 1, 1]], "extinction": [[0, 1]]}"#,
                r#"space: expected "value" or "normalized", got "hu""#,
            ),
            (
                r#"{"colour": [[0, 1, 1, 1]], "extinction": [[0, 1]]}"#,
                r#"unknown field "colour" (expected one of space, color, extinction, opacity, opacity_step, opacity_scale, unit_length)"#,
            ),
            (
                r#"{"color": [[0, 1, 1, 1]], "opacity": [[0, 1]], "opacity_step": 0}"#,
                "opacity_step: expected a positive number, got 0",
            ),
            (
                r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1]], "unit_length": "1"}"#,
                r#"unit_length: expected a positive number, got "1""#,
            ),
            (
                r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 1]], "opacity_scale": -1}"#,
                "opacity_scale: expected a number >= 0, got -1",
            ),
            (
                r#"{"color": 3, "extinction": [[0, 1]]}"#,
                "color: expected a list of [value, r, g, b] points, got 3",
            ),
            (
                r#"{"extinction": [[0, 1]]}"#,
                r#"missing field "color" (a list of [value, r, g, b] points)"#,
            ),
            (
                "[1, 2]",
                "expected a JSON object with fields space, color, extinction",
            ),
        ];
        for (text, want) in cases {
            let e = json_err(text);
            assert!(e.starts_with("invalid transfer function: "), "{e}");
            assert!(e.contains(want), "{text}: got {e}, want {want}");
        }
    }

    #[test]
    fn json_syntax_errors_keep_line_and_column() {
        let e = json_err("{\"color\": [[0, 1, 1, 1]],, }");
        assert!(
            e.starts_with("JSON: ") && e.contains("line 1 column"),
            "{e}"
        );
    }

    #[test]
    fn json_defaults_are_the_documented_ones() {
        let tf = TransferFunction::from_json(r#"{"color": [[0, 1, 1, 1]], "opacity": [[0, 0.5]]}"#)
            .unwrap();
        assert_eq!(tf.space, Space::Value);
        assert_eq!(
            (tf.opacity_step, tf.opacity_scale, tf.unit_length),
            (1.0, 1.0, 1.0)
        );
    }

    fn tf(text: &str) -> TransferFunction {
        TransferFunction::from_json(text).unwrap()
    }

    /// Positions from -5 to 45 in steps of 0.37 (inside, between and outside the points).
    fn probes() -> impl Iterator<Item = f64> {
        (0..135).map(|i| -5.0 + 0.37 * i as f64)
    }

    #[test]
    fn one_layer_reproduces_the_original() {
        let a = tf(r#"{"color": [[0,0,0,0],[10,1,0.5,0],[30,0.2,0.9,1]],
            "extinction": [[2,0],[12,3],[25,1]], "opacity_scale": 2, "unit_length": 0.5}"#);
        let l = TransferFunction::layered(&[(a.clone(), 1.0)]).unwrap();
        assert_eq!(
            (l.space, l.unit_length, l.opacity_scale),
            (Space::Value, 0.5, 1.0)
        );
        for s in probes() {
            assert!(
                (l.tau_per_world(s) - a.tau_per_world(s)).abs() < 1e-9,
                "{s}"
            );
            let (p, q) = (l.color_at(s), a.color_at(s));
            assert!(
                (0..3).all(|k| (p[k] - q[k]).abs() < 1e-9),
                "{s}: {p:?} {q:?}"
            );
        }
    }

    #[test]
    fn opacity_layers_are_converted() {
        let a = tf(r#"{"color": [[0,1,0,0]], "opacity": [[0,0.1],[10,0.8]], "opacity_step": 0.5}"#);
        let l = TransferFunction::layered(&[(a.clone(), 1.0)]).unwrap();
        let r = a.resolved([0.0, 1.0]);
        for s in probes() {
            assert!(
                (l.tau_per_world(s) - r.tau_per_world(s)).abs() < 1e-9,
                "{s}"
            );
        }
        assert!(l.tau_per_world(5.0) > 0.0);
    }

    #[test]
    fn disjoint_layers_keep_their_colours_and_sum_extinction() {
        let a = tf(r#"{"color": [[0,1,0,0]], "extinction": [[0,0],[1,1],[9,1],[10,0]]}"#);
        let b = tf(r#"{"color": [[0,0,0,1]], "extinction": [[20,0],[21,2],[29,2],[30,0]]}"#);
        let l = TransferFunction::layered(&[(a.clone(), 1.0), (b.clone(), 1.0)]).unwrap();
        for s in probes() {
            let sum = a.tau_per_world(s) + b.tau_per_world(s);
            assert!((l.tau_per_world(s) - sum).abs() < 1e-9, "{s}");
        }
        let close = |p: [f64; 3], q: [f64; 3]| (0..3).all(|k| (p[k] - q[k]).abs() < 1e-9);
        for s in [0.5, 5.0, 9.5] {
            assert!(
                close(l.color_at(s), [1.0, 0.0, 0.0]),
                "{s}: {:?}",
                l.color_at(s)
            );
        }
        for s in [20.5, 25.0, 29.5] {
            assert!(
                close(l.color_at(s), [0.0, 0.0, 1.0]),
                "{s}: {:?}",
                l.color_at(s)
            );
        }
        // Where neither absorbs the colour is the plain average.
        assert!(close(l.color_at(15.0), [0.5, 0.0, 0.5]));
    }

    #[test]
    fn overlapping_layers_mix_by_extinction() {
        let a = tf(r#"{"color": [[0,1,0,0]], "extinction": [[0,1]]}"#);
        let b = tf(r#"{"color": [[0,0,0,1]], "extinction": [[0,3]], "unit_length": 2}"#);
        // b absorbs 1.5 per world unit, a 1: red share 1 / 2.5.
        let l = TransferFunction::layered(&[(a, 1.0), (b, 1.0)]).unwrap();
        let c = l.color_at(0.0);
        assert!(
            (c[0] - 0.4).abs() < 1e-9 && (c[2] - 0.6).abs() < 1e-9,
            "{c:?}"
        );
        assert!((l.tau_per_world(0.0) - 2.5).abs() < 1e-9);
    }

    #[test]
    fn weights_scale_extinction() {
        let a = tf(r#"{"color": [[0,1,1,1]], "extinction": [[0,0],[10,4]]}"#);
        let l = TransferFunction::layered(&[(a.clone(), 0.2)]).unwrap();
        for s in probes() {
            assert!(
                (l.tau_per_world(s) - 0.2 * a.tau_per_world(s)).abs() < 1e-9,
                "{s}"
            );
        }
    }

    #[test]
    fn layered_rejects_bad_layers() {
        let a = tf(r#"{"color": [[0,1,1,1]], "extinction": [[0,1]]}"#);
        let norm = TransferFunction {
            space: Space::Normalized,
            ..a.clone()
        };
        let empty = TransferFunction {
            color: Vec::new(),
            ..a.clone()
        };
        let err = |layers: &[(TransferFunction, f64)]| {
            TransferFunction::layered(layers).unwrap_err().to_string()
        };
        assert!(err(&[]).contains("at least one layer"));
        assert!(err(&[(a.clone(), -1.0)]).contains("layer 0: weight -1"));
        assert!(err(&[(a.clone(), f64::NAN)]).contains("weight NaN"));
        assert!(err(&[(a.clone(), f64::INFINITY)]).contains("weight inf"));
        assert!(err(&[(a.clone(), 1.0), (norm, 1.0)]).contains("layer 1: not in value space"));
        assert!(err(&[(empty, 1.0)]).contains("layer 0: no colour control points"));
    }

    #[test]
    fn layer_samples_subdivide_each_interval() {
        let a = tf(r#"{"color": [[0,1,1,1],[9,1,1,1]], "extinction": [[18,1]]}"#);
        let s = layer_samples(&[(a, 1.0)]);
        assert_eq!(s.len(), 2 * 9 + 1);
        assert_eq!((s[0], s[1], s[9], s[18]), (0.0, 1.0, 9.0, 18.0));
    }

    #[test]
    fn colormap_at_interpolates_the_stops() {
        let lin = |c: [f64; 3]| c.map(srgb);
        assert_eq!(colormap_at(&INFERNO, 0.0), lin(INFERNO[0]));
        assert_eq!(colormap_at(&INFERNO, 1.0), lin(INFERNO[4]));
        assert_eq!(colormap_at(&INFERNO, 0.5), lin(INFERNO[2]));
        assert_eq!(colormap_at(&VIRIDIS, 7.0), lin(VIRIDIS[4]));
        assert_eq!(colormap_at(&VIRIDIS, -1.0), lin(VIRIDIS[0]));
        assert_eq!(colormap_at(&VIRIDIS, f64::NAN), lin(VIRIDIS[0]));
        let mid = colormap_at(&[[0.0; 3], [1.0; 3]], 0.5);
        assert!((mid[0] - srgb(0.5)).abs() < 1e-12);
        assert_eq!(colormap_at(&[[0.2, 0.4, 0.6]], 0.7), lin([0.2, 0.4, 0.6]));
        assert_eq!(colormap_at(&[], 0.5), [0.0; 3]);
    }

    #[test]
    fn interpolates_linearly() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0,0,0,0],[10,1,0.5,0]], "extinction": [[0,0],[10,2]]}"#,
        )
        .unwrap();
        assert!((tf.tau_per_world(2.5) - 0.5).abs() < 1e-12);
        assert!((tf.color_at(5.0)[1] - 0.25).abs() < 1e-12);
        assert_eq!(tf.tau_per_world(-5.0), 0.0);
        assert_eq!(tf.tau_per_world(50.0), 2.0);
    }
}
