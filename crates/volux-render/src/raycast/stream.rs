//! The fast fixed-step paths (no isosurfaces, no MIP): the rays of a tile flow through
//! [`LANES`] lanes that advance together, one sample per lane per step. Three rules share the
//! stream ([`SlabRule`]): the Riemann sum composites each sample's slab, pre-integration each
//! segment between consecutive samples, classified by the pair, and the trapezoid rule
//! ([`TrapezoidRule`]) each segment from its two ends. With Blinn-Phong shading (and a
//! gradient volume), each step's colours are lit lane-wise ([`BlinnPhong::light_lanes`]), at
//! the sample for Riemann, at the segment's middle for pre-integration, as ray by ray; shaded
//! trapezoid rays stay ray by ray, which light each end of a segment apart.
//!
//! Lanes hold different rays, so the front-to-back compositing of one ray (a chain of
//! dependent multiply-adds, `001_...txt` eq. 2.14) overlaps with the other lanes' chains, and
//! the position, reconstruction and classification arithmetic is done lane-wise. A lane whose
//! ray reaches the end of an occupied span or becomes opaque takes the next span or the next
//! ray of the tile (in 4 x 4 pixel blocks, so that lanes read neighbouring voxels); that
//! bookkeeping runs once per span, not per sample.
//!
//! A lane sums its ray in blocks of at most [`BLOCK_STEPS`] steps: the block's slabs are
//! composited in `f32` from zero, and the block is then composited under the ray's `f64` sum
//! ([`Lanes::fold`]). A single `f32` chain over hundreds of samples drifts by about 1e-6 (each
//! step rounds to half an ulp of the opacity so far, near 1); a block's partial sum is small,
//! so its rounding is too, and the ray composited in pieces (bricks, ranks: `003`) agrees with
//! the ray composited whole to about 1e-7. Keeping the whole sum in `f64` did the same at
//! 11 % of the Riemann frame (156 against 140 ms on Marschner-Lobb); the blocks cost 2.3 % of
//! a CT frame's instructions (callgrind, Riemann 0.25).
//!
//! Sample `i` of a ray sits at `t_i = start + i h`, `start = t0 + jitter h` (voxel space:
//! `base + i step`): a function of the ray and `i` only, so skipping empty space never moves a
//! sample. The Riemann slab `i` is `[t_i, t_i + h]`; the pre-integrated segment `i` is
//! `[t_(i-1), t_i]`, clipped to the ray, as in [`RayContext::preintegrated`].
use glam::{DVec3, Vec3};

use super::context::{first_at_or_after, pixel_hash, PixelOut, RayContext};
use crate::classify::LaneTable;
use crate::composite::{under64, under_if, under_partial, RayAccumulator};
use crate::integrate::adaptive::lanes::exp_lanes;
use crate::integrate::preintegrated::PreintegrationTable;
use crate::integrate::{riemann_step, Integrator};
use crate::intervals::IntervalSource;
use crate::macrocell::CellClass;
use crate::sampling::{Field, LANES};
use crate::shading::{BlinnPhong, CutFaces, GradientVolume, Lanes3};
use crate::tiles::TILE;

/// Shading in the stream: the model and the gradients it lights with.
#[derive(Clone, Copy)]
pub(super) struct StreamShading<'a> {
    pub(super) model: &'a BlinnPhong,
    pub(super) gradients: &'a GradientVolume,
    /// The cut faces, lit with the cut's normal.
    pub(super) cut_faces: Option<&'a CutFaces<'a>>,
}

/// How the stream composites: what one lane step adds, from the sample before it (`front`)
/// and the new one (`back`).
pub(super) trait SlabRule {
    /// Whether a step composites the segment between two samples (else the slab of `back`).
    const SEGMENTS: bool;

    /// Composites each lane's full slab or segment under its accumulated colour `acc`
    /// (emission only). An undefined (NaN) sample adds nothing, nor does a segment that ends
    /// at one.
    fn composite(&self, front: &[f32; LANES], back: &[f32; LANES], acc: &mut [[f32; 4]; LANES]);

    /// The premultiplied colour and opacity of each lane's full slab or segment (to be lit).
    fn entries(&self, front: &[f32; LANES], back: &[f32; LANES]) -> [[f32; 4]; LANES];

    /// One full segment's entry, as the ray-by-ray path computes it (segments only).
    fn segment(&self, front: f32, back: f32) -> [f32; 4];

    /// The entry of a segment shortened to the fraction `frac` of a step, and the fraction
    /// [`under_partial`] is still to correct it for (segments only); `None` when the
    /// segment adds nothing. By default the full segment's entry, opacity-corrected for its
    /// length, and nothing next to an undefined (NaN) sample.
    fn partial_segment(&self, front: f32, back: f32, frac: f32) -> Option<([f32; 4], f32)> {
        (!front.is_nan() && !back.is_nan()).then(|| (self.segment(front, back), frac))
    }
}

