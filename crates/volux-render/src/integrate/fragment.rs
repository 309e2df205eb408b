//! The colour of one PT fragment: a ray segment through a tetrahedron, from scalar `s_f` at
//! the front to `s_b` at the back over a length `l`, with the isosurfaces it crosses
//! (seed `000` §4.3 and eqs. 2.2-2.3; seed `002` §4.3, §4.4 and §4.6).
//!
//! Three optical models, one per segment rule ([`SegmentRule`]; the adaptive rule, which
//! integrates whole rays, colours the segments it is given exactly):
//! - `average`: Shirley and Tuchman's averaged colour and extinction
//!   ([`psi::average_fragment`]);
//! - `psi`: Moreland and Angel's partial pre-integration ([`psi::psi_fragment`]);
//! - `exact`: the closed-form integral of the linear segment for the piecewise-linear TF
//!   ([`SegmentIntegrator`]), the same function the ray casters use.
//!
//! # Isosurfaces (`002` §4.6)
//!
//! An isovalue `v` strictly between `s_f` and `s_b` (half-open, `t = (v - s_f)/(s_b - s_f)`
//! in `[0, 1)`, so a surface through a shared face is drawn by one cell only) is crossed at
//! `t l`. The segment is cut at its crossings: the volume before the first, the lit surface,
//! the volume to the next, and so on, composited front to back. The surface normal is the
//! gradient interpolated between the front and back gradients at `t`, and the surface is lit
//! with [`BlinnPhong`] (two-sided) and drawn with the isovalue's colour and opacity.
use glam::Vec3;

use super::psi::{self, CellClassifier, LinearPiece, PsiTable};
use super::segment::{SegmentIntegrator, SegmentRule};
use crate::composite::under;
use crate::isosurface::Isovalue;
use crate::shading::blinn_phong::BlinnPhong;

/// Everything a fragment's colour depends on besides its own `(s_f, s_b, l)`.
pub struct FragmentShader<'a> {
    /// The optical model.
    pub mode: SegmentRule,
    /// The exact integrator (for [`SegmentRule::Exact`]).
    pub exact: &'a SegmentIntegrator,
    /// The TF lookup table (for the average and ψ modes).
    pub classifier: &'a CellClassifier,
    /// The ψ table.
    pub psi: &'a PsiTable,
    /// The TF's breakpoints (value space, sorted): the ψ model cuts segments there.
    pub knots: &'a [f32],
    /// Isovalues, sorted by value.
    pub isosurfaces: &'a [Isovalue],
    /// Lighting of the isosurfaces.
    pub shading: BlinnPhong,
}

/// An optical model as a type, so that the per-fragment loop can be compiled once per model
/// (the mode is dispatched once per tile, not once per fragment).
pub trait ColorModel {
    /// Premultiplied RGBA of the volume along a segment of positive finite length.
    fn segment(shader: &FragmentShader<'_>, s_f: f32, s_b: f32, l: f32) -> [f32; 4];

    /// [`ColorModel::segment`] when the TF is `piece` (linear) between `s_f` and `s_b`: no
    /// table lookup and no breakpoint search.
    fn linear(
        shader: &FragmentShader<'_>,
        piece: &LinearPiece,
        s_f: f32,
        s_b: f32,
        l: f32,
    ) -> [f32; 4];
}

/// [`SegmentRule::Average`] as a type.
pub struct AverageModel;
/// [`SegmentRule::Psi`] as a type.
pub struct PsiModel;
/// [`SegmentRule::Exact`] as a type.
pub struct ExactModel;

impl ColorModel for AverageModel {
    #[inline(always)]
    fn segment(shader: &FragmentShader<'_>, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        psi::average_fragment(shader.classifier, s_f, s_b, l)
    }

    /// The mean of the front and back samples of a linear TF is its value at the mean
    /// scalar: one evaluation.
    #[inline(always)]
    fn linear(_: &FragmentShader<'_>, piece: &LinearPiece, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        if !(s_f.is_finite() && s_b.is_finite() && l.is_finite()) {
            return [0.0; 4];
        }
        let mid = piece.at(0.5 * (s_f + s_b));
        psi::average_rgba(mid, mid, l)
    }
}

