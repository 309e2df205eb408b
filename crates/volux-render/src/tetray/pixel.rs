//! One pixel of the tetrahedral ray caster: its ray walked through the mesh (seed `000`
//! §2.4) and coloured in one of three ways.
//!
//! - **Per segment** (exact or ψ colour): each walked segment `(s_in, s_out, length)` is
//!   coloured by the projection renderer's fragment shader
//!   ([`FragmentShader::fragment`], one implementation with PT), isosurfaces included
//!   (seed `002` §4.6: the segment is cut at its crossings, each lit with the normal
//!   interpolated between the gradients at the segment's end points), and composited front
//!   to back.
//! - **Adaptive Simpson** (seed `001` ch. 4, Algorithms 3 and 4): the segments are collected
//!   and the whole ray is integrated with [`adaptive_simpson_intervals`] over a
//!   [`SegmentMedium`], across cell boundaries, the contiguous runs of segments being the
//!   intervals (the gaps of a non-convex mesh are empty space, zero extinction). With
//!   isosurfaces, the ray is cut at their crossings and each piece is integrated with the
//!   share of the tolerance its length has, so the errors still add up to at most `tol`.
//! - **MIP**: the largest scalar along the ray is the largest segment end point (the field
//!   is linear in each cell), shown with its TF colour, opaque, as the grid MIP
//!   ([`crate::mip`]) does.
use glam::{DVec3, Vec3};
use volux_core::voi::{clip_by_planes, ClipPlane};
use volux_core::{TetMesh, TransferFunction};

use super::options::TetRayOptions;
use super::tables::Tables;
use super::walk::{Scratch, VisibleRay, WalkOutcome, WalkSegment, Walker};
use crate::composite::under64;
use crate::integrate::adaptive::{adaptive_simpson_intervals, AdaptiveParams};
use crate::integrate::fragment::FragmentShader;
use crate::integrate::psi::PsiTable;
use crate::integrate::SegmentRule;
use crate::integrate::{hides_breakpoints, hides_breakpoints_along, Medium, RayMedium};
use crate::isosurface::Isovalue;
use crate::shading::BlinnPhong;

/// What one pixel produced.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PixelOut {
    /// Premultiplied RGBA.
    pub rgba: [f32; 4],
    /// Estimated absolute error (adaptive rule), 0 otherwise.
    pub error: f32,
    /// Scalar values evaluated.
    pub samples: u64,
    /// Whether the adaptive rule accepted a step over its tolerance.
    pub missed: bool,
}

/// How the pixels of a frame are coloured.
enum Mode {
    Segments,
    Adaptive(AdaptiveParams),
    Mip,
}

/// Everything a pixel needs, shared by all pixels of a frame.
pub(crate) struct PixelContext<'a> {
    mesh: &'a TetMesh,
    mode: Mode,
    /// The colour of segments (average, ψ or exact; exact for the adaptive rule's pieces).
    rule: SegmentRule,
    tables: &'a Tables,
    psi: &'a PsiTable,
    isosurfaces: &'a [Isovalue],
    shading: BlinnPhong,
    gradients: &'a [Vec3],
    early: Option<f64>,
    clip: &'a [ClipPlane],
}

/// The part of the segment `s` inside the ray window `[c0, c1]` (the scalar interpolated
/// linearly, as the field is within a cell); `None` when none of it is.
fn trim(s: &WalkSegment, (c0, c1): (f64, f64)) -> Option<WalkSegment> {
    if s.t_out <= c0 || s.t_in >= c1 {
        return None;
    }
    let at = |t: f64| s.s_in + (s.s_out - s.s_in) * ((t - s.t_in) / (s.t_out - s.t_in));
    let mut out = *s;
    if s.t_in < c0 {
        (out.t_in, out.s_in) = (c0, at(c0));
    }
    if s.t_out > c1 {
        (out.t_out, out.s_out) = (c1, at(c1));
    }
    Some(out)
}