/// The Riemann sum: each sample's colour and slab opacity from the step table.
impl SlabRule for LaneTable {
    const SEGMENTS: bool = false;

    // Fused, not `entries` then `composite_entries`: going through the array of entries made
    // the Riemann frame 12 % slower (168 against 150 ms on Marschner-Lobb, best of 5).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn composite(&self, _front: &[f32; LANES], v: &[f32; LANES], acc: &mut [[f32; 4]; LANES]) {
        // Entries and fractions in two arrays (not pairs, which took shuffles to interleave),
        // and the lanes four at a time (a 16-lane loop was not unrolled).
        let (mut entry, mut frac) = ([0u32; LANES], [0.0f32; LANES]);
        for l in 0..LANES {
            (entry[l], frac[l]) = self.position(v[l]);
        }
        for g in (0..LANES).step_by(4) {
            for l in g..g + 4 {
                under_if(&mut acc[l], self.at(entry[l], frac[l]), !v[l].is_nan());
            }
        }
    }

    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn entries(&self, _front: &[f32; LANES], v: &[f32; LANES]) -> [[f32; 4]; LANES] {
        let mut at = [(0u32, 0.0f32); LANES];
        for l in 0..LANES {
            at[l] = self.position(v[l]);
        }
        let mut e = [[0.0f32; 4]; LANES];
        for l in 0..LANES {
            e[l] = self.at(at[l].0, at[l].1);
        }
        e
    }

    fn segment(&self, _front: f32, back: f32) -> [f32; 4] {
        let (i, f) = self.position(back);
        self.at(i, f)
    }
}

/// Pre-integration: each segment from the table entry of its front and back values.
impl SlabRule for PreintegrationTable {
    const SEGMENTS: bool = true;

    #[inline(always)]
    fn composite(&self, front: &[f32; LANES], back: &[f32; LANES], acc: &mut [[f32; 4]; LANES]) {
        composite_entries::<Self>(&self.entries(front, back), front, back, acc);
    }

    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn entries(&self, front: &[f32; LANES], back: &[f32; LANES]) -> [[f32; 4]; LANES] {
        let mut e = [[0.0f32; 4]; LANES];
        for l in 0..LANES {
            e[l] = self.lookup_lanes(front[l], back[l]);
        }
        e
    }

    fn segment(&self, front: f32, back: f32) -> [f32; 4] {
        self.lookup(front, back)
    }
}

/// The fixed-step trapezoid rule (`001_...txt` eq. 2.16 for both integrals) on the segments
/// between consecutive samples, in f32 lanes: with extinctions `tau_a`, `tau_b` and colours
/// `c_a`, `c_b` at a segment's ends, its opacity is `1 - exp(-h (tau_a + tau_b) / 2)` and its
/// colour, premultiplied and relative to the transmittance at its front,
/// `h / 2 (c_a tau_a + c_b tau_b (1 - alpha))`: composited front to back, the same sums as
/// [`fixed_intervals`](crate::integrate::fixed_intervals), whose undefined samples are empty
/// medium (no colour, no extinction) and do not stop the segment. Emission only: shaded rays
/// take the per-sample path, which lights each end apart.
pub(super) struct TrapezoidRule<'a> {
    /// Colour and extinction per world unit by value.
    pub(super) table: &'a LaneTable,
    /// The step in world units.
    pub(super) h: f32,
}

impl TrapezoidRule<'_> {
    /// Colour and extinction of the value `v`; an undefined value is empty medium.
    #[inline(always)]
    fn classify_one(&self, v: f32) -> [f32; 4] {
        let (i, f) = self.table.position(v);
        let c = self.table.at(i, f);
        if v.is_nan() {
            [0.0; 4]
        } else {
            c
        }
    }

    /// [`TrapezoidRule::classify_one`] of each lane's value.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn classify(&self, v: &[f32; LANES]) -> [[f32; 4]; LANES] {
        let mut e = [[0.0f32; 4]; LANES];
        for l in 0..LANES {
            e[l] = self.classify_one(v[l]);
        }
        e
    }

    /// The entries of segments of length `h` between the classified ends `a` and `b`.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn rule<const N: usize>(a: &[[f32; 4]; N], b: &[[f32; 4]; N], h: [f32; N]) -> [[f32; 4]; N] {
        let mut trans = [0.0f32; N];
        for l in 0..N {
            trans[l] = -0.5 * h[l] * (a[l][3] + b[l][3]);
        }
        exp_lanes(&mut trans);
        let mut e = [[0.0f32; 4]; N];
        for l in 0..N {
            let (wa, wb) = (0.5 * h[l] * a[l][3], 0.5 * h[l] * b[l][3] * trans[l]);
            for c in 0..3 {
                e[l][c] = wa * a[l][c] + wb * b[l][c];
            }
            e[l][3] = 1.0 - trans[l];
        }
        e
    }
}