/// Partial pre-integration is exact for colour and extinction linear along the segment, i.e.
/// for a TF linear between `s_f` and `s_b`. Moreland and Angel, and the seeds, apply it to the
/// whole segment whatever the TF does in between, which on a TF with kinks inside the
/// segment's value range is off by up to 0.7 in a channel (measured in `integrate::psi`).
/// Here a segment whose value range contains breakpoints is cut there, each piece (on which
/// the TF is linear) gets its own ψ colour, and the pieces are composited front to back: the
/// result is then exact up to the table's interpolation error, at the cost of one binary
/// search per fragment and one ψ lookup per piece.
impl ColorModel for PsiModel {
    #[inline(always)]
    fn segment(shader: &FragmentShader<'_>, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        let knots = shader.knots;
        let (lo, hi) = if s_f <= s_b { (s_f, s_b) } else { (s_b, s_f) };
        let first = knots.partition_point(|&k| k <= lo);
        let last = knots.partition_point(|&k| k < hi);
        if first >= last || s_f.is_nan() || s_b.is_nan() {
            return psi::psi_fragment(shader.classifier, shader.psi, s_f, s_b, l);
        }
        psi_pieces(shader, &knots[first..last], s_f, s_b, l)
    }

    #[inline(always)]
    fn linear(
        shader: &FragmentShader<'_>,
        piece: &LinearPiece,
        s_f: f32,
        s_b: f32,
        l: f32,
    ) -> [f32; 4] {
        if !(s_f.is_finite() && s_b.is_finite() && l.is_finite()) {
            return [0.0; 4];
        }
        psi::psi_rgba(shader.psi, piece.at(s_f), piece.at(s_b), l)
    }
}

/// ψ colour of a segment cut at `inner` (the breakpoints strictly inside its value range).
#[inline(never)]
fn psi_pieces(shader: &FragmentShader<'_>, inner: &[f32], s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
    let per_value = l / (s_b - s_f).abs();
    let mut acc = [0.0f32; 4];
    let mut s0 = s_f;
    let mut piece = |s1: f32, acc: &mut [f32; 4]| {
        let len = (s1 - s0).abs() * per_value;
        if len > 0.0 {
            under(
                acc,
                psi::psi_fragment(shader.classifier, shader.psi, s0, s1, len),
            );
        }
        s0 = s1;
    };
    if s_f < s_b {
        inner.iter().for_each(|&k| piece(k, &mut acc));
    } else {
        inner.iter().rev().for_each(|&k| piece(k, &mut acc));
    }
    piece(s_b, &mut acc);
    acc
}

impl ColorModel for ExactModel {
    #[inline(always)]
    fn segment(shader: &FragmentShader<'_>, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        shader
            .exact
            .integrate(f64::from(s_f), f64::from(s_b), f64::from(l))
            .map(|v| v as f32)
    }

    #[inline(always)]
    fn linear(
        shader: &FragmentShader<'_>,
        _: &LinearPiece,
        s_f: f32,
        s_b: f32,
        l: f32,
    ) -> [f32; 4] {
        Self::segment(shader, s_f, s_b, l)
    }
}

