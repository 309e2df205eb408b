//! The second pass of PT on lanes: one tetrahedron's fragments in one tile are gathered
//! by the rasterizer into a [`Batch`], then interpolated and coloured [`LANES`] at a time
//! and composited (seed `000` §4.3, seed `002` §4.3 and §4.4: per fragment, `s_f`, `s_b` and
//! `l`, here from the cell's face planes, the TF at both ends and the ψ colour).
//!
//! The fragments of one cell in one tile cover distinct pixels (the drawn face triangles are
//! interior-disjoint and the fill rule draws a shared edge once), so gathering them before
//! compositing any of them changes nothing: the early-termination test of each fragment
//! sees the pixel as it was before the cell, as it would drawing them one by one.
//!
//! # Attributes
//!
//! The rasterizer draws a cell's face triangles ([`super::planes`]) and writes, per pixel,
//! `w_f`, `σ_f`, `w_b`, `σ_b`: the entry and exit `w` (`1/z` under perspective, `z`
//! otherwise) from the face planes, and `σ` there (`(s - s_0) / z` or `s - s_0`), each one
//! multiply-add per pixel along a row; the lanes divide (perspective) and add `s_0` back.
//!
//! # Colour ([`CellColour`])
//!
//! The cell's vertex range `[lo, hi]` bounds every fragment's values. Where no TF breakpoint
//! lies inside it the TF is one linear piece there and the ψ (or average) colour needs no
//! lookup. Otherwise (ψ only) the range is cut at the breakpoints inside it, as
//! [`crate::integrate::fragment`] cuts each segment: every lane takes its segment's share of
//! each piece (`002` §4.4's partial pre-integration is exact on each), the pieces on which
//! the extinction vanishes are dropped for the whole cell (their fragments are transparent
//! black, which composites as nothing), and the rest are composited in ray order (front to
//! back when the values increase along the ray, back to front otherwise).
use std::cmp::Ordering;

use glam::Vec4;

use super::clip::{DepthSpan, Window, ALL};
use super::planes::{CellPlanes, FaceDraw};
use super::raster::{Row, Triangle, BIN_TILE};
use crate::composite::under;
use crate::integrate::fragment::FragmentShader;
use crate::integrate::psi::lanes::{average_rgba_lanes, lanes, psi_rgba_lanes, Lanes, LANES};
use crate::integrate::psi::{LinearPiece, PsiTable};
use crate::integrate::SegmentRule;

/// One piece of a cell's colour: the TF is `piece` for values in `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
struct Span {
    lo: f32,
    hi: f32,
    piece: LinearPiece,
}

/// How the lanes colour one cell's fragments.
#[derive(Debug, Default)]
pub struct CellColour {
    /// The cell's values lie in one linear piece of the TF (`spans[0]`).
    linear: bool,
    /// The ψ model (else the average model).
    psi: bool,
    /// The pieces with non-zero extinction, in increasing value order.
    spans: Vec<Span>,
    /// For a linear plan of the ψ or average model without isosurfaces: the value range
    /// `[below, above)` (the breakpoints around its piece) within which another cell's range
    /// gets the same plan (neighbouring cells often do).
    reuse: Option<(SegmentRule, f32, f32)>,
}