impl<'a> PixelContext<'a> {
    /// The context of a frame: `tables` classify with its TF, `gradients` are the vertex
    /// gradients (may be empty when there are no isosurfaces), `psi` the ψ table (read only
    /// with the ψ rule).
    pub fn new(
        mesh: &'a TetMesh,
        opts: &'a TetRayOptions,
        tables: &'a Tables,
        gradients: &'a [Vec3],
        psi: &'a PsiTable,
    ) -> Self {
        let mode = match (opts.mip, opts.color) {
            (true, _) => Mode::Mip,
            (false, SegmentRule::AdaptiveSimpson(p)) => Mode::Adaptive(p),
            _ => Mode::Segments,
        };
        let rule = match (&mode, opts.color) {
            (Mode::Segments, rule @ (SegmentRule::Average | SegmentRule::Psi)) => rule,
            _ => SegmentRule::Exact,
        };
        Self {
            mesh,
            mode,
            rule,
            tables,
            psi,
            isosurfaces: opts.isosurfaces.as_slice(),
            shading: opts.shading,
            gradients,
            early: opts.early_termination.map(f64::from),
            clip: &opts.clip_planes,
        }
    }

    /// The projection renderer's fragment shader with this frame's tables.
    fn shader(&self) -> FragmentShader<'_> {
        FragmentShader {
            mode: self.rule,
            exact: &self.tables.exact,
            classifier: &self.tables.classifier,
            psi: self.psi,
            knots: &self.tables.knots,
            isosurfaces: self.isosurfaces,
            shading: self.shading,
        }
    }

    /// Premultiplied RGBA of one segment without isosurfaces, in `f64` (exact, or the `f32`
    /// average or ψ colour).
    #[inline]
    fn segment(&self, s: &WalkSegment) -> [f64; 4] {
        let len = s.t_out - s.t_in;
        match self.rule {
            SegmentRule::Average | SegmentRule::Psi => self
                .shader()
                .segment(s.s_in as f32, s.s_out as f32, len as f32)
                .map(f64::from),
            _ => self.tables.exact.integrate(s.s_in, s.s_out, len),
        }
    }

    /// The gradient at point `p` of cell `tet`: the vertex gradients interpolated with the
    /// barycentric coordinates of `p`.
    fn gradient_at(&self, tet: u32, p: DVec3) -> Vec3 {
        let t = tet as usize;
        let v = self.mesh.tets()[t];
        let g = v.map(|i| {
            self.gradients
                .get(i as usize)
                .copied()
                .unwrap_or(Vec3::ZERO)
        });
        let x = self.mesh.tet_positions(t).map(|q| q.as_dvec3());
        let (e1, e2, e3, dp) = (x[1] - x[0], x[2] - x[0], x[3] - x[0], p - x[0]);
        let det = e1.cross(e2).dot(e3);
        if !(det.is_finite() && det != 0.0) {
            return (g[0] + g[1] + g[2] + g[3]) * 0.25;
        }
        let l1 = dp.cross(e2).dot(e3) / det;
        let l2 = e1.cross(dp).dot(e3) / det;
        let l3 = e1.cross(e2).dot(dp) / det;
        let l = [1.0 - l1 - l2 - l3, l1, l2, l3].map(|l| l as f32);
        g[0] * l[0] + g[1] * l[1] + g[2] * l[2] + g[3] * l[3]
    }

    /// The gradients at the entry and exit of a segment of the ray `o + t d`.
    fn segment_gradients(&self, o: DVec3, d: DVec3, s: &WalkSegment) -> (Vec3, Vec3) {
        (
            self.gradient_at(s.tet, o + d * s.t_in),
            self.gradient_at(s.tet, o + d * s.t_out),
        )
    }

    /// Walks the ray `o + t d` and colours it; `segments` is scratch space. With `visible`
    /// (per-segment colours only: the visible cells and the ray parameter past which none is
    /// met) the walk leaves out the cells that colour as transparent black
    /// ([`super::skip`]), which does not change the pixel.
    pub fn pixel(
        &self,
        walker: &Walker<'_>,
        visible: Option<VisibleRay<'_>>,
        o: DVec3,
        d: DVec3,
        scratch: &mut Scratch,
        segments: &mut Vec<WalkSegment>,
    ) -> (PixelOut, WalkOutcome) {
        let all = (f64::NEG_INFINITY, f64::INFINITY);
        let Some(window) = clip_by_planes(self.clip, o, d, all) else {
            return (PixelOut::default(), WalkOutcome::default());
        };
        match self.mode {
            Mode::Segments => {
                let mut acc = [0.0f64; 4];
                let shader = self.shader();
                let view = d.as_vec3();
                let iso = !self.isosurfaces.is_empty();
                let sink = |s: &WalkSegment| {
                    // Segments before the clipped window are passed, the first after it ends
                    // the walk.
                    let Some(s) = &trim(s, window) else {
                        return s.t_in < window.1;
                    };
                    let c = if iso {
                        shader
                            .fragment(
                                s.s_in as f32,
                                s.s_out as f32,
                                (s.t_out - s.t_in) as f32,
                                || self.segment_gradients(o, d, s),
                                || view,
                            )
                            .map(f64::from)
                    } else {
                        self.segment(s)
                    };
                    under64(&mut acc, c);
                    self.early.is_none_or(|e| acc[3] < e)
                };
                let outcome = match visible {
                    Some(start) => walker.trace_visible(&start, o, d, sink),
                    None => walker.trace(o, d, scratch, sink),
                };
                let out = PixelOut {
                    rgba: acc.map(|v| v as f32),
                    samples: 2 * outcome.segments,
                    ..PixelOut::default()
                };
                (out, outcome)
            }
            Mode::Mip => {
                let mut best: Option<f64> = None;
                let outcome = walker.trace(o, d, scratch, |s| {
                    let Some(s) = trim(s, window) else {
                        return s.t_in < window.1;
                    };
                    let m = s.s_in.max(s.s_out);
                    if m.is_finite() {
                        best = Some(best.map_or(m, |b| b.max(m)));
                    }
                    true
                });
                let rgba = match best {
                    Some(v) => {
                        let c = self.tables.tf.color_at(v);
                        [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
                    }
                    None => [0.0; 4],
                };
                let out = PixelOut {
                    rgba,
                    samples: 2 * outcome.segments,
                    ..PixelOut::default()
                };
                (out, outcome)
            }
            Mode::Adaptive(p) => {
                segments.clear();
                let outcome = walker.trace(o, d, scratch, |s| {
                    let Some(s) = trim(s, window) else {
                        return s.t_in < window.1;
                    };
                    segments.push(s);
                    true
                });
                (self.adaptive(o, d, segments, &p), outcome)
            }
        }
    }

    /// The isosurface crossings of the segments, in ray order: `(t, premultiplied RGBA of the
    /// lit surface)`, with the half-open rule of the fragment shader (a value equal to the
    /// exit scalar is left to the next segment).
    fn crossings(&self, o: DVec3, d: DVec3, segs: &[WalkSegment]) -> Vec<(f64, [f64; 4])> {
        let mut cuts = Vec::new();
        if self.isosurfaces.is_empty() {
            return cuts;
        }
        let view = d.as_vec3();
        for s in segs {
            if s.s_in == s.s_out {
                continue;
            }
            let mut grads = None;
            for iso in self.isosurfaces {
                let f = (f64::from(iso.value) - s.s_in) / (s.s_out - s.s_in);
                if !(0.0..1.0).contains(&f) {
                    continue;
                }
                let (gf, gb) = *grads.get_or_insert_with(|| self.segment_gradients(o, d, s));
                let normal = gf + (gb - gf) * f as f32;
                let rgb = self
                    .shading
                    .shade([iso.rgba[0], iso.rgba[1], iso.rgba[2]], normal, view);
                let a = f64::from(iso.rgba[3]);
                cuts.push((
                    s.t_in + f * (s.t_out - s.t_in),
                    [
                        f64::from(rgb[0]) * a,
                        f64::from(rgb[1]) * a,
                        f64::from(rgb[2]) * a,
                        a,
                    ],
                ));
            }
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        cuts
    }

    /// Adaptive Simpson over the whole ray (seed `001` ch. 4), cut at isosurface crossings.
    fn adaptive(&self, o: DVec3, d: DVec3, segs: &[WalkSegment], p: &AdaptiveParams) -> PixelOut {
        let mut out = PixelOut::default();
        if segs.is_empty() {
            return out;
        }
        // Contiguous runs of segments: the intervals; the gaps between them are empty.
        let mut runs: Vec<(f64, f64)> = Vec::new();
        for s in segs {
            match runs.last_mut() {
                Some(last) if s.t_in <= last.1 => last.1 = last.1.max(s.t_out),
                _ => runs.push((s.t_in, s.t_out)),
            }
        }
        let total: f64 = runs.iter().map(|r| r.1 - r.0).sum();
        if total.is_nan() || total <= 0.0 {
            return out;
        }
        let cuts = self.crossings(o, d, segs);
        let mut medium = SegmentMedium {
            segs,
            cursor: 0,
            tf: &self.tables.tf,
            breakpoints: &self.tables.breakpoints,
        };
        let mut acc = [0.0f64; 4];
        let (mut error, mut samples, mut missed) = (0.0f64, 0u64, false);
        let mut t_lo = f64::NEG_INFINITY;
        let mut pieces: Vec<(f64, f64)> = Vec::with_capacity(runs.len());
        let ends = cuts
            .iter()
            .map(|&(t, c)| (t, Some(c)))
            .chain(std::iter::once((f64::INFINITY, None)));
        for (t_hi, surface) in ends {
            pieces.clear();
            pieces.extend(
                runs.iter()
                    .map(|&(a, b)| (a.max(t_lo), b.min(t_hi)))
                    .filter(|(a, b)| b > a),
            );
            let len: f64 = pieces.iter().map(|r| r.1 - r.0).sum();
            if len > 0.0 {
                let early = self.early.map(|e| {
                    if acc[3] < 1.0 {
                        (e - acc[3]) / (1.0 - acc[3])
                    } else {
                        0.0
                    }
                });
                let params = AdaptiveParams {
                    tol: p.tol * len / total,
                    early_termination: early,
                    ..*p
                };
                let r = adaptive_simpson_intervals(&mut medium, &pieces, &params);
                error += (1.0 - acc[3]) * r.error;
                samples += r.samples;
                missed |= r.tolerance_missed;
                under64(&mut acc, r.rgba);
            }
            if let Some(c) = surface {
                under64(&mut acc, c);
            }
            t_lo = t_hi;
            if self.early.is_some_and(|e| acc[3] >= e) {
                break;
            }
        }
        out.rgba = acc.map(|v| v as f32);
        out.error = error as f32;
        out.samples = samples;
        out.missed = missed;
        out
    }
}

/// The classified medium along one ray, as the adaptive integrator sees it (seed `001`
/// ch. 4): the scalar linear within each walked segment, classified exactly by the resolved
/// TF; zero extinction between segments. Samples arrive nearly in order, so a cursor finds
/// the segment of `t` in amortized constant time.
pub(crate) struct SegmentMedium<'s> {
    /// The walked segments, front to back.
    pub segs: &'s [WalkSegment],
    /// The segment of the last sample.
    pub cursor: usize,
    /// The TF, resolved against the mesh's range.
    pub tf: &'s TransferFunction,
    /// The TF's breakpoints, sorted ([`TransferFunction::breakpoints`]).
    pub breakpoints: &'s [f64],
}