impl FragmentShader<'_> {
    /// Premultiplied RGBA of the volume along a segment.
    #[inline]
    pub fn segment(&self, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        match self.mode {
            SegmentRule::Average => self.segment_with::<AverageModel>(s_f, s_b, l),
            SegmentRule::Psi => self.segment_with::<PsiModel>(s_f, s_b, l),
            _ => self.segment_with::<ExactModel>(s_f, s_b, l),
        }
    }

    /// [`FragmentShader::segment`] with the model `M` (which should be the shader's mode).
    #[inline(always)]
    pub fn segment_with<M: ColorModel>(&self, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
        if l.is_nan() || l <= 0.0 {
            return [0.0; 4];
        }
        M::segment(self, s_f, s_b, l)
    }

    /// [`FragmentShader::segment_with`] for a segment whose values lie in a range on which
    /// the TF is `piece` (from [`CellClassifier::linear_on`]).
    #[inline(always)]
    pub fn segment_linear<M: ColorModel>(
        &self,
        piece: &LinearPiece,
        s_f: f32,
        s_b: f32,
        l: f32,
    ) -> [f32; 4] {
        if l.is_nan() || l <= 0.0 {
            return [0.0; 4];
        }
        M::linear(self, piece, s_f, s_b, l)
    }

    /// The TF on `[lo, hi]` as one linear piece, when it is linear there and no isosurface
    /// lies in `[lo, hi]`: fragments whose values stay in that range (those of a cell whose
    /// vertex values span it) can then use [`FragmentShader::segment_linear`] in place of
    /// [`FragmentShader::fragment_with`].
    #[inline]
    pub fn linear_on(&self, lo: f32, hi: f32) -> Option<&LinearPiece> {
        let i = self.isosurfaces.partition_point(|i| i.value < lo);
        if self.isosurfaces.get(i).is_some_and(|i| i.value <= hi) {
            return None;
        }
        self.classifier.linear_on(lo, hi)
    }

    /// Premultiplied RGBA of a fragment, isosurfaces included. `gradients` gives the front
    /// and back gradients (called only when a surface is crossed); `view_dir` is the pixel's
    /// ray direction.
    #[inline]
    pub fn fragment(
        &self,
        s_f: f32,
        s_b: f32,
        l: f32,
        gradients: impl FnOnce() -> (Vec3, Vec3),
        view_dir: impl FnOnce() -> Vec3,
    ) -> [f32; 4] {
        match self.mode {
            SegmentRule::Average => {
                self.fragment_with::<AverageModel>(s_f, s_b, l, gradients, view_dir)
            }
            SegmentRule::Psi => self.fragment_with::<PsiModel>(s_f, s_b, l, gradients, view_dir),
            _ => self.fragment_with::<ExactModel>(s_f, s_b, l, gradients, view_dir),
        }
    }

    /// [`FragmentShader::fragment`] with the model `M` (which should be the shader's mode).
    #[inline(always)]
    pub fn fragment_with<M: ColorModel>(
        &self,
        s_f: f32,
        s_b: f32,
        l: f32,
        gradients: impl FnOnce() -> (Vec3, Vec3),
        view_dir: impl FnOnce() -> Vec3,
    ) -> [f32; 4] {
        if self.isosurfaces.is_empty() || s_f == s_b {
            return self.segment_with::<M>(s_f, s_b, l);
        }
        self.fragment_iso::<M>(s_f, s_b, l, gradients, view_dir)
    }

    /// The isosurface path of [`FragmentShader::fragment_with`] (kept out of line).
    #[inline(never)]
    fn fragment_iso<M: ColorModel>(
        &self,
        s_f: f32,
        s_b: f32,
        l: f32,
        gradients: impl FnOnce() -> (Vec3, Vec3),
        view_dir: impl FnOnce() -> Vec3,
    ) -> [f32; 4] {
        let (lo, hi) = if s_f < s_b { (s_f, s_b) } else { (s_b, s_f) };
        let first = self.isosurfaces.partition_point(|i| i.value < lo);
        let crossing = |iso: &Isovalue| {
            let t = (iso.value - s_f) / (s_b - s_f);
            (0.0..1.0).contains(&t).then_some(t)
        };
        let hits = self.isosurfaces[first..]
            .iter()
            .take_while(|i| i.value <= hi)
            .filter_map(|i| crossing(i).map(|t| (t, i)));
        let mut acc = [0.0f32; 4];
        let (mut s0, mut t0) = (s_f, 0.0f32);
        let mut lit: Option<(Vec3, Vec3, Vec3)> = None;
        let mut view_dir = Some(view_dir);
        let mut gradients = Some(gradients);
        // Crossings come in the order of the values; along the ray they are in order of t,
        // which is the same order when s increases and the reverse when it decreases.
        let mut list: [(f32, Option<&Isovalue>); 8] = [(0.0, None); 8];
        let mut n = 0;
        for h in hits {
            if n < list.len() {
                list[n] = (h.0, Some(h.1));
                n += 1;
            }
        }
        let list = &mut list[..n];
        if s_b < s_f {
            list.reverse();
        }
        for &(t, iso) in list.iter() {
            let Some(iso) = iso else { continue };
            under(
                &mut acc,
                self.segment_with::<M>(s0, iso.value, (t - t0) * l),
            );
            let (gf, gb, dir) = *lit.get_or_insert_with(|| {
                let (gf, gb) = gradients.take().map_or((Vec3::ZERO, Vec3::ZERO), |g| g());
                let dir = view_dir.take().map_or(Vec3::Z, |v| v());
                (gf, gb, dir)
            });
            let normal = gf + (gb - gf) * t;
            let rgb = self
                .shading
                .shade([iso.rgba[0], iso.rgba[1], iso.rgba[2]], normal, dir);
            let a = iso.rgba[3];
            under(&mut acc, [rgb[0] * a, rgb[1] * a, rgb[2] * a, a]);
            (s0, t0) = (iso.value, t);
        }
        under(&mut acc, self.segment_with::<M>(s0, s_b, (1.0 - t0) * l));
        acc
    }
}