impl CellColour {
    /// Plans the colour of a cell whose vertex values span `[lo, hi]`; `false` when the lanes
    /// cannot colour it and the per-fragment path must ([`FragmentShader::fragment_with`]):
    /// the exact model, an isosurface value in the range, non-finite values, or the average
    /// model across breakpoints (which it does not cut at).
    pub fn plan(&mut self, shader: &FragmentShader<'_>, lo: f32, hi: f32) -> bool {
        if let Some((mode, below, above)) = self.reuse {
            // No breakpoint in `(lo, hi)` and `lo` below the next: the same piece.
            let finite = lo.is_finite() && hi.is_finite();
            if finite && mode == shader.mode && below <= lo && lo <= hi && hi <= above && lo < above
            {
                return true;
            }
        }
        self.reuse = None;
        self.psi = match shader.mode {
            SegmentRule::Psi => true,
            SegmentRule::Average => false,
            _ => return false,
        };
        if !(lo.is_finite() && hi.is_finite()) {
            return false;
        }
        let i = shader.isosurfaces.partition_point(|i| i.value < lo);
        if shader.isosurfaces.get(i).is_some_and(|i| i.value <= hi) {
            return false;
        }
        let Some((knots, pieces)) = shader.classifier.pieces_on(lo, hi) else {
            return false;
        };
        self.spans.clear();
        self.linear = knots.is_empty();
        if self.linear {
            self.spans.push(Span {
                lo: f32::NEG_INFINITY,
                hi: f32::INFINITY,
                piece: pieces[0],
            });
            if shader.isosurfaces.is_empty() {
                let (below, above) = shader.classifier.piece_bounds(lo);
                self.reuse = Some((shader.mode, below, above));
            }
            return true;
        }
        if !self.psi {
            return false;
        }
        for (j, piece) in pieces.iter().enumerate() {
            let below = if j == 0 { None } else { knots.get(j - 1) };
            let above = knots.get(j);
            // The extinction is linear on the piece: zero at both ends of the cell's part of
            // it means zero throughout.
            let (a, b) = (
                below.map_or(lo, |&k| k.max(lo)),
                above.map_or(hi, |&k| k.min(hi)),
            );
            if piece.at(a)[3] <= 0.0 && piece.at(b)[3] <= 0.0 {
                continue;
            }
            self.spans.push(Span {
                lo: below.copied().unwrap_or(f32::NEG_INFINITY),
                hi: above.copied().unwrap_or(f32::INFINITY),
                piece: *piece,
            });
        }
        true
    }
}

/// What [`Batch::shade`] needs of the cell: its values are `offset + σ / w` (perspective) or
/// `offset + σ` (orthographic), clamped to its vertex range `[lo, hi]` (which rounding, or
/// the fit of a nearly flat cell, could leave).
#[derive(Clone, Copy, Debug)]
pub struct CellValues {
    /// The scalar at the cell's origin ([`CellPlanes::offset`]).
    pub offset: f32,
    /// The least vertex value.
    pub lo: f32,
    /// The greatest vertex value.
    pub hi: f32,
}

/// Capacity of a [`Batch`]: a power of two above a tile's pixels (a cell covers each at most
/// once), a row and a lane group of padding, so that masked indices need no bounds check.
const CAPACITY: usize = 8192;
const _: () =
    assert!(BIN_TILE * BIN_TILE + BIN_TILE + LANES <= CAPACITY && CAPACITY.is_power_of_two());
// The lane groups are `Vec4`s where a select is needed.
const _: () = assert!(LANES == 4);

/// One cell's fragments in one tile, as structure of arrays (see the module documentation).
#[derive(Debug)]
pub struct Batch {
    len: usize,
    pixel: Box<[u32; CAPACITY]>,
    /// The four attribute planes at each fragment.
    attr: Box<[[f32; CAPACITY]; 4]>,
    secant: Box<[f32; CAPACITY]>,
    /// Outputs of [`Batch::shade`]: front depth and premultiplied RGBA.
    z_f: Box<[f32; CAPACITY]>,
    rgba: Box<[[f32; CAPACITY]; 4]>,
}

impl Default for Batch {
    fn default() -> Self {
        Self::new()
    }
}

impl Batch {
    /// An empty batch (for tiles of up to [`BIN_TILE`] x [`BIN_TILE`] pixels).
    pub fn new() -> Self {
        Self {
            len: 0,
            pixel: Box::new([0; CAPACITY]),
            attr: Box::new([[0.0; CAPACITY]; 4]),
            secant: Box::new([0.0; CAPACITY]),
            z_f: Box::new([0.0; CAPACITY]),
            rgba: Box::new([[0.0; CAPACITY]; 4]),
        }
    }

    /// Number of fragments held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no fragment is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Empties the batch.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Whether `n` more fragments fit.
    fn fits(&self, n: usize) -> bool {
        self.len + n + LANES <= CAPACITY
    }
}

/// What the rasterizer needs to gather one cell's fragments into a [`Batch`].
pub struct Gather<'a> {
    /// Per tile pixel, the secant of its ray to the view direction, then [`LANES`] padding
    /// entries (a row's last lane group reads past its end).
    pub secant: &'a [f32],
    /// Per tile pixel, its window of view depth inside the clipping planes
    /// ([`super::clip`]); `None` without planes.
    pub window: Option<&'a [Window]>,
    /// The tile's first column.
    pub x0: i64,
    /// The tile's first row.
    pub y0: i64,
    /// The tile's width.
    pub width: i64,
    /// Pixels at or above this opacity take no more fragments.
    pub early: f32,
}