impl SlabRule for TrapezoidRule<'_> {
    const SEGMENTS: bool = true;

    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn composite(&self, front: &[f32; LANES], back: &[f32; LANES], acc: &mut [[f32; 4]; LANES]) {
        let e = self.entries(front, back);
        for l in 0..LANES {
            let w = 1.0 - acc[l][3];
            for c in 0..4 {
                acc[l][c] += w * e[l][c];
            }
        }
    }

    #[inline(always)]
    fn entries(&self, front: &[f32; LANES], back: &[f32; LANES]) -> [[f32; 4]; LANES] {
        Self::rule(&self.classify(front), &self.classify(back), [self.h; LANES])
    }

    fn segment(&self, front: f32, back: f32) -> [f32; 4] {
        self.partial_segment(front, back, 1.0)
            .map_or([0.0; 4], |(e, _)| e)
    }

    /// The rule on the shortened segment itself: no correction left.
    fn partial_segment(&self, front: f32, back: f32, frac: f32) -> Option<([f32; 4], f32)> {
        let (a, b) = (self.classify_one(front), self.classify_one(back));
        let e = Self::rule(&[a], &[b], [self.h * frac]);
        Some((e[0], 1.0))
    }
}

/// Composites the entries `e` of each lane's slab or segment under `acc` (see
/// [`SlabRule::composite`]).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn composite_entries<R: SlabRule>(
    e: &[[f32; 4]; LANES],
    front: &[f32; LANES],
    back: &[f32; LANES],
    acc: &mut [[f32; 4]; LANES],
) {
    for l in 0..LANES {
        let undefined = back[l].is_nan() | (R::SEGMENTS & front[l].is_nan());
        under_if(&mut acc[l], e[l], !undefined);
    }
}

/// The most steps a lane composites in `f32` before folding them into its `f64` sum.
const BLOCK_STEPS: i32 = 32;

/// The opacity of a block at which a ray of opacity `a` so far reaches `stop`: the `x` with
/// `a + (1 - a) x = stop`; minus infinity once `a` reaches `stop`, infinite for a ray without
/// early termination that is opaque.
#[inline(always)]
fn block_stop(stop: f64, a: f64) -> f32 {
    if a >= stop {
        f32::NEG_INFINITY
    } else {
        ((stop - a) / (1.0 - a)) as f32
    }
}

/// Side of the pixel blocks in which a tile's rays enter the lanes.
const BLOCK: usize = 4;

/// How far (voxels) a ray's first walk of its spans reaches; each later walk reaches twice as
/// far as the one before. Rays that become opaque early never walk the rest of the macrocells
/// they cross: the walk was 10 % of a Marschner-Lobb frame and 23 % of an MRI head frame
/// (Riemann 0.5, perf), most of it past the early-termination point.
const FIRST_REACH: f64 = 64.0;

/// The lighting of one step's lanes: the lit colour is `rgb k + s`.
struct LaneLight {
    k: [f32; LANES],
    s: [f32; LANES],
}

impl LaneLight {
    /// The premultiplied entry `e` of lane `l`, lit: `rgb a k + s a`.
    #[inline(always)]
    fn apply(&self, e: [f32; 4], l: usize) -> [f32; 4] {
        let (k, s) = (self.k[l], self.s[l] * e[3]);
        [e[0] * k + s, e[1] * k + s, e[2] * k + s, e[3]]
    }
}

/// Per-lane bookkeeping, touched once per span.
#[derive(Default)]
struct LaneRay {
    /// Index of the ray's pixel in its tile.
    pixel: usize,
    /// Voxel-space position of sample 0 (f64, for the partial last slab) and step.
    base: DVec3,
    step: DVec3,
    /// Distance of sample 0 and step length (world units), and the ray's entry and exit
    /// distances.
    start: f64,
    h: f64,
    t0: f64,
    t1: f64,
    spans: Vec<(f64, f64)>,
    /// Voxel-space origin and direction of the ray, where the walk of its spans stopped
    /// (`t1` once walked to the end) and how far (voxels) the next walk reaches.
    o_v: DVec3,
    d_v: DVec3,
    walked: f64,
    reach: f64,
    /// The ray's world direction, for lighting.
    view: Vec3,
    /// The next span to enter.
    span: usize,
    /// First lane step of the current span, and the end (exclusive) of the span's slabs.
    i_first: i32,
    i_after: i32,
    /// The ray's first shortened slab or segment ([`LaneRay::first_partial`]).
    partial: i32,
    /// Segments before this one are composited (a segment may straddle two spans).
    next: i32,
    samples: u64,
}

impl LaneRay {
    /// The first sample index `i` with `start + i h >= b` (0 at least).
    fn first_at_or_after(&self, b: f64) -> i32 {
        first_at_or_after(self.start, self.h, b)
    }

