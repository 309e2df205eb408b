//! Adaptive Simpson with coupled control (`001_...txt` Algorithm 3) over the rays of a tile,
//! [`RAYS`] rays at a time, in f32 lanes ([`AdaptiveLanes`]): each round samples the four
//! new points of every ray's step in one call of the [`LANES`]-lane sampler, classifies them
//! lane-wise, and lets the integrator judge all the steps together.
//!
//! One ray's steps form a serial chain (sample, estimate the error, accept or halve), so a ray
//! alone keeps the processor waiting; several rays' steps taken together fill the lanes, and
//! their rules, error estimates and `exp` run lane-wise. Rays enter the slots in 4 x 4 pixel
//! blocks, so that a round's points lie close together in the volume. Shaded renders light
//! each round's colours lane-wise with the cached gradient volume, as the stream does.
use glam::{DVec3, Vec3};

use super::context::{pixel, PixelOut, RayContext};
use super::stream::{block_order, StreamShading};
use crate::classify::{BreakpointRanks, LaneTable};
use crate::integrate::adaptive::lanes::{AdaptiveLanes, LaneMedia, RAYS};
use crate::integrate::{AdaptiveParams, Integrator};
use crate::sampling::{Field, LANES};
use crate::shading::Lanes3;
use crate::tiles::TILE;

/// The ray in one slot: its pixel, the intervals to integrate and the next one to enter.
#[derive(Default)]
struct Slot {
    pixel: usize,
    spans: Vec<(f64, f64)>,
    next: usize,
}

mod resume;

// A round's points fill one call of the sampler.
const _: () = assert!(crate::integrate::adaptive::lanes::LANES == LANES);

/// What the lane path needs beyond the ray context.
pub(super) struct LanePath<'a> {
    params: AdaptiveParams,
    table: &'a LaneTable,
    ranks: &'a BreakpointRanks,
    shading: Option<StreamShading<'a>>,
}

/// The tile's rays in flight: slots and their voxel-space origins and directions, lane-wise,
/// and the lighting directions of each lane's ray (towards the eye, the light, their half
/// vector) with whether it is lit.
struct Flight {
    lanes: AdaptiveLanes,
    slots: [Option<Slot>; RAYS],
    origin: [[f32; RAYS]; 3],
    dir: [[f32; RAYS]; 3],
    to_eye: Lanes3,
    light: Lanes3,
    half: Lanes3,
    lit: [bool; LANES],
}