impl Gather<'_> {
    /// Appends the covered, not yet opaque pixels of the face triangle `tri` (set up from
    /// `face.tri`) of the cell `cell` to `batch`, with their entry and exit attributes from
    /// the cell's planes ([`super::planes`]); calls `flush` first whenever a row might not
    /// fit (never for a single cell in a tile). `acc` holds the tile's accumulated pixels,
    /// read for early termination.
    #[inline(always)]
    pub fn face<const PERSP: bool>(
        &self,
        batch: &mut Batch,
        acc: &mut [[f32; 4]],
        tri: &Triangle,
        cell: &CellPlanes,
        face: &FaceDraw,
        mut flush: impl FnMut(&mut Batch, &mut [[f32; 4]]),
    ) {
        // The other side's extreme: the farthest entry, the nearest exit (in `w`, which
        // grows toward the eye under perspective and away from it otherwise).
        let min = face.known_front != PERSP;
        tri.spans(|row| {
            let width = (row.hi - row.lo + 1) as usize;
            if !batch.fits(width) {
                flush(batch, acc);
            }
            if min {
                self.row::<true>(batch, acc, &row, cell, face);
            } else {
                self.row::<false>(batch, acc, &row, cell, face);
            }
        });
    }

    /// One span of [`Gather::face`] (`MIN`: the other side's crossing is the least of its
    /// planes): its pixels are appended (one pass, no bounds check per pixel), then the
    /// opaque ones (if any) removed.
    #[inline(always)]
    fn row<const MIN: bool>(
        &self,
        batch: &mut Batch,
        acc: &[[f32; 4]],
        row: &Row,
        cell: &CellPlanes,
        face: &FaceDraw,
    ) {
        let start = ((row.y - self.y0) * self.width + row.lo - self.x0) as usize;
        let width = (row.hi - row.lo + 1) as usize;
        let n = batch.len;
        let dx = row.lo as f32 + 0.5 - cell.origin[0];
        let dy = row.y as f32 + 0.5 - cell.origin[1];
        let k0 = face.known.at(dx, dy);
        let o = face.others.map(|p| p.at(dx, dy));
        let s0 = cell.sigma.at(dx, dy);
        let (ka, oa, sa) = (face.known.a, face.others.map(|p| p.a), cell.sigma.a);
        let (gamma, w0) = (cell.gamma, cell.w0);
        let (kw, ks, ow, os) = if face.known_front {
            (0, 1, 2, 3)
        } else {
            (2, 3, 0, 1)
        };
        // Whole lane groups: the pixels past the row's end (at most `LANES - 1`, which
        // `fits` and the secant's padding leave room for) are written and not counted, so
        // every group is one straight-line SIMD step, however short the row.
        let steps = Vec4::new(0.0, 1.0, 2.0, 3.0);
        for g in (0..width).step_by(LANES) {
            let i = steps + Vec4::splat(g as f32);
            let k = Vec4::splat(k0) + i * ka;
            let [p, q, r] = [0, 1, 2].map(|j| Vec4::splat(o[j]) + i * oa[j]);
            // `min` and `max` of SSE2 give the second operand when unordered, as the scalar
            // selects `if a < b { a } else { b }` did.
            let e = if MIN {
                p.min(q).min(r)
            } else {
                p.max(q).max(r)
            };
            let sigma = Vec4::splat(s0) + i * sa;
            let (ks_v, os_v) = (sigma + (k - w0) * gamma, sigma + (e - w0) * gamma);
            let (at, px) = (n + g, start + g);
            for m in 0..LANES {
                batch.pixel[(at + m) & (CAPACITY - 1)] = (px + m) as u32;
            }
            batch.secant[at..at + LANES].copy_from_slice(&self.secant[px..px + LANES]);
            let attr = &mut *batch.attr;
            attr[kw][at..at + LANES].copy_from_slice(&k.to_array());
            attr[ks][at..at + LANES].copy_from_slice(&ks_v.to_array());
            attr[ow][at..at + LANES].copy_from_slice(&e.to_array());
            attr[os][at..at + LANES].copy_from_slice(&os_v.to_array());
        }
        let opaque = acc[start..start + width].iter().any(|a| a[3] >= self.early);
        batch.len = if opaque {
            batch.keep_live(n, n + width, |p| acc[p as usize][3] < self.early)
        } else {
            n + width
        };
    }
}