    /// The first sample index `i` with `start + i h > a`.
    fn first_after(&self, a: f64) -> i32 {
        let mut k = self.first_at_or_after(a);
        while self.start + self.h * f64::from(k) <= a {
            k += 1;
        }
        k
    }

    /// The first slab (Riemann: `[t_i, t_i + h]`; segments: `[t_(i-1), t_i]`) reaching
    /// beyond the ray's exit: it and those after it are shortened.
    fn first_partial(&self, segments: bool) -> i32 {
        if segments {
            return self.first_after(self.t1);
        }
        let mut k = self.first_at_or_after(self.t1 - self.h);
        while k > 0 && self.start + self.h * f64::from(k - 1) + self.h > self.t1 {
            k -= 1;
        }
        while self.start + self.h * f64::from(k) + self.h <= self.t1 {
            k += 1;
        }
        k
    }

    /// Walks the ray's next spans from where the last walk stopped, twice as far as the last
    /// time (rays that become opaque early never walk the rest); false when none is left.
    fn walk_on(&mut self, intervals: Option<&dyn IntervalSource>, unit: f64) -> bool {
        let Some(occ) = intervals else {
            return false;
        };
        while self.walked < self.t1 {
            self.reach *= 2.0;
            let limit = self.walked + self.reach * unit;
            let ends = (self.walked, self.t1);
            self.walked = occ.occupied_until(self.o_v, self.d_v, ends, limit, &mut self.spans);
            self.span = 0;
            if !self.spans.is_empty() {
                return true;
            }
        }
        false
    }

    /// The voxel-space position of sample `i`, clamped to the ray's extent.
    fn position(&self, i: i32) -> Vec3 {
        self.position_at(self.start + self.h * f64::from(i))
    }

    /// The voxel-space position at distance `t`, clamped to the ray's extent.
    fn position_at(&self, t: f64) -> Vec3 {
        let t = t.clamp(self.t0, self.t1);
        (self.base + self.step * ((t - self.start) / self.h)).as_vec3()
    }
}

/// Each lane's sample lattice, `base + i step` in voxel space: the next sample index `i`, and
/// the end (exclusive) of the run of samples the lane takes before it needs attention. An
/// idle lane steps in place and never ends. Shared by the lane traversals.
pub(super) struct LaneLattice {
    base: Lanes3,
    step: Lanes3,
    pub(super) i: [i32; LANES],
    pub(super) end: [i32; LANES],
}

impl LaneLattice {
    pub(super) fn new() -> Self {
        Self {
            base: [[0.0; LANES]; 3],
            step: [[0.0; LANES]; 3],
            i: [0; LANES],
            end: [i32::MAX; LANES],
        }
    }

    /// Lane `l` takes the lattice of sample 0 at `base` and step `step` (voxel space).
    pub(super) fn set(&mut self, l: usize, base: DVec3, step: DVec3) {
        for a in 0..3 {
            self.base[a][l] = base[a] as f32;
            self.step[a][l] = step[a] as f32;
        }
    }

    /// Lane `l` now samples from `i` up to `end` (exclusive).
    pub(super) fn enter(&mut self, l: usize, i: i32, end: i32) {
        (self.i[l], self.end[l]) = (i, end);
    }

    /// Lane `l` steps in place and never ends.
    pub(super) fn idle(&mut self, l: usize) {
        (self.i[l], self.end[l]) = (0, i32::MAX);
        for a in 0..3 {
            self.step[a][l] = 0.0;
        }
    }

    /// The voxel-space positions of every lane's next sample.
    #[inline(always)]
    pub(super) fn positions(&self) -> Lanes3 {
        self.positions_at(&self.i)
    }

    /// The voxel-space positions of the samples `i` of the lanes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(super) fn positions_at(&self, i: &[i32; LANES]) -> Lanes3 {
        let mut pos = [[0.0f32; LANES]; 3];
        for a in 0..3 {
            for l in 0..LANES {
                pos[a][l] = self.base[a][l] + self.step[a][l] * i[l] as f32;
            }
        }
        pos
    }

    /// The voxel-space positions of the samples `first + k` of the lanes, `first` their
    /// indices as f32: the same values as [`LaneLattice::positions_at`] (indices below 2^24
    /// are exact in f32), without converting every lane's index every step.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(super) fn positions_after(&self, first: &[f32; LANES], k: f32) -> Lanes3 {
        let mut pos = [[0.0f32; LANES]; 3];
        for a in 0..3 {
            for l in 0..LANES {
                pos[a][l] = self.base[a][l] + self.step[a][l] * (first[l] + k);
            }
        }
        pos
    }

    /// The number of samples every lane takes before the first one reaches its end (one at
    /// least): a run of steps that needs no per-lane end test.
    pub(super) fn run(&self) -> i32 {
        let mut run = i32::MAX;
        for l in 0..LANES {
            run = run.min(self.end[l].saturating_sub(self.i[l]));
        }
        run.max(1)
    }

    /// The bit mask of the lanes that reached their end.
    #[inline(always)]
    pub(super) fn ended(&self) -> u32 {
        let mut ended = 0u32;
        for l in 0..LANES {
            ended |= u32::from(self.i[l] >= self.end[l]) << l;
        }
        ended
    }

    /// Advances every lane by one sample; the bit mask of the lanes that reached their end.
    #[inline(always)]
    pub(super) fn advance(&mut self) -> u32 {
        let mut ended = 0u32;
        for l in 0..LANES {
            self.i[l] += 1;
            ended |= u32::from(self.i[l] >= self.end[l]) << l;
        }
        ended
    }
}

