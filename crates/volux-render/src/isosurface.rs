//! Isosurfaces along a ray: which isovalues a ray step crosses, and where.
//!
//! The seed `002` (§4.6) renders isosurfaces as Phong-lit, possibly semi-transparent layers
//! composited with the volume. A traversal that samples the field at consecutive distances
//! `t_a < t_b` asks [`Isosurfaces::crossings`] for the isovalues crossed in `(t_a, t_b]`; each
//! crossing is located by root refinement on the field itself (not by linear interpolation of
//! the two samples), then shaded with [`crate::shading`] and composited with its RGBA.
//!
//! Detection only sees the two samples: an isovalue is crossed when it lies between `v_a`
//! and `v_b`. A field that is not monotonic between samples can cross an isovalue twice (or
//! any even number of times) without a sign change, and such crossings are missed; with an
//! odd number, one of them is found. Smaller steps are the cure.
use serde::{Deserialize, Serialize};

/// One isosurface: a scalar value and the colour and opacity it is drawn with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Isovalue {
    /// The scalar value (data units).
    pub value: f32,
    /// Linear RGB colour and opacity (not premultiplied), each in `[0, 1]`.
    pub rgba: [f32; 4],
}

/// A crossing of an isosurface by a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Distance along the ray (in the units of the `t` given to
    /// [`Isosurfaces::crossings`]).
    pub t: f64,
    /// Index of the isovalue in [`Isosurfaces::as_slice`].
    pub iso_index: usize,
}

/// A set of isovalues, sorted by value (ties keep their given order).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Vec<Isovalue>", into = "Vec<Isovalue>")]
pub struct Isosurfaces(Vec<Isovalue>);

impl TryFrom<Vec<Isovalue>> for Isosurfaces {
    type Error = String;
    fn try_from(v: Vec<Isovalue>) -> Result<Self, String> {
        Self::new(v)
    }
}

impl From<Isosurfaces> for Vec<Isovalue> {
    fn from(s: Isosurfaces) -> Self {
        s.0
    }
}

impl Isosurfaces {
    /// Crossings are located to within this fraction of the step `|t_b - t_a|` (1e-4 voxel
    /// for steps up to 10 voxels, whatever the unit of `t`).
    pub const REL_TOL: f64 = 1e-5;
    /// Most field samples spent refining one crossing.
    pub const MAX_ITERATIONS: usize = 32;

    /// The isovalues, sorted by value. Errors on a non-finite value or an RGBA component
    /// outside `[0, 1]`.
    pub fn new(mut values: Vec<Isovalue>) -> Result<Self, String> {
        for iso in &values {
            check(iso)?;
        }
        values.sort_by(|a, b| a.value.total_cmp(&b.value));
        Ok(Self(values))
    }

    /// The isovalues, sorted by value.
    pub fn as_slice(&self) -> &[Isovalue] {
        &self.0
    }

    /// Number of isovalues.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Appends to `out` every crossing of an isovalue between the samples `v_a` at `t_a` and
    /// `v_b` at `t_b`, sorted by `t` (so a traversal calling this for consecutive steps
    /// accumulates the crossings of its whole ray in order).
    ///
    /// - An isovalue `c` is crossed in `(t_a, t_b]` when it lies in `(v_a, v_b]` (rising) or
    ///   `[v_b, v_a)` (falling): a sample exactly on `c` counts for the interval it *ends*,
    ///   never for the next one, so a surface through a sample is reported once (at that
    ///   sample's `t`, with no refinement), and a plateau at exactly `c` only where it starts.
    ///   Consequently a sample on `c` at the very first `t_a` of a ray is not reported.
    /// - Otherwise the crossing is refined with the Illinois variant of regula falsi on
    ///   `sample` (the field at any `t`), falling back to bisection, to within
    ///   [`REL_TOL`](Self::REL_TOL) of the step; typically 3 to 5 samples per crossing.
    /// - Only sign changes at the two samples are seen (see the module documentation).
    /// - Non-finite `t` or `v` give no crossing; a non-finite refinement sample ends the
    ///   refinement with the current secant estimate. Never panics.
    pub fn crossings(
        &self,
        t_a: f64,
        v_a: f32,
        t_b: f64,
        v_b: f32,
        mut sample: impl FnMut(f64) -> f32,
        out: &mut Vec<Crossing>,
    ) {
        if !(t_a.is_finite() && t_b.is_finite() && v_a.is_finite() && v_b.is_finite())
            || v_a == v_b
            || self.0.is_empty()
        {
            return;
        }
        // Isovalues in (v_a, v_b] or [v_b, v_a), by binary search on the sorted values.
        let (first, last) = if v_a < v_b {
            (
                self.0.partition_point(|i| i.value <= v_a),
                self.0.partition_point(|i| i.value <= v_b),
            )
        } else {
            (
                self.0.partition_point(|i| i.value < v_b),
                self.0.partition_point(|i| i.value < v_a),
            )
        };
        if first >= last {
            return;
        }
        let start = out.len();
        let tol = Self::REL_TOL * (t_b - t_a).abs();
        for (k, iso) in self.0[first..last].iter().enumerate() {
            let c = iso.value;
            let t = if v_b == c {
                t_b
            } else {
                refine(t_a, v_a - c, t_b, v_b - c, tol, |t| sample(t) - c)
            };
            out.push(Crossing {
                t,
                iso_index: first + k,
            });
        }
        // Monotonic fields give value order (reversed when falling); sort for the rest.
        out[start..].sort_by(|a, b| a.t.total_cmp(&b.t));
    }
}

