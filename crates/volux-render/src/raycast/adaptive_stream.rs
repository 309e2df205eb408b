//! Adaptive Simpson with coupled control (`001_...txt` Algorithm 3) over the rays of a tile,
//! [`RAYS`] rays at a time: each round asks every ray for the samples of its next step (the
//! up to four points its probe lacks, or the first point of its next interval) and takes them
//! all in one call of the [`LANES`]-lane sampler, then lets each ray judge its step.
//!
//! One ray's steps form a serial chain (sample, estimate the error, accept or halve), so a ray
//! alone keeps the processor waiting; several rays' samples taken together fill the lanes. The
//! step control itself is [`CoupledRay`], the integrator's own: images are the ones
//! [`adaptive_simpson_intervals`](crate::integrate::adaptive_simpson_intervals) gives ray by
//! ray.
use super::stream::block_order;
use super::{pixel, GridRay, PixelOut, RayContext, TILE};
use crate::integrate::{AdaptiveParams, CoupledRay, Integrator, Medium, StepControl};
use crate::sampling::{Field, LANES};

/// Rays advanced together: each may ask for up to four samples per round.
const RAYS: usize = LANES / 4;

/// One ray of the round.
struct Slot<'a, F> {
    ray: CoupledRay,
    medium: GridRay<'a, F>,
    spans: Vec<(f64, f64)>,
    /// Index of the ray's pixel in its tile.
    pixel: usize,
    /// The distances to sample this round, and how many.
    ts: [f64; 4],
    wants: usize,
}

impl<F: Field> RayContext<'_, F> {
    /// The adaptive parameters in world units when tiles take the batched path: coupled
    /// control, table classification, no shading (its gradients are taken per sample).
    pub(super) fn adaptive_stream_params(&self) -> Option<AdaptiveParams> {
        let Integrator::AdaptiveSimpson(p) = self.opts.integrator else {
            return None;
        };
        if p.control != StepControl::Coupled || self.opts.shading.is_some() || self.opts.mip {
            return None;
        }
        Some(self.adaptive_in_world(&p))
    }

    /// Renders the tile at (`x0`, `y0`) with adaptive Simpson, [`RAYS`] rays at a time.
    pub(super) fn adaptive_stream(
        &self,
        p: &AdaptiveParams,
        x0: usize,
        y0: usize,
    ) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let (tw, th) = ((x0 + TILE).min(w) - x0, (y0 + TILE).min(h) - y0);
        let mut px = vec![PixelOut::default(); tw * th];
        let mut queue = block_order(tw, th).into_iter();
        let mut next = |spans| self.next_adaptive_ray(p, &mut queue, (x0, y0, tw), spans);
        let mut slots: Vec<Slot<'_, F>> = (0..RAYS).map_while(|_| next(Vec::new())).collect();
        while !slots.is_empty() {
            let mut pos = [[0.0f32; LANES]; 3];
            let mut k = 0;
            while k < slots.len() {
                let s = &mut slots[k];
                s.wants = s.ray.wants(&s.spans, &mut s.ts);
                if s.wants == 0 {
                    px[s.pixel] = pixel(&s.ray.result());
                    match next(std::mem::take(&mut s.spans)) {
                        Some(fresh) => slots[k] = fresh,
                        None => {
                            slots.swap_remove(k);
                        }
                    }
                    continue;
                }
                for (j, &t) in s.ts[..s.wants].iter().enumerate() {
                    let q = s.medium.o_v + s.medium.d_v * t;
                    for a in 0..3 {
                        pos[a][4 * k + j] = q[a] as f32;
                    }
                }
                k += 1;
            }
            let v = self.field.sample_lanes(&pos);
            for (k, s) in slots.iter_mut().enumerate() {
                let mut media = [Medium::default(); 4];
                for (j, m) in media[..s.wants].iter_mut().enumerate() {
                    let x = v[4 * k + j];
                    if !x.is_nan() {
                        *m = s.medium.classify(f64::from(x));
                    }
                }
                s.ray.supply(&s.medium, &media[..s.wants]);
            }
        }
        px
    }

    /// The next ray of the tile that hits the volume (rays that miss keep their default
    /// pixel), ready to integrate; `spans` is a finished ray's, reused.
    fn next_adaptive_ray(
        &self,
        p: &AdaptiveParams,
        queue: &mut impl Iterator<Item = usize>,
        (x0, y0, tw): (usize, usize, usize),
        mut spans: Vec<(f64, f64)>,
    ) -> Option<Slot<'_, F>> {
        for pixel in queue.by_ref() {
            let (gx, gy) = (x0 + pixel % tw, y0 + pixel / tw);
            let ray = self.rays.ray(gx as f64 + 0.5, gy as f64 + 0.5);
            if let Some((o_v, d_v, ..)) = self.setup(ray.origin, ray.dir, &mut spans) {
                return Some(Slot {
                    ray: CoupledRay::new(&spans, p),
                    medium: self.medium(o_v, d_v),
                    spans,
                    pixel,
                    ts: [0.0; 4],
                    wants: 0,
                });
            }
        }
        None
    }
}
