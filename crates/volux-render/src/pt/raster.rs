//! Screen tiles, binning of tetrahedra into tiles in drawing order, and scanline
//! rasterization of fan triangles with exact fixed-point edge functions and the top-left fill
//! rule (seed `000` §4.3: the second pass; here on the CPU).
//!
//! # Fill rule
//!
//! Vertices are snapped to `1/256` pixel ([`SUBPIXEL`]), so in fixed point the edge function
//! `E_ab(p) = (b - a) × (p - a)` at a pixel centre is an exact `i64`, and
//! `E_ab(p) = -E_ba(p)` exactly. A pixel centre strictly inside a triangle is drawn; one
//! exactly on an edge is drawn only if the edge is a *top-left* edge of the (positively
//! oriented) triangle: direction `d = b - a` with `d.y < 0`, or `d.y = 0` and `d.x > 0`. The
//! rule is antisymmetric (exactly one of `d`, `-d` qualifies), so a pixel centre on an edge
//! shared by two triangles is drawn by exactly one of them: no gaps, no double blending, both
//! between the triangles of one fan and between neighbouring tetrahedra.
//!
//! # Scanlines
//!
//! Along a pixel row every edge function is affine in the column, `E(x) = C + D x`, so each
//! row's span of columns is the intersection of three half-lines solved with exact integer
//! floor and ceiling divisions; the pixels of the span are then walked with incremental
//! `E`s. Barycentric coordinates are `E / area`.
use rayon::prelude::*;

use super::project::SUBPIXEL;
use crate::error::{Remedy, RenderError};
use crate::tiles::{Rect, TileGrid};

/// Edge in pixels of Projected Tetrahedra's binning tiles: a tile's bin of tetrahedra is read
/// once per tile, so PT's tiles are larger than the tile driver's ([`crate::tiles::TILE`]),
/// and named apart from it.
pub const BIN_TILE: usize = 64;

/// The PT screen tiles of a `width x height` image.
pub fn tiles(width: usize, height: usize) -> TileGrid {
    TileGrid::new(width, height, BIN_TILE)
}

/// The screen box of a tetrahedron's projection.
#[inline]
pub fn screen_box(v: &[[f32; 3]; 4]) -> ([f32; 2], [f32; 2]) {
    let mut min = [v[0][0], v[0][1]];
    let mut max = min;
    for p in &v[1..] {
        min = [min[0].min(p[0]), min[1].min(p[1])];
        max = [max[0].max(p[0]), max[1].max(p[1])];
    }
    (min, max)
}

/// Whether the screen box of the projected vertices `v` holds the centre of a pixel of
/// `clip`: when it does not, none of the cell's triangles draws a pixel there (each lies in
/// the box), so the cell can be skipped before any set-up.
#[inline]
pub fn box_holds_centre(v: &[[f32; 3]; 4], clip: Rect) -> bool {
    let (min, max) = screen_box(v);
    centre_box(min, max, clip).is_some()
}

/// For every tile, the tetrahedra overlapping it, in drawing order (a CSR layout: the items of
/// tile `i` are `items[offsets[i]..offsets[i + 1]]`).
#[derive(Clone, Debug, Default)]
pub struct Bins {
    /// `count + 1` offsets into `items`.
    pub offsets: Vec<u32>,
    /// Tetrahedron ids.
    pub items: Vec<u32>,
}

impl Bins {
    /// The tetrahedra of tile `i`, in drawing order.
    pub fn tile(&self, i: usize) -> &[u32] {
        let (a, b) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
        &self.items[a..b]
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        4 * (self.offsets.capacity() + self.items.capacity())
    }
}

/// A tetrahedron's tile range `[tx0, ty0, tx1, ty1]` (inclusive) in `tiles`, or
/// [`NO_TILES`] when its vertices could not be projected or its box covers no pixel centre;
/// tile indices fit in 16 bits (images are at most 32768 pixels wide).
#[inline]
pub fn tile_range(v: Option<[[f32; 3]; 4]>, tiles: &TileGrid) -> [u16; 4] {
    let Some(v) = v else {
        return NO_TILES;
    };
    let (min, max) = screen_box(&v);
    let full = Rect {
        x0: 0,
        y0: 0,
        x1: tiles.width,
        y1: tiles.height,
    };
    match centre_box(min, max, full) {
        Some(b) => b.map(|p| (p as usize / tiles.side) as u16),
        None => NO_TILES,
    }
}