/// The lanes: hot per-sample state laid out lane-wise, and each lane's ray.
struct Lanes {
    /// The lattices; a lane's run ends with the full slabs of its current span.
    lattice: LaneLattice,
    /// Each lane's current block, composited from zero in `f32`.
    acc: [[f32; 4]; LANES],
    /// Each lane's ray up to its current block, in `f64` ([`RayAccumulator`]).
    sum: [[f64; 4]; LANES],
    /// The last sample taken (the front of the next segment; NaN where undefined).
    front: [f32; LANES],
    /// Opacity of the current block at which the lane's ray stops (from `ray_stop` and
    /// `sum`); infinite for an idle lane.
    stop: [f32; LANES],
    /// Opacity at which the lane's ray stops; infinite for an idle lane.
    ray_stop: [f64; LANES],
    /// Lighting directions of the lane's ray (towards the eye, the light, their half vector)
    /// and whether it is lit.
    to_eye: Lanes3,
    light: Lanes3,
    half: Lanes3,
    lit: [bool; LANES],
    rays: [LaneRay; LANES],
    live: [bool; LANES],
    /// The lanes whose current span the field may hide part of (a sculpt mask's partly
    /// removed macrocells, or unknown): only their samples are tested against the mask.
    hiding: u32,
}

impl Lanes {
    fn new() -> Self {
        Self {
            lattice: LaneLattice::new(),
            acc: [[0.0; 4]; LANES],
            sum: [[0.0; 4]; LANES],
            front: [0.0; LANES],
            stop: [f32::INFINITY; LANES],
            ray_stop: [f64::INFINITY; LANES],
            to_eye: [[0.0; LANES]; 3],
            light: [[0.0; LANES]; 3],
            half: [[0.0; LANES]; 3],
            lit: [false; LANES],
            rays: std::array::from_fn(|_| LaneRay::default()),
            live: [false; LANES],
            hiding: 0,
        }
    }

    /// Makes lane `l` idle (it keeps stepping in place, its results unused).
    fn idle(&mut self, l: usize) {
        self.live[l] = false;
        self.hiding &= !(1 << l);
        self.stop[l] = f32::INFINITY;
        self.ray_stop[l] = f64::INFINITY;
        self.lattice.idle(l);
    }

    /// Lane `l` starts a ray that stops at opacity `stop`.
    fn start(&mut self, l: usize, stop: f64) {
        self.live[l] = true;
        self.ray_stop[l] = stop;
        self.set_sum(l, RayAccumulator::default());
    }

    /// Composites lane `l`'s block under its ray's sum and starts a new block.
    #[inline(always)]
    fn fold(&mut self, l: usize) {
        let mut sum = self.sum[l];
        under64(&mut sum, self.acc[l].map(f64::from));
        self.set_sum(l, RayAccumulator { rgba: sum });
    }

    /// [`Lanes::fold`] of every lane (written lane-wise, the fold took 0.2 % fewer
    /// instructions: not worth a second copy of it).
    #[inline(always)]
    fn fold_all(&mut self) {
        for l in 0..LANES {
            self.fold(l);
        }
    }

    /// Lane `l`'s ray so far, its block folded in.
    fn ray(&mut self, l: usize) -> RayAccumulator {
        self.fold(l);
        RayAccumulator { rgba: self.sum[l] }
    }

    /// Lane `l`'s ray is `sum`, with an empty block ([`block_stop`]).
    #[inline(always)]
    fn set_sum(&mut self, l: usize, sum: RayAccumulator) {
        self.sum[l] = sum.rgba;
        self.acc[l] = [0.0; 4];
        self.stop[l] = block_stop(self.ray_stop[l], sum.rgba[3]);
    }
}