impl Batch {
    /// Keeps, of the fragments `from..to` (the last ones), those whose pixel passes `live`;
    /// returns the new length.
    fn keep_live(&mut self, from: usize, to: usize, live: impl Fn(u32) -> bool) -> usize {
        let mut m = from;
        for i in from..to {
            if live(self.pixel[i]) {
                self.pixel[m] = self.pixel[i];
                for a in self.attr.iter_mut() {
                    a[m] = a[i];
                }
                self.secant[m] = self.secant[i];
                m += 1;
            }
        }
        m
    }
}

/// A lane group of the batch's array `v` from `i`.
#[inline(always)]
fn load(v: &[f32], i: usize) -> Lanes {
    let mut out = [0.0; LANES];
    out.copy_from_slice(&v[i..i + LANES]);
    out
}

/// `piece` at every lane's value, channel-major (the arithmetic of [`LinearPiece::at`]).
#[inline(always)]
fn piece_at(piece: &LinearPiece, s: &Lanes) -> [Lanes; 4] {
    let (origin, at, slope) = piece.coefficients();
    let d = lanes(|k| s[k] - origin);
    let c = |c: usize| lanes(|k| at[c] + slope[c] * d[k]);
    [c(0), c(1), c(2), c(3)]
}

impl Batch {
    /// Interpolates and colours every fragment (`PERSP`: the attributes are the perspective
    /// planes), trimmed to its pixel's `window` when there are clipping planes: fills the
    /// front depths and the premultiplied RGBA.
    pub fn shade<const PERSP: bool>(
        &mut self,
        colour: &CellColour,
        table: &PsiTable,
        values: CellValues,
        window: Option<&[Window]>,
    ) {
        if self.len == 0 {
            return;
        }
        // Pad the last lane group with copies of the last fragment.
        let end = self.len.div_ceil(LANES) * LANES;
        for i in self.len..end {
            for a in self.attr.iter_mut() {
                a[i] = a[self.len - 1];
            }
            self.secant[i] = self.secant[self.len - 1];
        }
        for i in (0..end).step_by(LANES) {
            let [wf, nf, wb, nb] = [
                load(&self.attr[0], i),
                load(&self.attr[1], i),
                load(&self.attr[2], i),
                load(&self.attr[3], i),
            ];
            let sec = load(&self.secant[..], i);
            let z_f = lanes(|k| if PERSP { 1.0 / wf[k] } else { wf[k] });
            let z_b = lanes(|k| if PERSP { 1.0 / wb[k] } else { wb[k] });
            let value = |n: f32, z: f32| {
                let s = values.offset + if PERSP { n * z } else { n };
                s.max(values.lo).min(values.hi)
            };
            let mut s_f = lanes(|k| value(nf[k], z_f[k]));
            let mut s_b = lanes(|k| value(nb[k], z_b[k]));
            let (mut z_f, mut z_b) = (z_f, z_b);
            if let Some(window) = window {
                self.trim(i, window, [&mut z_f, &mut s_f, &mut z_b, &mut s_b]);
            }
            let len = lanes(|k| ((z_b[k] - z_f[k]) * sec[k]).max(0.0));
            let rgba = colour.lanes(table, &s_f, &s_b, &len);
            // Transparent black for unusable inputs, as the scalar models give (a finite
            // `len` implies finite depths).
            let inf = Vec4::splat(f32::INFINITY);
            let (sf, sb, ln) = (Vec4::from(s_f), Vec4::from(s_b), Vec4::from(len));
            let ok =
                sf.abs().cmplt(inf) & sb.abs().cmplt(inf) & ln.cmplt(inf) & ln.cmpgt(Vec4::ZERO);
            self.z_f[i..i + LANES].copy_from_slice(&z_f);
            for (out, v) in self.rgba.iter_mut().zip(&rgba) {
                let v = Vec4::select(ok, Vec4::from(*v), Vec4::ZERO);
                out[i..i + LANES].copy_from_slice(&v.to_array());
            }
        }
    }

    /// Trims the fragments of the lane group from `i`, given as `[z_f, s_f, z_b, s_b]`, to
    /// their pixels' windows ([`DepthSpan::trim`]); one wholly outside gets zero length, which
    /// colours as transparent black (nothing).
    #[inline(always)]
    fn trim(&self, i: usize, window: &[Window], [z_f, s_f, z_b, s_b]: [&mut Lanes; 4]) {
        for k in 0..LANES {
            let w = window.get(self.pixel[i + k] as usize).copied();
            let span = DepthSpan {
                z_f: z_f[k],
                s_f: s_f[k],
                z_b: z_b[k],
                s_b: s_b[k],
            };
            match span.trim(w.unwrap_or(ALL)) {
                Some((t, _)) => (z_f[k], s_f[k], z_b[k], s_b[k]) = (t.z_f, t.s_f, t.z_b, t.s_b),
                None => z_b[k] = z_f[k],
            }
        }
    }