/// The pixels `[x0, y0, x1, y1]` (inclusive) of `clip` whose centres lie in the screen box
/// `[min, max]`, or `None`: in fixed point, with the rasterizer's own rounding of the box
/// ([`Triangle::new`]), so a cell is binned to every tile in which it can draw a pixel.
#[inline]
fn centre_box(min: [f32; 2], max: [f32; 2], clip: Rect) -> Option<[i64; 4]> {
    let (lo, hi) = (fixed(min), fixed(max));
    let x0 = first_centre(lo[0]).max(clip.x0 as i64);
    let x1 = last_centre(hi[0]).min(clip.x1 as i64 - 1);
    let y0 = first_centre(lo[1]).max(clip.y0 as i64);
    let y1 = last_centre(hi[1]).min(clip.y1 as i64 - 1);
    (x0 <= x1 && y0 <= y1).then_some([x0, y0, x1, y1])
}

/// The empty tile range.
pub const NO_TILES: [u16; 4] = [1, 1, 0, 0];

/// Bins the tetrahedra of `order` into `tiles` by their tile ranges `ranges` (indexed by
/// tetrahedron id, as [`tile_range`] gives them), keeping the order within every tile (a
/// two-pass counting sort: counts per tile, prefix sums, fill). Errors, before the bins are
/// allocated, when they would exceed the memory budget or hold more entries than `u32`
/// offsets can count, or when `order` names a tetrahedron `ranges` does not hold.
pub fn bin_by_range(
    order: &[u32],
    ranges: &[[u16; 4]],
    tiles: &TileGrid,
) -> Result<Bins, RenderError> {
    let n = tiles.count();
    // The ranges in drawing order, gathered once in parallel: the two passes below then
    // read them in sequence instead of at random (the bench's 1.25 M-cell dense frame: bin
    // 38-45 ms -> 24-30 ms on 2 threads).
    let ordered: Vec<[u16; 4]> = order
        .par_iter()
        .map(|&t| {
            ranges.get(t as usize).copied().ok_or_else(|| {
                RenderError::Internal(format!("binning: tetrahedron {t} has no tile range"))
            })
        })
        .collect::<Result<_, _>>()?;
    let tiles_of = |[x0, y0, x1, y1]: [u16; 4]| {
        (usize::from(y0)..=usize::from(y1)).flat_map(move |ty| {
            (usize::from(x0)..=usize::from(x1)).map(move |tx| ty * tiles.cols + tx)
        })
    };
    let mut counts = vec![0u32; n + 1];
    let mut entries = 0u64;
    for &r in &ordered {
        for i in tiles_of(r) {
            counts[i + 1] += 1;
            entries += 1;
        }
    }
    check_bins(entries)?;
    for i in 0..n {
        counts[i + 1] += counts[i];
    }
    let mut items = vec![0u32; counts[n] as usize];
    let mut cursor = counts.clone();
    for (&t, &r) in order.iter().zip(&ordered) {
        for i in tiles_of(r) {
            items[cursor[i] as usize] = t;
            cursor[i] += 1;
        }
    }
    Ok(Bins {
        offsets: counts,
        items,
    })
}

/// Checks the number of bin `entries` (one per tile a tetrahedron overlaps) against the
/// memory budget (4 bytes each) and the `u32` offsets.
fn check_bins(entries: u64) -> Result<(), RenderError> {
    volux_core::limits::check_alloc("PT's tile bins", entries, 4)?;
    if entries > u64::from(u32::MAX) {
        return Err(RenderError::OverLimit {
            what: "PT's tile bins (entries)".into(),
            count: entries,
            limit: u64::from(u32::MAX),
            remedy: Some(Remedy::SmallerImage),
        });
    }
    Ok(())
}

/// A screen position in fixed point (`SUBPIXEL` units).
///
/// Projected positions are snapped to the sub-pixel grid, so `xy * SUBPIXEL` is normally an
/// exact integer and the conversion needs no rounding; other values are rounded to nearest.
#[inline]
pub fn fixed(xy: [f32; 2]) -> [i64; 2] {
    #[inline(always)]
    fn one(v: f32) -> i64 {
        let t = v * SUBPIXEL;
        let i = t as i64;
        if i as f32 == t {
            i
        } else {
            t.round() as i64
        }
    }
    [one(xy[0]), one(xy[1])]
}

