//! Maximum intensity projection in lanes: the rays of a tile flow through [`LANES`] lanes that
//! sample their lattices together, each lane keeping its largest sample and the two samples
//! around it; when a ray ends, its maximum is refined between samples as ray by ray
//! ([`mip::refine_peak`]) and its pixel written. The same lattice, maximum and refinement as
//! [`RayContext::mip`] (tested), with the lattice sampled in f32.
use super::context::{MipRay, PixelOut, RayContext};
use super::stream::{block_order, LaneLattice};
use crate::mip;
use crate::sampling::{Field, LANES};
use crate::tiles::TILE;

/// The lanes: per-lane lattice and running maximum, and each lane's ray.
struct MipLanes {
    /// The lattices; a lane's run is its ray's whole lattice.
    lattice: LaneLattice,
    /// The largest sample so far (`-inf` before any), its index, the samples before and after
    /// it (NaN where undefined or not taken yet), and whether the one after is due.
    best: [f32; LANES],
    best_i: [i32; LANES],
    before: [f32; LANES],
    after: [f32; LANES],
    waiting: [bool; LANES],
    /// The previous sample (NaN where undefined).
    prev: [f32; LANES],
    rays: [(usize, MipRay); LANES],
    live: [bool; LANES],
}

impl MipLanes {
    fn new() -> Self {
        Self {
            lattice: LaneLattice::new(),
            best: [f32::NEG_INFINITY; LANES],
            best_i: [0; LANES],
            before: [f32::NAN; LANES],
            after: [f32::NAN; LANES],
            waiting: [false; LANES],
            prev: [f32::NAN; LANES],
            rays: [(0, MipRay::default()); LANES],
            live: [false; LANES],
        }
    }

    /// Lane `l` starts ray `ray` of pixel `pixel` with `n` lattice samples.
    fn start(&mut self, l: usize, pixel: usize, ray: MipRay, n: i32) {
        let (base, step) = (ray.o_v + ray.d_v * ray.t0, ray.d_v * ray.step);
        self.lattice.set(l, base, step);
        self.lattice.enter(l, 0, n);
        (self.best[l], self.best_i[l]) = (f32::NEG_INFINITY, 0);
        (self.before[l], self.after[l], self.prev[l]) = (f32::NAN, f32::NAN, f32::NAN);
        self.waiting[l] = false;
        self.rays[l] = (pixel, ray);
        self.live[l] = true;
    }

    /// Makes lane `l` idle (it keeps sampling in place, its results unused).
    fn idle(&mut self, l: usize) {
        self.live[l] = false;
        self.lattice.idle(l);
    }
}

impl<F: Field> RayContext<'_, F> {
    /// Renders the tile at (`x0`, `y0`) by maximum intensity projection, in lanes.
    pub(super) fn mip_stream(&self, x0: usize, y0: usize) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let (tw, th) = ((x0 + TILE).min(w) - x0, (y0 + TILE).min(h) - y0);
        let mut px = vec![PixelOut::default(); tw * th];
        let mut queue = block_order(tw, th).into_iter();
        let mut lanes = MipLanes::new();
        for l in 0..LANES {
            self.mip_refill(&mut lanes, l, &mut queue, (x0, y0, tw));
        }
        while lanes.live.iter().any(|&b| b) {
            let done = self.mip_steps(&mut lanes);
            for l in 0..LANES {
                if done & (1 << l) != 0 && lanes.live[l] {
                    px[lanes.rays[l].0] = self.mip_finish(&lanes, l);
                    self.mip_refill(&mut lanes, l, &mut queue, (x0, y0, tw));
                }
            }
        }
        px
    }

    /// Advances every lane by one sample until some lane has sampled its whole lattice;
    /// returns the bit mask of those lanes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn mip_steps(&self, lanes: &mut MipLanes) -> u32 {
        loop {
            let v = self.field.sample_lanes(&lanes.lattice.positions());
            for l in 0..LANES {
                // Non-finite values are undefined; NaN never compares larger.
                let v = if v[l].is_finite() { v[l] } else { f32::NAN };
                if lanes.waiting[l] {
                    lanes.after[l] = v;
                }
                // The first of equal maxima wins.
                let better = v > lanes.best[l];
                lanes.waiting[l] = better;
                if better {
                    (lanes.best[l], lanes.best_i[l]) = (v, lanes.lattice.i[l]);
                    (lanes.before[l], lanes.after[l]) = (lanes.prev[l], f32::NAN);
                }
                lanes.prev[l] = v;
            }
            let done = lanes.lattice.advance();
            if done != 0 {
                return done;
            }
        }
    }

    /// The pixel of lane `l`'s finished ray: its maximum refined between samples.
    fn mip_finish(&self, lanes: &MipLanes, l: usize) -> PixelOut {
        let ray = lanes.rays[l].1;
        let mut n = lanes.lattice.end[l] as u64;
        let best = lanes.best[l];
        if best == f32::NEG_INFINITY {
            return self.mip_pixel(None, n);
        }
        let defined = |v: f32| (!v.is_nan()).then_some(v);
        let t = ray.t0 + ray.step * f64::from(lanes.best_i[l]);
        let around = (defined(lanes.before[l]), defined(lanes.after[l]));
        let (v, _) = mip::refine_peak((best, t), around, ray.step, |t| {
            n += 1;
            self.field.sample64(ray.o_v + ray.d_v * t).map(|v| v as f32)
        });
        self.mip_pixel(Some(v), n)
    }

    /// Starts the tile's next ray that hits the volume in lane `l` (rays that miss keep their
    /// default pixel), or leaves the lane idle.
    fn mip_refill(
        &self,
        lanes: &mut MipLanes,
        l: usize,
        queue: &mut impl Iterator<Item = usize>,
        (x0, y0, tw): (usize, usize, usize),
    ) {
        for pixel in queue.by_ref() {
            let (gx, gy) = (x0 + pixel % tw, y0 + pixel / tw);
            let r = self.rays.ray(gx as f64 + 0.5, gy as f64 + 0.5);
            if let Some(ray) = self.mip_ray(r.origin, r.dir) {
                lanes.start(l, pixel, ray, lattice_count(&ray));
                return;
            }
        }
        lanes.idle(l);
    }
}

/// The number of lattice points `t0 + i step <= t1` ([`mip::max_along`]'s lattice), at least 1
/// and at most `i32::MAX / 2`.
fn lattice_count(ray: &MipRay) -> i32 {
    let t = |i: i64| ray.t0 + ray.step * i as f64;
    let limit = i64::from(i32::MAX / 2);
    let mut n = (((ray.t1 - ray.t0) / ray.step).max(0.0).min(limit as f64) as i64) + 1;
    while n < limit && t(n) <= ray.t1 {
        n += 1;
    }
    while n > 1 && t(n - 1) > ray.t1 {
        n -= 1;
    }
    n as i32
}