    /// Composites the shaded fragments under the tile's pixels `acc`, in batch order.
    pub fn composite(&self, acc: &mut [[f32; 4]]) {
        let n = self.len;
        let [r, g, b, a] = &*self.rgba;
        let rgba = r[..n].iter().zip(&g[..n]).zip(b[..n].iter().zip(&a[..n]));
        for (&p, ((&r, &g), (&b, &a))) in self.pixel[..n].iter().zip(rgba) {
            under(&mut acc[p as usize], [r, g, b, a]);
        }
    }

    /// The shaded fragments as `(pixel, front depth, RGBA)`, in batch order.
    pub fn fragments(&self) -> impl Iterator<Item = (u32, f32, [f32; 4])> + '_ {
        (0..self.len).map(|i| {
            let rgba = [0, 1, 2, 3].map(|c| self.rgba[c][i]);
            (self.pixel[i], self.z_f[i], rgba)
        })
    }
}

impl CellColour {
    /// The colour of one lane group of segments `s_f -> s_b` of lengths `l`.
    #[inline(always)]
    fn lanes(&self, table: &PsiTable, s_f: &Lanes, s_b: &Lanes, l: &Lanes) -> [Lanes; 4] {
        if self.linear {
            let piece = &self.spans[0].piece;
            if self.psi {
                return psi_rgba_lanes(table, &piece_at(piece, s_f), &piece_at(piece, s_b), l);
            }
            let mid = piece_at(piece, &lanes(|k| 0.5 * (s_f[k] + s_b[k])));
            return average_rgba_lanes(&mid, &mid, l);
        }
        self.pieces(table, s_f, s_b, l)
    }

    /// The ψ colour of segments cut at the breakpoints: each span's share, composited in ray
    /// order (see the module documentation). The values of a cell's neighbouring fragments
    /// nearly always change in the same direction along their rays; lane groups that agree
    /// take the spans in ray order with no per-lane choice.
    #[inline(always)]
    fn pieces(&self, table: &PsiTable, s_f: &Lanes, s_b: &Lanes, l: &Lanes) -> [Lanes; 4] {
        let rising = (0..LANES).filter(|&k| s_f[k] <= s_b[k]).count();
        if rising == LANES {
            self.pieces_along::<true>(table, s_f, s_b, l)
        } else if rising == 0 {
            self.pieces_along::<false>(table, s_f, s_b, l)
        } else {
            self.pieces_mixed(table, s_f, s_b, l)
        }
    }

    /// [`CellColour::pieces`] for lanes whose values all rise (`RISING`) or all fall along
    /// their rays: the spans in ray order, each composited under the previous ones.
    #[inline(always)]
    fn pieces_along<const RISING: bool>(
        &self,
        table: &PsiTable,
        s_f: &Lanes,
        s_b: &Lanes,
        l: &Lanes,
    ) -> [Lanes; 4] {
        let (lo, hi) = if RISING { (s_f, s_b) } else { (s_b, s_f) };
        let inv_width = lanes(|k| 1.0 / (hi[k] - lo[k]));
        let mut acc = [[0.0f32; LANES]; 4];
        // Without constant segments (`s_f == s_b`, in the span holding their value) only the
        // spans that meet the lane group's range `(min lo, max hi)` can take a share.
        let constant = (0..LANES).any(|k| lo[k].partial_cmp(&hi[k]) != Some(Ordering::Less));
        let spans = if constant {
            &self.spans[..]
        } else {
            self.spans_meeting(lo, hi)
        };
        let mut visit = |span: &Span| {
            let a = lanes(|k| lo[k].max(span.lo));
            let b = lanes(|k| hi[k].min(span.hi));
            let share = if constant {
                span_share(span, lo, hi, &a, &b, &inv_width)
            } else {
                lanes(|k| clamp_share((b[k] - a[k]) * inv_width[k]))
            };
            if !Vec4::from(share).cmpgt(Vec4::ZERO).any() {
                return;
            }
            let (front, back) = if RISING { (&a, &b) } else { (&b, &a) };
            let len = lanes(|k| share[k] * l[k]);
            let c = psi_rgba_lanes(
                table,
                &piece_at(&span.piece, front),
                &piece_at(&span.piece, back),
                &len,
            );
            let w = lanes(|k| 1.0 - acc[3][k]);
            for (a, c) in acc.iter_mut().zip(&c) {
                *a = lanes(|k| a[k] + w[k] * c[k]);
            }
        };
        if RISING {
            spans.iter().for_each(&mut visit);
        } else {
            spans.iter().rev().for_each(&mut visit);
        }
        acc
    }