const SHIFT: u32 = 8;
const HALF: i64 = (SUBPIXEL as i64) / 2;
const ONE: i64 = SUBPIXEL as i64;
const _: () = assert!(ONE == 1 << SHIFT);

/// Rows (or columns) wider than this are clipped to their span with divisions; narrower
/// ones are walked pixel by pixel with incremental edge functions.
const WALK_MAX: i64 = 16;

/// One edge `a -> b` of a triangle: `E = C_row + D x` along a row.
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: [i64; 2],
    d: [i64; 2],
    /// 0 when pixel centres on the edge are drawn (top-left edge), 1 otherwise.
    bias: i64,
}

impl Edge {
    #[inline]
    fn new(a: [i64; 2], b: [i64; 2]) -> Self {
        let d = [b[0] - a[0], b[1] - a[1]];
        let top_left = d[1] < 0 || (d[1] == 0 && d[0] > 0);
        Self {
            a,
            d,
            bias: if top_left { 0 } else { 1 },
        }
    }

    /// `E` at the centre of pixel `(0, y)`, and its increment per column.
    #[inline]
    fn row(&self, y: i64) -> (i64, i64) {
        let py = y * ONE + HALF;
        let c = self.d[0] * (py - self.a[1]) - self.d[1] * (HALF - self.a[0]);
        (c, -self.d[1] * ONE)
    }
}

/// Boxes narrower than this many columns have their spans found by walking
/// ([`Triangle::spans`]).
const SPAN_WALK_MAX: i64 = 4;

/// One edge's bound on the covered columns of successive rows: a pixel `x` is on the inner
/// side when `C + D x >= bias`, i.e. `x >= -floor(M / D)` for `D > 0` and
/// `x <= floor(M / -D)` for `D < 0`, with `M = C - bias`; `M` grows by the edge's `dx ONE` per
/// row, so `floor(M / |D|)` is stepped as a quotient and a remainder.
#[derive(Clone, Copy, Debug)]
struct EdgeBound {
    /// `E` at the centre of column 0 of the current row, and its increment per row.
    c: i64,
    t: i64,
    /// `E`'s increment per column.
    d: i64,
    /// `|D|`, or `i64::MAX` for a horizontal edge (whose remainder never carries).
    k: i64,
    /// `floor(M / |D|)` and `M mod |D|` on the current row (`M` itself when `D = 0`).
    q: i64,
    r: i64,
    /// The same for `M`'s increment per row.
    tq: i64,
    tr: i64,
}

impl EdgeBound {
    #[inline(always)]
    fn new(e: &Edge, y: i64) -> Self {
        let (c, d) = e.row(y);
        let (m, t) = (c - e.bias, e.d[0] * ONE);
        let k = if d == 0 { i64::MAX } else { d.abs() };
        let (q, r, tq, tr) = if d == 0 {
            (m, 0, t, 0)
        } else {
            (
                m.div_euclid(k),
                m.rem_euclid(k),
                t.div_euclid(k),
                t.rem_euclid(k),
            )
        };
        Self {
            c,
            t,
            d,
            k,
            q,
            r,
            tq,
            tr,
        }
    }

    /// `[lo, hi]` narrowed to this edge's inner side on the current row (empty when the row
    /// is outside a horizontal edge).
    #[inline(always)]
    fn clip(&self, lo: i64, hi: i64) -> (i64, i64) {
        let low = if self.d > 0 { -self.q } else { i64::MIN };
        let high = if self.d < 0 {
            self.q
        } else if self.d == 0 && self.q < 0 {
            i64::MIN
        } else {
            i64::MAX
        };
        (lo.max(low), hi.min(high))
    }

    /// Moves to the next row.
    #[inline(always)]
    fn step(&mut self) {
        self.c += self.t;
        let r = self.r + self.tr;
        let carry = r >= self.k;
        self.r = if carry { r - self.k } else { r };
        self.q += self.tq + i64::from(carry);
    }
}

/// `floor(a / b)` for `b > 0`.
#[inline]
fn floor_div(a: i64, b: i64) -> i64 {
    a.div_euclid(b)
}

/// `ceil(a / b)` for `b > 0`.
#[inline]
fn ceil_div(a: i64, b: i64) -> i64 {
    -(-a).div_euclid(b)
}