fn check(iso: &Isovalue) -> Result<(), String> {
    if !iso.value.is_finite() {
        return Err(format!("isovalue {} must be finite", iso.value));
    }
    if let Some(c) = iso.rgba.iter().find(|c| !(0.0..=1.0).contains(*c)) {
        return Err(format!(
            "isovalue {}: colour component {c} must be in [0, 1]",
            iso.value
        ));
    }
    Ok(())
}

/// A root of `f` between `a` and `b` where `fa = f(a)` and `fb = f(b)` are non-zero with
/// opposite signs: Illinois regula falsi with a bisection safeguard, until the bracket is
/// narrower than `tol` or `MAX_ITERATIONS` samples are spent.
fn refine(
    mut a: f64,
    mut fa: f32,
    mut b: f64,
    mut fb: f32,
    tol: f64,
    mut f: impl FnMut(f64) -> f32,
) -> f64 {
    let secant = |a: f64, fa: f32, b: f64, fb: f32| {
        let (fa, fb) = (fa as f64, fb as f64);
        let t = a - fa * (b - a) / (fb - fa);
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if t > lo && t < hi {
            t
        } else {
            0.5 * (a + b)
        }
    };
    // Which end was kept last time (+1: a, -1: b), for the Illinois halving.
    let mut kept = 0i8;
    let mut width = (b - a).abs();
    for it in 0..Isosurfaces::MAX_ITERATIONS {
        if (b - a).abs() <= tol {
            break;
        }
        // Every third step, bisect if the bracket has not at least halved in the last two.
        let t = if it % 3 == 2 && (b - a).abs() > 0.5 * width {
            0.5 * (a + b)
        } else {
            secant(a, fa, b, fb)
        };
        if it % 3 == 2 {
            width = (b - a).abs();
        }
        let ft = f(t);
        if ft == 0.0 {
            return t;
        }
        if !ft.is_finite() {
            break;
        }
        if (ft < 0.0) == (fb < 0.0) {
            b = t;
            fb = ft;
            if kept == 1 {
                fa *= 0.5;
            }
            kept = 1;
        } else {
            a = t;
            fa = ft;
            if kept == -1 {
                fb *= 0.5;
            }
            kept = -1;
        }
    }
    secant(a, fa, b, fb)
}