impl<F: Field> RayContext<'_, F> {
    /// Renders the tile at (`x0`, `y0`) with the lane stream (see the module docs).
    pub(super) fn lane_stream<R: SlabRule>(&self, rule: &R, x0: usize, y0: usize) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let (tw, th) = ((x0 + TILE).min(w) - x0, (y0 + TILE).min(h) - y0);
        let mut px = vec![PixelOut::default(); tw * th];
        let mut queue = block_order(tw, th).into_iter();
        let mut lanes = Lanes::new();
        for l in 0..LANES {
            self.refill(rule, &mut lanes, l, &mut queue, &mut px, (x0, y0, tw));
        }
        let shading = self.stream_shading();
        while lanes.live.iter().any(|&b| b) {
            let cold = match shading {
                Some(sh) => self.steps::<R, true>(&mut lanes, rule, Some(sh)),
                None => self.steps::<R, false>(&mut lanes, rule, None),
            };
            for l in 0..LANES {
                if cold & (1 << l) != 0 {
                    self.lane_event(rule, &mut lanes, l, &mut queue, &mut px, (x0, y0, tw));
                }
            }
        }
        px
    }

    /// Advances every lane by one sample until some live lane needs attention; returns the
    /// bit mask of those lanes.
    // Lane loops index several per-lane arrays at once: that is what vectorizes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn steps<R: SlabRule, const LIT: bool>(
        &self,
        lanes: &mut Lanes,
        rule: &R,
        shading: Option<StreamShading<'_>>,
    ) -> u32 {
        // A run of steps that no lane's end interrupts, with the sample indices in a local
        // array: testing each lane's end every step took about 11 instructions per sample (the
        // compiler extracted, incremented and compared each lane's index on its own).
        // Every lane advances one sample per step: the run counts the steps, and the lanes'
        // indices advance by that count at its end.
        // Runs of at most a block: folding inside the run cost more (4 % of a CT frame's
        // instructions against 2.3 %: the lanes' sums no longer stayed in registers).
        let run = lanes.lattice.run().min(BLOCK_STEPS);
        let first = lanes.lattice.i.map(|i| i as f32);
        let mut k = 0;
        while k < run {
            let pos = lanes.lattice.positions_after(&first, k as f32);
            let mut v = self.field.sample_lanes_unhidden(&pos);
            if lanes.hiding != 0 {
                self.field.hide_lanes(&pos, &mut v, lanes.hiding);
            }
            match shading {
                Some(sh) if LIT => {
                    let mut e = rule.entries(&lanes.front, &v);
                    // Light only steps where some lane is not transparent.
                    if e.iter().any(|e| e[3] > 0.0) {
                        let light = Self::light_step::<R>(sh, lanes, &pos);
                        for (l, e) in e.iter_mut().enumerate() {
                            *e = light.apply(*e, l);
                        }
                    }
                    composite_entries::<R>(&e, &lanes.front, &v, &mut lanes.acc);
                }
                _ => rule.composite(&lanes.front, &v, &mut lanes.acc),
            }
            if R::SEGMENTS {
                lanes.front = v;
            }
            k += 1;
            // Whether some lane became opaque, as one i32 mask reduction (a bool one was
            // branch by branch).
            let mut opaque = 0i32;
            for l in 0..LANES {
                opaque |= -i32::from(lanes.acc[l][3] >= lanes.stop[l]);
            }
            if opaque != 0 {
                break;
            }
        }
        for i in lanes.lattice.i.iter_mut() {
            *i += k;
        }
        lanes.fold_all();
        let mut mask = lanes.lattice.ended();
        for l in 0..LANES {
            mask |= u32::from(lanes.acc[l][3] >= lanes.stop[l]) << l;
        }
        mask
    }

    /// The lighting of this step's lanes at their sample positions `pos` (Riemann) or at the
    /// middle of their segments (pre-integration).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn light_step<R: SlabRule>(sh: StreamShading<'_>, lanes: &Lanes, pos: &Lanes3) -> LaneLight {
        let mut p = *pos;
        if R::SEGMENTS {
            for a in 0..3 {
                for l in 0..LANES {
                    p[a][l] -= 0.5 * lanes.lattice.step[a][l];
                }
            }
        }
        let mut g = sh.gradients.gradient_lanes(&p);
        if let Some(cuts) = sh.cut_faces {
            cuts.lighting_gradient_lanes(&p, &mut g, lanes.hiding);
        }
        let dirs = (&lanes.to_eye, &lanes.light, &lanes.half);
        let (k, s) = sh.model.light_lanes(&g, dirs, &lanes.lit);
        LaneLight { k, s }
    }

    /// Handles lane `l` after its last sample: early termination, the end of its span (with
    /// the partial last slab of the ray), or a new ray.
    fn lane_event<R: SlabRule>(
        &self,
        rule: &R,
        lanes: &mut Lanes,
        l: usize,
        queue: &mut impl Iterator<Item = usize>,
        px: &mut [PixelOut],
        tile: (usize, usize, usize),
    ) {
        if !lanes.live[l] {
            return;
        }
        let done = lanes.lattice.i[l];
        let r = &mut lanes.rays[l];
        r.samples += (done - r.i_first).max(0) as u64;
        if lanes.acc[l][3] < lanes.stop[l] && self.continue_ray(rule, lanes, l, done) {
            return;
        }
        self.finish(lanes, l, px);
        self.refill(rule, lanes, l, queue, px, tile);
    }

    /// Lane `l`'s ray has composited its current span's slabs before `done`: composites the
    /// span's remaining ones (shortened at the ray's end), then enters the next span that
    /// has full slabs. False when the ray is finished (no span left, or opaque).
    fn continue_ray<R: SlabRule>(&self, rule: &R, lanes: &mut Lanes, l: usize, done: i32) -> bool {
        let mut range = (done, lanes.rays[l].i_after);
        loop {
            if !self.shortened(rule, lanes, l, range) {
                return false;
            }
            let r = &mut lanes.rays[l];
            if r.span == r.spans.len()
                && !r.walk_on(self.intervals, self.place.spacing.min_element())
            {
                return false;
            }
            let (a, b) = r.spans[r.span];
            r.span += 1;
            let hides = self
                .mask_classes
                .is_none_or(|o| o.class_at(r.o_v + r.d_v * (0.5 * (a + b))) != CellClass::Sample);
            lanes.hiding = (lanes.hiding & !(1 << l)) | (u32::from(hides) << l);
            let (first, after, lane_first) = if R::SEGMENTS {
                // The segments that overlap `[a, b]` and are not composited yet; segment 0
                // (before `t_0`) is shortened.
                let first = r.first_after(a).max(r.next);
                let after = (r.first_at_or_after(b) + 1).max(first);
                r.next = after;
                (first, after, first.max(1).min(after))
            } else {
                // The exact comparison of `first_at_or_after`: spans that touch (a run the
                // mask hides in part next to one it does not) share their boundary sample
                // neither twice nor never.
                let first = r.first_at_or_after(a);
                (first, r.first_at_or_after(b).max(first), first)
            };
            if R::SEGMENTS && first < after {
                // The span's first segment starts from a fresh sample, as ray by ray.
                lanes.front[l] = self.field.sample(r.position(first - 1)).unwrap_or(f32::NAN);
                r.samples += 1;
                if !self.shortened(rule, lanes, l, (first, lane_first)) {
                    return false;
                }
            }
            let r = &mut lanes.rays[l];
            let end = after.min(r.partial).max(lane_first);
            (r.i_first, r.i_after) = (lane_first, after);
            if end > lane_first {
                lanes.lattice.enter(l, lane_first, end);
                return true;
            }
            range = (lane_first, after);
        }
    }

    /// Composites lane `l`'s slabs or segments `from..to` one by one, each with the part of
    /// it inside the ray; false if the ray became opaque.
    fn shortened<R: SlabRule>(
        &self,
        rule: &R,
        lanes: &mut Lanes,
        l: usize,
        (from, to): (i32, i32),
    ) -> bool {
        let mut acc = lanes.ray(l);
        let stop = lanes.ray_stop[l];
        let r = &mut lanes.rays[l];
        for i in from..to {
            let t = r.start + r.h * f64::from(i);
            let v = self.field.sample(r.position(i));
            r.samples += 1;
            if R::SEGMENTS {
                let front = lanes.front[l];
                let back = v.unwrap_or(f32::NAN);
                lanes.front[l] = back;
                let (ta, tb) = ((t - r.h).max(r.t0), t.min(r.t1));
                let Some((e, frac)) = rule.partial_segment(front, back, ((tb - ta) / r.h) as f32)
                else {
                    continue;
                };
                let mid = r.position_at(0.5 * (ta + tb));
                under_partial(&mut acc, self.lit_segment(e, mid, r.view), frac);
            } else if let Some(v) = v {
                let c = self.lit_sample(self.table.lookup(v), r.position(i), r.view);
                riemann_step(&mut acc, c, (r.t1 - t).min(r.h) as f32);
            }
            if acc.alpha() >= stop {
                lanes.set_sum(l, acc);
                return false;
            }
        }
        lanes.set_sum(l, acc);
        true
    }

    /// Writes lane `l`'s pixel.
    fn finish(&self, lanes: &mut Lanes, l: usize, px: &mut [PixelOut]) {
        let acc = lanes.ray(l);
        let r = &lanes.rays[l];
        px[r.pixel] = PixelOut::composited(&acc, r.samples);
        lanes.idle(l);
    }

    /// Loads the next ray of the tile that hits the volume into lane `l` (rays that miss are
    /// written as they are met); leaves the lane idle when the tile is done.
    fn refill<R: SlabRule>(
        &self,
        rule: &R,
        lanes: &mut Lanes,
        l: usize,
        queue: &mut impl Iterator<Item = usize>,
        px: &mut [PixelOut],
        (x0, y0, tw): (usize, usize, usize),
    ) {
        let (Integrator::Riemann { step }
        | Integrator::Preintegrated { step }
        | Integrator::Trapezoid { step }) = self.opts.integrator
        else {
            return;
        };
        // The trapezoid rule samples `t0 + i h`, as ray by ray.
        let jittered =
            self.opts.jitter && !matches!(self.opts.integrator, Integrator::Trapezoid { .. });
        for pixel in queue.by_ref() {
            let (gx, gy) = (x0 + pixel % tw, y0 + pixel / tw);
            let ray = self.rays.ray(gx as f64 + 0.5, gy as f64 + 0.5);
            let jitter = if jittered { pixel_hash(gx, gy) } else { 0.0 };
            let mut spans = std::mem::take(&mut lanes.rays[l].spans);
            let Some(((o_v, d_v, t0, t1, unit), walked)) =
                self.setup_until(ray.origin, ray.dir, &mut spans, FIRST_REACH)
            else {
                lanes.rays[l].spans = spans;
                continue;
            };
            let hh = step * unit;
            let start = t0 + jitter * hh;
            let (base, stp) = (o_v + d_v * start, d_v * hh);
            let view = (d_v * self.place.spacing).normalize_or_zero().as_vec3();
            lanes.rays[l] = LaneRay {
                pixel,
                base,
                step: stp,
                start,
                h: hh,
                t0,
                t1,
                spans,
                o_v,
                d_v,
                walked,
                reach: FIRST_REACH,
                view,
                ..LaneRay::default()
            };
            if let Some(sh) = self.stream_shading() {
                let ray = sh.model.ray_light(view);
                let r = ray.unwrap_or_default();
                for a in 0..3 {
                    lanes.to_eye[a][l] = r.to_eye[a];
                    lanes.light[a][l] = r.light[a];
                    lanes.half[a][l] = r.half[a];
                }
                lanes.lit[l] = ray.is_some();
            }
            lanes.rays[l].partial = lanes.rays[l].first_partial(R::SEGMENTS);
            lanes.lattice.set(l, base, stp);
            lanes.start(l, f64::from(self.opts.early_termination.unwrap_or(2.0)));
            if self.continue_ray(rule, lanes, l, 0) {
                return;
            }
            self.finish(lanes, l, px);
        }
        lanes.idle(l);
    }
}