/// The first pixel index whose centre `i * ONE + HALF` is `>= v` (fixed point).
#[inline]
fn first_centre(v: i64) -> i64 {
    // ceil((v - HALF) / ONE)
    -((HALF - v) >> SHIFT)
}

/// The last pixel index whose centre is `<= v` (fixed point).
#[inline]
fn last_centre(v: i64) -> i64 {
    // floor((v - HALF) / ONE)
    (v - HALF) >> SHIFT
}

/// A triangle set up for scan conversion inside a clip rectangle: its edges (positively
/// oriented, with the top-left biases), `1 / area`, and the pixels of the clip rectangle
/// whose centres lie in its bounding box.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// `edges[j]` is the edge opposite vertex `j` of the triangle as given, so that its `E`
    /// over the area is that vertex's barycentric coordinate.
    edges: [Edge; 3],
    inv_area: f32,
    x0: i64,
    x1: i64,
    y0: i64,
    y1: i64,
}

impl Triangle {
    /// Sets up the triangle `v` (fixed-point positions) inside `clip`; `None` when it has zero
    /// area or no pixel centre of `clip` lies in its bounding box (it draws nothing).
    #[inline]
    pub fn new(v: [[i64; 2]; 3], clip: Rect) -> Option<Self> {
        let xmin = v[0][0].min(v[1][0]).min(v[2][0]);
        let xmax = v[0][0].max(v[1][0]).max(v[2][0]);
        let ymin = v[0][1].min(v[1][1]).min(v[2][1]);
        let ymax = v[0][1].max(v[1][1]).max(v[2][1]);
        let x0 = first_centre(xmin).max(clip.x0 as i64);
        let x1 = last_centre(xmax).min(clip.x1 as i64 - 1);
        let y0 = first_centre(ymin).max(clip.y0 as i64);
        let y1 = last_centre(ymax).min(clip.y1 as i64 - 1);
        if x0 > x1 || y0 > y1 {
            return None;
        }
        let area =
            (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
        if area == 0 {
            return None;
        }
        // Positively oriented edges; λ_j is E of the edge opposite v_j.
        let edges = if area > 0 {
            [
                Edge::new(v[1], v[2]),
                Edge::new(v[2], v[0]),
                Edge::new(v[0], v[1]),
            ]
        } else {
            // The triangle (v0, v2, v1): the edge opposite v0 is v2 -> v1, opposite v2 (its
            // second vertex) is v1 -> v0, opposite v1 is v0 -> v2.
            [
                Edge::new(v[2], v[1]),
                Edge::new(v[0], v[2]),
                Edge::new(v[1], v[0]),
            ]
        };
        Some(Self {
            edges,
            inv_area: 1.0 / area.abs() as f32,
            x0,
            x1,
            y0,
            y1,
        })
    }

    /// Calls `frag(x, y, λ)` for every covered pixel, row by row, with the barycentric
    /// coordinates `λ` of its centre in the order of the vertices given to [`Triangle::new`].
    #[inline(always)]
    pub fn for_each(&self, frag: impl FnMut(usize, usize, [f32; 3])) {
        self.scan(self.x1 - self.x0 < WALK_MAX, frag);
    }

    /// [`Triangle::for_each`], walking every pixel of the box's rows (`walk`) or clipping
    /// each row to its span with exact divisions first; both draw the same pixels.
    #[inline(always)]
    fn scan(&self, walk: bool, mut frag: impl FnMut(usize, usize, [f32; 3])) {
        let inv = self.inv_area;
        self.rows_with(walk, |row| {
            let mut cur = row.e;
            for x in row.lo..row.hi + 1 {
                if row.inside(cur) {
                    let l = [
                        cur[0] as f32 * inv,
                        cur[1] as f32 * inv,
                        cur[2] as f32 * inv,
                    ];
                    frag(x as usize, row.y as usize, l);
                }
                cur = [cur[0] + row.d[0], cur[1] + row.d[1], cur[2] + row.d[2]];
            }
        });
    }

    /// `1 / (twice the area)` in fixed point: the barycentric coordinate of vertex `j` is
    /// `E_j` times this.
    #[inline(always)]
    pub fn inv_area(&self) -> f32 {
        self.inv_area
    }

    /// Calls `row` for every pixel row of the triangle's box that may hold covered pixels,
    /// with the columns to visit and the edge functions at the first of them. Narrow boxes
    /// give every column of the box and [`Row::inside`] tells the covered ones; wide ones
    /// give each row's exact span (every pixel inside). Together the rows cover exactly the
    /// pixels of [`Triangle::for_each`].
    #[inline(always)]
    pub fn rows(&self, row: impl FnMut(Row)) {
        self.rows_with(self.x1 - self.x0 < WALK_MAX, row);
    }

    /// Calls `span` for every pixel row of the triangle that holds covered pixels, with its
    /// exact span of covered columns (every pixel of the [`Row`] is inside). Each edge's
    /// bound on the columns, `ceil` or `floor` of `(bias - C) / D` as in the clipped scan, is
    /// stepped from row to row with an exact quotient and remainder (a DDA), so there is
    /// one division per edge and triangle instead of one per edge and row, and no pixel is
    /// visited outside the triangle. The same pixels as [`Triangle::for_each`].
    #[inline(always)]
    pub fn spans(&self, mut span: impl FnMut(Row)) {
        if self.x1 - self.x0 < SPAN_WALK_MAX {
            self.walked_spans(span);
            return;
        }
        let rows = self.y0..self.y1 + 1;
        let mut bounds = self.edges.map(|e| EdgeBound::new(&e, self.y0));
        let d = bounds.map(|b| b.d);
        for y in rows {
            let (mut lo, mut hi) = (self.x0, self.x1);
            for b in &bounds {
                (lo, hi) = b.clip(lo, hi);
            }
            if lo <= hi {
                let e = [0, 1, 2].map(|j| bounds[j].c + d[j] * lo);
                span(Row {
                    y,
                    lo,
                    hi,
                    e,
                    d,
                    bias: SPAN_BIAS,
                });
            }
            for b in &mut bounds {
                b.step();
            }
        }
    }

    /// [`Triangle::spans`] for narrow boxes: each row of the box is walked to find its span
    /// (a triangle meets a row in one interval), which for a few columns costs less than
    /// setting up the edge steppers.
    #[inline(always)]
    fn walked_spans(&self, mut span: impl FnMut(Row)) {
        self.rows_with(true, |row| {
            let (mut lo, mut hi) = (i64::MAX, i64::MIN);
            let mut e = row.e;
            for x in row.lo..row.hi + 1 {
                let inside = row.inside(e);
                lo = if inside { lo.min(x) } else { lo };
                hi = if inside { hi.max(x) } else { hi };
                e = [e[0] + row.d[0], e[1] + row.d[1], e[2] + row.d[2]];
            }
            if lo <= hi {
                let k = lo - row.lo;
                let e = [0, 1, 2].map(|j| row.e[j] + row.d[j] * k);
                span(Row {
                    lo,
                    hi,
                    e,
                    bias: SPAN_BIAS,
                    ..row
                });
            }
        });
    }

    /// [`Triangle::rows`] with the choice between walking and clipping made by the caller.
    #[inline(always)]
    fn rows_with(&self, walk: bool, mut row: impl FnMut(Row)) {
        let [e0, e1, e2] = self.edges;
        let bias = [e0.bias, e1.bias, e2.bias];
        for y in self.y0..self.y1 + 1 {
            let (c0, d0) = e0.row(y);
            let (c1, d1) = e1.row(y);
            let (c2, d2) = e2.row(y);
            let (mut lo, mut hi) = (self.x0, self.x1);
            if !walk {
                // Need c + d x >= bias for every edge.
                for (c, d, b) in [(c0, d0, bias[0]), (c1, d1, bias[1]), (c2, d2, bias[2])] {
                    if d > 0 {
                        lo = lo.max(ceil_div(b - c, d));
                    } else if d < 0 {
                        hi = hi.min(floor_div(c - b, -d));
                    } else if c < b {
                        hi = lo - 1;
                    }
                }
                if lo > hi {
                    continue;
                }
            }
            row(Row {
                y,
                lo,
                hi,
                e: [c0 + d0 * lo, c1 + d1 * lo, c2 + d2 * lo],
                d: [d0, d1, d2],
                bias: if walk { bias } else { SPAN_BIAS },
            });
        }
    }
}

/// The biases of a [`Row`] that is an exact span: every `E - bias` is then `>= 0` (the `E`s of
/// covered pixels are at least 0 and below `2^62`).
const SPAN_BIAS: [i64; 3] = [i64::MIN / 2; 3];

/// One pixel row of a [`Triangle`]: columns `lo..=hi` of row `y`, with the three edge
/// functions `e` at column `lo` and their increments `d` per column.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// The pixel row.
    pub y: i64,
    /// First column.
    pub lo: i64,
    /// Last column.
    pub hi: i64,
    /// Edge functions at `(lo, y)`; barycentric `j` is `e[j] * inv_area`.
    pub e: [i64; 3],
    /// Their increments per column.
    pub d: [i64; 3],
    bias: [i64; 3],
}