    /// The spans that meet `(min lo, max hi)` over the lanes (the spans are sorted and
    /// disjoint).
    #[inline(always)]
    fn spans_meeting(&self, lo: &Lanes, hi: &Lanes) -> &[Span] {
        let min = lo
            .iter()
            .fold(f32::INFINITY, |m, &v| if v < m { v } else { m });
        let max = hi
            .iter()
            .fold(f32::NEG_INFINITY, |m, &v| if v > m { v } else { m });
        let first = self.spans.partition_point(|s| s.hi <= min);
        let last = self.spans.partition_point(|s| s.lo < max).max(first);
        &self.spans[first..last]
    }

    /// [`CellColour::pieces`] for lane groups of both directions: the spans in increasing
    /// value order, composited behind (rising lanes) or in front of (falling lanes) what is
    /// accumulated.
    #[inline(always)]
    fn pieces_mixed(&self, table: &PsiTable, s_f: &Lanes, s_b: &Lanes, l: &Lanes) -> [Lanes; 4] {
        let lo = lanes(|k| s_f[k].min(s_b[k]));
        let hi = lanes(|k| s_f[k].max(s_b[k]));
        // 1 where the values rise along the ray, 0 where they fall.
        let rising = lanes(|k| f32::from(u8::from(s_f[k] <= s_b[k])));
        let inv_width = lanes(|k| 1.0 / (hi[k] - lo[k]));
        let mut acc = [[0.0f32; LANES]; 4];
        for span in &self.spans {
            let a = lanes(|k| lo[k].max(span.lo));
            let b = lanes(|k| hi[k].min(span.hi));
            let share = span_share(span, &lo, &hi, &a, &b, &inv_width);
            if !Vec4::from(share).cmpgt(Vec4::ZERO).any() {
                continue;
            }
            let front = lanes(|k| if rising[k] > 0.0 { a[k] } else { b[k] });
            let back = lanes(|k| if rising[k] > 0.0 { b[k] } else { a[k] });
            let len = lanes(|k| share[k] * l[k]);
            let c = psi_rgba_lanes(
                table,
                &piece_at(&span.piece, &front),
                &piece_at(&span.piece, &back),
                &len,
            );
            // Rising: this span is behind what is accumulated (under); falling: in front.
            let keep = lanes(|k| if rising[k] > 0.0 { 1.0 } else { 1.0 - c[3][k] });
            let add = lanes(|k| {
                if rising[k] > 0.0 {
                    1.0 - acc[3][k]
                } else {
                    1.0
                }
            });
            for (a, c) in acc.iter_mut().zip(&c) {
                *a = lanes(|k| a[k] * keep[k] + add[k] * c[k]);
            }
        }
        acc
    }
}

/// Each lane's share of its segment `[lo, hi]` (values) that lies in `span`, given the
/// overlap `[a, b]` and `1 / (hi - lo)`; a constant segment lies in the one span holding its
/// value. Written as selects (no branch per lane).
#[inline(always)]
fn span_share(
    span: &Span,
    lo: &Lanes,
    hi: &Lanes,
    a: &Lanes,
    b: &Lanes,
    inv_width: &Lanes,
) -> Lanes {
    lanes(|k| {
        let f = clamp_share((b[k] - a[k]) * inv_width[k]);
        let holds = if span.lo <= lo[k] && lo[k] < span.hi {
            1.0
        } else {
            0.0
        };
        if hi[k] > lo[k] {
            f
        } else {
            holds
        }
    })
}

/// A share clamped to `[0, 1]`; NaN (a constant segment) gives 0.
#[inline(always)]
fn clamp_share(f: f32) -> f32 {
    let f = if f > 0.0 { f } else { 0.0 };
    if f < 1.0 {
        f
    } else {
        1.0
    }
}