impl<F: Field> RayContext<'_, F> {
    /// The shading of the lane stream: the model and the cached gradient volume, if shading
    /// is on.
    pub(super) fn stream_shading(&self) -> Option<StreamShading<'_>> {
        Some(StreamShading {
            model: self.opts.shading.as_ref()?,
            gradients: self.gradients?,
            cut_faces: self.cut_faces.as_ref(),
        })
    }
}

/// Pixel indices of a `tw` x `th` tile in [`BLOCK`] x [`BLOCK`] blocks, row-major within
/// and across blocks.
pub(super) fn block_order(tw: usize, th: usize) -> Vec<usize> {
    let mut out = Vec::with_capacity(tw * th);
    for by in (0..th).step_by(BLOCK) {
        for bx in (0..tw).step_by(BLOCK) {
            for y in by..(by + BLOCK).min(th) {
                for x in bx..(bx + BLOCK).min(tw) {
                    out.push(y * tw + x);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raycast::context::ceil_index;

    #[test]
    fn ceil_index_is_the_clamped_ceiling() {
        for x in [0.0, 0.2, 1.0, 1.000_000_1, 2.5, 7.999_999, 1e6 + 0.5] {
            assert_eq!(ceil_index(x), x.ceil() as i32, "{x}");
        }
        assert_eq!(ceil_index(-3.5), 0);
        assert_eq!(ceil_index(f64::NAN), 0);
        assert_eq!(ceil_index(1e300), i32::MAX / 2);
    }

    /// A run ends with the first lane to reach its end; idle lanes never end it, and a run is
    /// one sample at least.
    #[test]
    fn a_run_ends_with_the_first_lane_to_end() {
        let mut lattice = LaneLattice::new();
        assert_eq!(lattice.run(), i32::MAX);
        lattice.enter(3, 10, 17);
        lattice.enter(9, 0, 40);
        assert_eq!(lattice.run(), 7);
        for _ in 0..7 {
            lattice.advance();
        }
        assert_eq!(lattice.ended(), 1 << 3);
        lattice.idle(3);
        assert_eq!(lattice.run(), 33);
        lattice.enter(5, 8, 8);
        assert_eq!(lattice.run(), 1);
    }

    #[test]
    fn block_order_visits_every_pixel_once() {
        for (tw, th) in [(16, 16), (7, 5), (1, 9), (4, 4)] {
            let mut seen = block_order(tw, th);
            assert_eq!(seen.len(), tw * th);
            seen.sort_unstable();
            assert!(seen.iter().enumerate().all(|(k, &p)| k == p), "{tw}x{th}");
        }
        // The first block of a 16-wide tile is its top-left 4 x 4 pixels.
        let order = block_order(16, 16);
        assert_eq!(&order[..5], &[0, 1, 2, 3, 16]);
    }
}