impl Row {
    /// Whether the pixel whose edge functions are `e` is covered (top-left rule).
    #[inline(always)]
    pub fn inside(&self, e: [i64; 3]) -> bool {
        ((e[0] - self.bias[0]) | (e[1] - self.bias[1]) | (e[2] - self.bias[2])) >= 0
    }
}

/// Scan-converts the triangle `v` (fixed-point positions) inside `clip`, calling
/// `frag(x, y, λ)` for every covered pixel with the barycentric coordinates `λ` of its centre
/// relative to `v` (in `v`'s order, whatever the orientation). Zero-area triangles draw
/// nothing.
#[inline]
pub fn rasterize_triangle(v: [[i64; 2]; 3], clip: Rect, frag: impl FnMut(usize, usize, [f32; 3])) {
    if let Some(t) = Triangle::new(v, clip) {
        t.for_each(frag);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A xorshift generator of integers in `[0, n)` (reproducible random triangles).
    fn xorshift(mut seed: u64) -> impl FnMut(i64) -> i64 {
        move |n| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as i64 % n
        }
    }

    fn fx(x: f32, y: f32) -> [i64; 2] {
        fixed([x, y])
    }

    fn coverage(tris: &[[[i64; 2]; 3]], w: usize, h: usize) -> Vec<u32> {
        let mut count = vec![0u32; w * h];
        let clip = Rect {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        };
        for t in tris {
            rasterize_triangle(*t, clip, |x, y, l| {
                assert!(l.iter().all(|&v| (-1e-5..=1.0 + 1e-5).contains(&v)));
                assert!((l[0] + l[1] + l[2] - 1.0).abs() < 1e-4);
                count[y * w + x] += 1;
            });
        }
        count
    }

    #[test]
    fn tile_ranges_are_the_tile_grids_on_snapped_boxes() {
        let tiles = TileGrid::new(200, 130, BIN_TILE);
        let mut rnd = xorshift(0x7157_ab1e_2024_0001);
        for _ in 0..20_000 {
            // Snapped positions around and across the image, some on pixel centres.
            let mut p = || (rnd(300 * ONE) - 50 * ONE) as f32 / SUBPIXEL;
            let v: [[f32; 3]; 4] = std::array::from_fn(|_| [p(), p(), 1.0]);
            let (min, max) = screen_box(&v);
            let expected = tiles
                .range(min, max)
                .map_or(NO_TILES, |r| r.map(|x| x as u16));
            assert_eq!(tile_range(Some(v), &tiles), expected, "{v:?}");
            let all = Rect {
                x0: 0,
                y0: 0,
                x1: 200,
                y1: 130,
            };
            assert_eq!(box_holds_centre(&v, all), expected != NO_TILES, "{v:?}");
        }
    }

    #[test]
    fn bins_keep_the_order_and_the_tile_ranges() {
        let tiles = TileGrid::new(3 * BIN_TILE, 2 * BIN_TILE, BIN_TILE);
        // Tetrahedron t's range, indexed by id; the order visits them out of id order.
        let ranges = [
            [0, 0, 1, 0],
            NO_TILES,
            [1, 0, 2, 1],
            [0, 1, 0, 1],
            [2, 1, 2, 1],
        ];
        let order = [4, 2, 0, 1, 3];
        let bins = bin_by_range(&order, &ranges, &tiles).unwrap();
        let expected: [&[u32]; 6] = [&[0], &[2, 0], &[2], &[3], &[2], &[4, 2]];
        for (i, e) in expected.iter().enumerate() {
            assert_eq!(bins.tile(i), *e, "tile {i}");
        }
        assert!(
            bin_by_range(&[5], &ranges, &tiles).is_err(),
            "an id without a range"
        );
    }

    #[test]
    fn shared_edges_are_covered_exactly_once() {
        // A fan of triangles around a centre with vertices on pixel centres and edges through
        // pixel centres (the hard case for fill rules), plus random meshes of a square.
        let c = fx(8.5, 8.5);
        let rim = [
            fx(0.5, 0.5),
            fx(8.5, 0.5),
            fx(16.5, 0.5),
            fx(16.5, 8.5),
            fx(16.5, 16.5),
            fx(8.5, 16.5),
            fx(0.5, 16.5),
            fx(0.5, 8.5),
        ];
        let tris: Vec<_> = (0..8).map(|i| [c, rim[i], rim[(i + 1) % 8]]).collect();
        let count = coverage(&tris, 20, 20);
        for y in 0..20 {
            for x in 0..20 {
                let inside = (0..=16).contains(&x) && (0..=16).contains(&y);
                let n = count[y * 20 + x];
                // The square [0.5, 16.5]^2: centres on its outer boundary belong to one side
                // only (top-left), so interior pixels are exactly once and none twice.
                assert!(n <= 1, "pixel {x},{y} drawn {n} times");
                if inside && x < 16 && y < 16 {
                    assert_eq!(n, 1, "pixel {x},{y} missed");
                }
            }
        }
    }

    #[test]
    fn random_triangulations_cover_once() {
        // Triangulate a square with random interior points snapped to the sub-pixel grid
        // (a fan around each of 2 points is enough to create arbitrary shared edges).
        let mut seed = 12345u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let p = fx(2.0 + 20.0 * rnd() as f32, 2.0 + 20.0 * rnd() as f32);
            let p = [
                p[0] / 64 * 64 + [0, 128][(rnd() * 2.0) as usize],
                p[1] / 64 * 64,
            ];
            let corners = [fx(0.0, 0.0), fx(24.0, 0.0), fx(24.0, 24.0), fx(0.0, 24.0)];
            let tris: Vec<_> = (0..4)
                .map(|i| {
                    if i % 2 == 0 {
                        [p, corners[i], corners[(i + 1) % 4]]
                    } else {
                        [corners[(i + 1) % 4], p, corners[i]]
                    }
                })
                .collect();
            let count = coverage(&tris, 24, 24);
            assert!(count.iter().all(|&n| n == 1), "a pixel missed or doubled");
        }
    }

    #[test]
    fn spans_cover_the_pixels_of_for_each() {
        let mut rnd = xorshift(0x1234_5678_9abc_def1u64);
        let clip = Rect {
            x0: 3,
            y0: 2,
            x1: 35,
            y1: 27,
        };
        for i in 0..20_000 {
            let span = [4 * ONE, 12 * ONE, 40 * ONE][i % 3];
            let step = if i % 4 == 0 { HALF } else { 1 };
            let mut p = || [rnd(span / step) * step, rnd(span / step) * step];
            let v = [p(), p(), p()];
            let Some(t) = Triangle::new(v, clip) else {
                continue;
            };
            let mut a = Vec::new();
            t.for_each(|x, y, _| a.push((x as i64, y as i64)));
            let mut b = Vec::new();
            t.spans(|row| {
                let mut e = row.e;
                for x in row.lo..=row.hi {
                    assert!(row.inside(e));
                    // The edge functions the span gives are those of its pixels.
                    let l = e.map(|e| e as f32 * t.inv_area());
                    assert!(l.iter().all(|&v| v >= -1e-6), "{v:?}");
                    b.push((x, row.y));
                    e = [0, 1, 2].map(|j| e[j] + row.d[j]);
                }
            });
            assert_eq!(a, b, "{v:?}");
        }
    }

    #[test]
    fn walking_and_spans_draw_the_same_pixels() {
        let mut rnd = xorshift(987654321u64);
        let clip = Rect {
            x0: 3,
            y0: 2,
            x1: 29,
            y1: 27,
        };
        for i in 0..20_000 {
            // Small and large triangles, on and off the pixel-centre grid (multiples of HALF
            // put vertices and edges through centres).
            let span = if i % 2 == 0 { 8 * ONE } else { 40 * ONE };
            let step = if i % 3 == 0 { HALF } else { 1 };
            let mut p = || [rnd(span / step) * step, rnd(span / step) * step];
            let v = [p(), p(), p()];
            let Some(t) = Triangle::new(v, clip) else {
                continue;
            };
            let (mut a, mut b) = (Vec::new(), Vec::new());
            t.scan(true, |x, y, l| a.push((x, y, l)));
            t.scan(false, |x, y, l| b.push((x, y, l)));
            assert_eq!(a, b, "{v:?}");
        }
    }
}