/// Parses the CLI form `VALUE:R,G,B,A` (e.g. `-500:1,0.9,0.8,0.5`; components in `[0, 1]`,
/// spaces allowed around numbers).
pub fn parse_iso(spec: &str) -> Result<Isovalue, String> {
    let usage = "expected VALUE:R,G,B,A with R, G, B, A in [0, 1], e.g. 500:1,0.9,0.8,0.5";
    let (value, rgba) = spec
        .split_once(':')
        .ok_or_else(|| format!("isosurface {spec:?}: missing ':' ({usage})"))?;
    let value: f32 = value.trim().parse().map_err(|_| {
        format!(
            "isosurface {spec:?}: value {:?} is not a number",
            value.trim()
        )
    })?;
    let parts: Vec<&str> = rgba.split(',').collect();
    if parts.len() != 4 {
        return Err(format!(
            "isosurface {spec:?}: {} colour components, {usage}",
            parts.len()
        ));
    }
    let mut c = [0.0f32; 4];
    for (slot, (name, part)) in c.iter_mut().zip(["R", "G", "B", "A"].iter().zip(&parts)) {
        *slot = part.trim().parse().map_err(|_| {
            format!(
                "isosurface {spec:?}: {name} {:?} is not a number",
                part.trim()
            )
        })?;
    }
    let iso = Isovalue { value, rgba: c };
    check(&iso).map_err(|e| format!("isosurface {spec:?}: {e}"))?;
    Ok(iso)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn isos(values: &[f32]) -> Isosurfaces {
        Isosurfaces::new(
            values
                .iter()
                .map(|&value| Isovalue {
                    value,
                    rgba: [1.0; 4],
                })
                .collect(),
        )
        .unwrap()
    }

    /// Walks `v` from `t0` to `t1` with step `h`, as a traversal would.
    fn walk(s: &Isosurfaces, v: impl Fn(f64) -> f32, t0: f64, t1: f64, h: f64) -> Vec<Crossing> {
        let mut out = Vec::new();
        let n = ((t1 - t0) / h).round() as usize;
        for i in 0..n {
            let (ta, tb) = (t0 + i as f64 * h, t0 + (i + 1) as f64 * h);
            s.crossings(ta, v(ta), tb, v(tb), &v, &mut out);
        }
        out
    }

    #[test]
    fn crossings_of_sin_match_the_exact_roots() {
        let s = isos(&[-0.3, 0.0, 0.5]);
        let calls = std::cell::Cell::new(0usize);
        let v = |t: f64| {
            calls.set(calls.get() + 1);
            t.sin() as f32
        };
        let (t0, t1, h) = (0.1, 20.1, 0.5);
        let got = walk(&s, v, t0, t1, h);
        let mut exact = Vec::new();
        for (idx, c) in [(0usize, -0.3f64), (1, 0.0), (2, 0.5)] {
            let r = c.asin();
            for k in -1..8 {
                let base = 2.0 * std::f64::consts::PI * k as f64;
                for t in [base + r, base + std::f64::consts::PI - r] {
                    if t > t0 && t <= t1 {
                        exact.push((t, idx));
                    }
                }
            }
        }
        exact.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(got.len(), exact.len(), "{got:?}");
        for (g, (t, idx)) in got.iter().zip(&exact) {
            assert_eq!(g.iso_index, *idx);
            // f32 samples: the value error near a root is ~1e-7, far below 1e-4 in t.
            assert!((g.t - t).abs() < 1e-4, "{} vs {t}", g.t);
        }
        // Sorted along the ray.
        assert!(got.windows(2).all(|w| w[0].t <= w[1].t));
        let samples = 2 * (((t1 - t0) / h).round() as usize);
        let per_crossing = (calls.get() - samples) as f64 / got.len() as f64;
        assert!(
            per_crossing <= 8.0,
            "{per_crossing} refinement samples per crossing"
        );
    }

    #[test]
    fn several_isovalues_in_one_step_come_out_sorted_by_t() {
        let s = isos(&[0.8, 0.2, 0.5]);
        assert_eq!(
            s.as_slice().iter().map(|i| i.value).collect::<Vec<_>>(),
            [0.2, 0.5, 0.8]
        );
        let mut out = Vec::new();
        // Rising: 0.2 first.
        let rise = |t: f64| (t * t) as f32;
        s.crossings(0.0, 0.0, 1.0, 1.0, rise, &mut out);
        let idx: Vec<_> = out.iter().map(|c| c.iso_index).collect();
        assert_eq!(idx, [0, 1, 2]);
        for (c, v) in out.iter().zip([0.2f64, 0.5, 0.8]) {
            assert!((c.t - v.sqrt()).abs() < 1e-5, "{c:?}");
        }
        // Falling: 0.8 first; appended after the earlier crossings.
        let fall = |t: f64| (1.0 - t) as f32;
        s.crossings(2.0, 1.0, 3.0, 0.0, |t| fall(t - 2.0), &mut out);
        let idx: Vec<_> = out[3..].iter().map(|c| c.iso_index).collect();
        assert_eq!(idx, [2, 1, 0]);
        assert!(out.windows(2).all(|w| w[0].t <= w[1].t));
    }

    #[test]
    fn exact_hits_are_counted_once() {
        let s = isos(&[0.5]);
        // Samples 0, 0.5, 1 (linear): the hit at t = 1 belongs to (0, 1] only.
        let lin = |t: f64| (0.5 * t) as f32;
        let got = walk(&s, lin, 0.0, 2.0, 1.0);
        assert_eq!(
            got,
            [Crossing {
                t: 1.0,
                iso_index: 0
            }]
        );
        // A touch (0, 0.5, 0): reported once, where it happens.
        let tent = |t: f64| (0.5 - (t - 1.0).abs() * 0.5) as f32;
        assert_eq!(walk(&s, tent, 0.0, 2.0, 1.0).len(), 1);
        // A plateau at exactly the isovalue: once, where it starts.
        let plateau = |t: f64| if t < 1.0 { (0.5 * t) as f32 } else { 0.5 };
        assert_eq!(
            walk(&s, plateau, 0.0, 4.0, 1.0),
            [Crossing {
                t: 1.0,
                iso_index: 0
            }]
        );
        // Leaving the isovalue from an exact sample is not a new crossing.
        let mut out = Vec::new();
        s.crossings(1.0, 0.5, 2.0, 1.0, lin, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn odd_inputs_do_not_panic() {
        let s = isos(&[0.5]);
        let mut out = Vec::new();
        s.crossings(0.0, f32::NAN, 1.0, 1.0, |_| 0.0, &mut out);
        s.crossings(f64::NAN, 0.0, 1.0, 1.0, |_| 0.0, &mut out);
        s.crossings(0.0, 0.0, 1.0, f32::INFINITY, |_| 0.0, &mut out);
        assert!(out.is_empty());
        // Undefined field inside the step: still one crossing, inside the step.
        s.crossings(0.0, 0.0, 1.0, 1.0, |_| f32::NAN, &mut out);
        assert_eq!(out.len(), 1);
        assert!(out[0].t > 0.0 && out[0].t < 1.0);
        // A step given backwards works too.
        out.clear();
        s.crossings(1.0, 0.0, 0.0, 1.0, |t| (1.0 - t) as f32, &mut out);
        assert!((out[0].t - 0.5).abs() < 1e-5);
        assert!(Isosurfaces::new(vec![Isovalue {
            value: f32::NAN,
            rgba: [1.0; 4]
        }])
        .is_err());
        let mut none = Vec::new();
        Isosurfaces::default().crossings(0.0, 0.0, 1.0, 1.0, |_| 0.0, &mut none);
        assert!(none.is_empty());
    }

    #[test]
    fn parse_iso_accepts_good_specs() {
        assert_eq!(
            parse_iso("500:1,0.9,0.8,0.5").unwrap(),
            Isovalue {
                value: 500.0,
                rgba: [1.0, 0.9, 0.8, 0.5]
            }
        );
        assert_eq!(
            parse_iso(" -1e2 : 0, 0.25 ,1,1 ").unwrap(),
            Isovalue {
                value: -100.0,
                rgba: [0.0, 0.25, 1.0, 1.0]
            }
        );
    }

    #[test]
    fn parse_iso_rejects_bad_specs_with_clear_messages() {
        let err = |s: &str| parse_iso(s).unwrap_err();
        assert!(err("500").contains("missing ':'"));
        assert!(err("abc:1,1,1,1").contains("value \"abc\" is not a number"));
        assert!(err("500:1,1,1").contains("3 colour components"));
        assert!(err("500:1,1,1,1,1").contains("5 colour components"));
        assert!(err("500:1,x,1,1").contains("G \"x\" is not a number"));
        assert!(err("500:1,1,1,2").contains("colour component 2 must be in [0, 1]"));
        assert!(err("nan:1,1,1,1").contains("must be finite"));
        assert!(err("500:1,1,NaN,1").contains("must be in [0, 1]"));
        assert!(err("").contains("expected VALUE:R,G,B,A"));
    }
}