impl<F: Field> RayContext<'_, F> {
    /// The adaptive parameters in world units and the classification tables when tiles take
    /// the lane path: coupled control, shading only with the cached gradient volume, no MIP,
    /// and a tolerance the f32 lanes resolve.
    pub(super) fn adaptive_stream_params(&self) -> Option<LanePath<'_>> {
        let Integrator::AdaptiveSimpson(p) = self.opts.integrator else {
            return None;
        };
        let lane_path = p.control.is_coupled()
            && p.tol >= AdaptiveLanes::MIN_TOL
            && (self.opts.shading.is_none() || self.gradients.is_some())
            && !self.opts.mip;
        Some(LanePath {
            params: self.adaptive_in_world(&p),
            table: self.lane_table.as_ref().filter(|_| lane_path)?,
            ranks: self.breakpoint_ranks.as_ref()?,
            shading: self.stream_shading(),
        })
    }

    /// Renders the tile at (`x0`, `y0`) with adaptive Simpson, [`RAYS`] rays at a time.
    pub(super) fn adaptive_stream(
        &self,
        path: LanePath<'_>,
        x0: usize,
        y0: usize,
    ) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let (tw, th) = ((x0 + TILE).min(w) - x0, (y0 + TILE).min(h) - y0);
        let mut px = vec![PixelOut::default(); tw * th];
        let mut queue = block_order(tw, th).into_iter();
        let mut f = Flight::new(&path);
        for r in 0..RAYS {
            self.load_ray(&mut f, r, Vec::new(), &mut queue, (x0, y0, tw));
            self.advance(&mut f, r, &mut px, &mut queue, (x0, y0, tw));
        }
        while f.lanes.is_busy() {
            self.round(&mut f, &path);
            for r in 0..RAYS {
                self.advance(&mut f, r, &mut px, &mut queue, (x0, y0, tw));
            }
        }
        px
    }

    /// Samples, classifies and judges one round of the rays in flight.
    fn round(&self, f: &mut Flight, path: &LanePath<'_>) {
        let media = match path.shading {
            Some(sh) => self.round_media::<true>(f, path, Some(sh)),
            None => self.round_media::<false>(f, path, None),
        };
        f.lanes.supply(&media);
    }

    /// Samples and classifies the points of this round.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn round_media<const LIT: bool>(
        &self,
        f: &Flight,
        path: &LanePath<'_>,
        shading: Option<StreamShading<'_>>,
    ) -> LaneMedia {
        let t = f.lanes.distances();
        let mut pos = [[0.0f32; LANES]; 3];
        for a in 0..3 {
            for l in 0..LANES {
                pos[a][l] = f.origin[a][l % RAYS] + f.dir[a][l % RAYS] * t[l];
            }
        }
        let v = self.field.sample_lanes(&pos);
        let mut m = LaneMedia::default();
        // The lighting (factor, highlight) per lane; the emission-only path has none.
        let (k, s) = match shading {
            Some(sh) if LIT => {
                let mut g = sh.gradients.gradient_lanes(&pos);
                if let Some(cuts) = sh.cut_faces {
                    cuts.lighting_gradient_lanes(&pos, &mut g, u32::MAX);
                }
                sh.model
                    .light_lanes(&g, (&f.to_eye, &f.light, &f.half), &f.lit)
            }
            _ => ([1.0; LANES], [0.0; LANES]),
        };
        for l in 0..LANES {
            let (i, frac) = path.table.position(v[l]);
            let e = path.table.at(i, frac);
            let ranks = path.ranks.at(i);
            // An undefined (NaN) sample is empty, of value 0.
            let defined = !v[l].is_nan();
            // Lit colours where shading is on (only lit where extinction is not zero, as ray
            // by ray; elsewhere the colour is multiplied by 0).
            for c in 0..3 {
                let lit = if LIT { e[c] * k[l] + s[l] } else { e[c] };
                m.rgb[c][l] = if defined { lit } else { 0.0 };
            }
            m.tau[l] = if defined { e[3] } else { 0.0 };
            m.value[l] = if defined { v[l] } else { 0.0 };
            // No peak is looked for next to an undefined sample (the medium there is empty):
            // counts that never meet the test.
            m.breakpoints_at_or_below[l] = if defined { ranks[0] } else { 1e9 };
            m.breakpoints_below[l] = if defined { ranks[1] } else { -1e9 };
        }
        m
    }

    /// Enters slot `r`'s next interval while its ray needs one; a finished ray writes its
    /// pixel and the slot takes the tile's next ray.
    fn advance(
        &self,
        f: &mut Flight,
        r: usize,
        px: &mut [PixelOut],
        queue: &mut impl Iterator<Item = usize>,
        tile: (usize, usize, usize),
    ) {
        while f.lanes.needs_span(r) {
            let Some(slot) = f.slots[r].as_mut() else {
                f.lanes.idle(r);
                return;
            };
            let span = slot.spans.get(slot.next).copied();
            slot.next += 1;
            match span {
                Some(s) if !f.lanes.is_opaque(r) => {
                    f.lanes.enter(r, s);
                }
                _ => {
                    px[slot.pixel] = pixel(&f.lanes.result(r));
                    let spans = std::mem::take(&mut slot.spans);
                    self.load_ray(f, r, spans, queue, tile);
                }
            }
        }
    }

    /// Loads the tile's next ray that hits the volume into slot `r` (rays that miss keep their
    /// default pixel), or empties the slot; `spans` is a finished ray's, reused.
    fn load_ray(
        &self,
        f: &mut Flight,
        r: usize,
        mut spans: Vec<(f64, f64)>,
        queue: &mut impl Iterator<Item = usize>,
        (x0, y0, tw): (usize, usize, usize),
    ) {
        for pixel in queue.by_ref() {
            let (gx, gy) = (x0 + pixel % tw, y0 + pixel / tw);
            let ray = self.rays.ray(gx as f64 + 0.5, gy as f64 + 0.5);
            if let Some((o_v, d_v, ..)) = self.setup(ray.origin, ray.dir, &mut spans) {
                self.aim(f, r, o_v, d_v);
                f.lanes
                    .start(r, spans.iter().map(|(a, b)| (b - a).max(0.0)).sum());
                f.slots[r] = Some(Slot {
                    pixel,
                    spans,
                    next: 0,
                });
                return;
            }
        }
        f.slots[r] = None;
        f.lanes.idle(r);
    }

    /// Slot `r`'s ray becomes the voxel-space ray `o_v + t d_v`, with its lighting.
    fn aim(&self, f: &mut Flight, r: usize, o_v: DVec3, d_v: DVec3) {
        let (o, d): (Vec3, Vec3) = (o_v.as_vec3(), d_v.as_vec3());
        for a in 0..3 {
            (f.origin[a][r], f.dir[a][r]) = (o[a], d[a]);
        }
        if let Some(sh) = self.stream_shading() {
            let view = (d_v * self.place.spacing).normalize_or_zero().as_vec3();
            let ray = sh.model.ray_light(view);
            let dirs = ray.unwrap_or_default();
            // The ray's lanes: its point k is lane (k - 1) RAYS + r.
            for l in (r..LANES).step_by(RAYS) {
                for a in 0..3 {
                    f.to_eye[a][l] = dirs.to_eye[a];
                    f.light[a][l] = dirs.light[a];
                    f.half[a][l] = dirs.half[a];
                }
                f.lit[l] = ray.is_some();
            }
        }
    }
}

impl Flight {
    fn new(path: &LanePath<'_>) -> Self {
        Self {
            lanes: AdaptiveLanes::new(&path.params),
            slots: Default::default(),
            origin: [[0.0; RAYS]; 3],
            dir: [[0.0; RAYS]; 3],
            to_eye: [[0.0; LANES]; 3],
            light: [[0.0; LANES]; 3],
            half: [[0.0; LANES]; 3],
            lit: [false; LANES],
        }
    }
}