impl SegmentMedium<'_> {
    /// The scalar at `t`, `None` outside the segments (rounding at a run's ends forgiven).
    pub fn value(&mut self, t: f64) -> Option<f64> {
        let segs = self.segs;
        if segs.is_empty() {
            return None;
        }
        let mut i = self.cursor.min(segs.len() - 1);
        while i > 0 && t < segs[i].t_in {
            i -= 1;
        }
        while i + 1 < segs.len() && t > segs[i].t_out {
            i += 1;
        }
        self.cursor = i;
        let s = &segs[i];
        let len = s.t_out - s.t_in;
        let slack = 1e-9 * (len + t.abs());
        if t < s.t_in - slack || t > s.t_out + slack {
            return None;
        }
        let f = ((t - s.t_in) / len).clamp(0.0, 1.0);
        Some(s.s_in + (s.s_out - s.s_in) * f)
    }
}

impl RayMedium for SegmentMedium<'_> {
    fn at(&mut self, t: f64) -> Medium {
        match self.value(t) {
            Some(v) => Medium {
                rgb: self.tf.color_at(v),
                tau: self.tf.tau_per_world(v),
                value: v,
            },
            None => Medium::default(),
        }
    }

    fn hides_features(&self, a: f64, b: f64) -> bool {
        hides_breakpoints(self.breakpoints, a, b)
    }

    fn hides_features_along(&self, values: &[f64; 5]) -> bool {
        hides_breakpoints_along(self.breakpoints, values)
    }
}
