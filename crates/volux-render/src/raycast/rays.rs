//! The ray-by-ray loops of the grid ray caster: the medium along a ray, the integrators'
//! loops, isosurfaces, lighting and MIP, one ray at a time (the reference, and the paths the
//! lane streams do not take).
use glam::{DVec3, Vec3};
use volux_core::voi::clip_by_planes;
use volux_core::TransferFunction;

use super::clip::{ray_box, voxel_crossings};
use super::context::{
    first_at_or_after, pixel, pixel_hash, GridRay, MipRay, PixelOut, RayContext, RayShading,
};
use super::stream::TrapezoidRule;
use crate::classify::{Classified, LaneTable};
use crate::composite::{under_partial, RayAccumulator};
use crate::integrate::preintegrated::PreintegrationTable;
use crate::integrate::{
    adaptive_simpson_intervals, adaptive_simpson_pieces, fixed_intervals, hides_breakpoints,
    hides_breakpoints_along, riemann_step, AdaptiveParams, FixedRule, Integrator, Medium,
    RayIntegral, RayMedium,
};
use crate::isosurface::Crossing;
use crate::mip;
use crate::sampling::Field;
use crate::shading;
use crate::tiles::TILE;

/// A ray set up for sampling ([`RayContext::setup`]): its voxel-space origin and direction,
/// entry and exit distances, and the voxel unit of steps.
pub(super) type RaySetup = (DVec3, DVec3, f64, f64, f64);

impl<F: Field> RayMedium for GridRay<'_, F> {
    fn at(&mut self, t: f64) -> Medium {
        let p = self.o_v + self.d_v * t;
        // The f64 reconstruction for the reference; the table-classified integrators work to
        // tolerances far above f32 rounding (1e-7 of the data range).
        let v = match self.exact {
            Some(_) => self.field.sample64(p),
            None => self.field.sample(p.as_vec3()).map(f64::from),
        };
        let Some(v) = v else {
            return Medium::default();
        };
        let mut m = self.classify(v);
        let q = p.as_vec3();
        if let Some(rgb) = self
            .labels
            .and_then(|l| l.colour_at(q))
            .or_else(|| self.data_colour.map(|c| c.colour_at(q)))
        {
            m.rgb = rgb.map(f64::from);
        }
        if let (Some(sh), true) = (&self.shade, m.tau > 0.0) {
            let p = p.as_vec3();
            let mut g = match sh.gradients {
                Some(g) => g.gradient(p),
                None => shading::gradient(self.field, p, sh.spacing),
            };
            if let Some(cuts) = sh.cut_faces {
                g = cuts.lighting_gradient(p, g);
            }
            m.rgb = sh
                .model
                .shade(m.rgb.map(|c| c as f32), g, sh.view)
                .map(f64::from);
        }
        m
    }

    fn at4(&mut self, t: [f64; 4]) -> [Medium; 4] {
        if self.exact.is_some()
            || self.shade.is_some()
            || self.labels.is_some()
            || self.data_colour.is_some()
        {
            return t.map(|t| self.at(t));
        }
        let mut p = [[0.0f32; 4]; 3];
        for (k, &t) in t.iter().enumerate() {
            let q = self.o_v + self.d_v * t;
            (p[0][k], p[1][k], p[2][k]) = (q.x as f32, q.y as f32, q.z as f32);
        }
        let v = self.field.sample4(&p);
        let mut out = [Medium::default(); 4];
        for (o, &v) in out.iter_mut().zip(&v) {
            if !v.is_nan() {
                *o = self.classify(f64::from(v));
            }
        }
        out
    }

    fn hides_features(&self, a: f64, b: f64) -> bool {
        hides_breakpoints(self.breakpoints, a, b)
    }

    fn hides_features_along(&self, values: &[f64; 5]) -> bool {
        hides_breakpoints_along(self.breakpoints, values)
    }
}

impl<F: Field> GridRay<'_, F> {
    #[inline(always)]
    fn classify(&self, v: f64) -> Medium {
        match self.exact {
            Some(tf) => classify_exact(tf, v),
            None => {
                let c = self.table.lookup(v as f32);
                Medium {
                    rgb: c.rgb.map(f64::from),
                    tau: c.tau as f64,
                    value: v,
                }
            }
        }
    }
}

impl<F: Field> RayContext<'_, F> {
    /// Integrates one ray; `spans` is scratch space reused across the rays of a tile.
    fn cast(
        &self,
        origin: DVec3,
        dir: DVec3,
        jitter: f64,
        spans: &mut Vec<(f64, f64)>,
    ) -> PixelOut {
        let Some((o_v, d_v, t0, t1, unit)) = self.setup(origin, dir, spans) else {
            return PixelOut::default();
        };
        let spans = &spans[..];
        let integral = match self.opts.integrator {
            Integrator::Riemann { step } => {
                return self.riemann(o_v, d_v, (t0, t1), spans, step * unit, jitter)
            }
            Integrator::Trapezoid { step } => {
                self.fixed(o_v, d_v, (t0, t1), spans, step * unit, FixedRule::Trapezoid)
            }
            Integrator::Simpson { step } => {
                self.fixed(o_v, d_v, (t0, t1), spans, step * unit, FixedRule::Simpson)
            }
            Integrator::AdaptiveSimpson(p) => adaptive_simpson_intervals(
                &mut self.medium(o_v, d_v),
                spans,
                &self.adaptive_in_world(&p),
            ),
            Integrator::Preintegrated { step } => {
                return self.preintegrated(o_v, d_v, (t0, t1), spans, step * unit, jitter)
            }
            Integrator::Reference => self.reference(o_v, d_v, t0, t1, unit),
        };
        pixel(&integral)
    }

    /// A ray's voxel-space origin and direction, its entry and exit distances, the voxel unit
    /// of steps, and in `spans` the parts of it to sample; `None` if it misses the volume.
    pub(super) fn setup(
        &self,
        origin: DVec3,
        dir: DVec3,
        spans: &mut Vec<(f64, f64)>,
    ) -> Option<RaySetup> {
        self.setup_until(origin, dir, spans, f64::INFINITY)
            .map(|(ray, _)| ray)
    }

    /// [`RayContext::setup`] with the spans walked only until about `reach` voxels past the
    /// entry ([`IntervalSource::occupied_until`](crate::intervals::IntervalSource)), and where
    /// they stop (the exit distance when the whole ray was walked).
    pub(super) fn setup_until(
        &self,
        origin: DVec3,
        dir: DVec3,
        spans: &mut Vec<(f64, f64)>,
        reach: f64,
    ) -> Option<(RaySetup, f64)> {
        let place = &self.place;
        let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
        let (t0, t1) = clip_by_planes(&self.clip, origin, dir, (t0, t1))?;
        let unit = place.spacing.min_element();
        let o_v = (origin - place.origin) / place.spacing;
        let d_v = dir / place.spacing;
        spans.clear();
        let walked = match self.intervals {
            Some(occ) => occ.occupied_until(o_v, d_v, (t0, t1), t0 + reach * unit, spans),
            None => {
                spans.push((t0, t1));
                t1
            }
        };
        Some(((o_v, d_v, t0, t1, unit), walked))
    }

    /// The table-classified medium along a ray (voxel-space origin and direction).
    pub(super) fn medium(&self, o_v: DVec3, d_v: DVec3) -> GridRay<'_, F> {
        GridRay {
            field: self.field,
            o_v,
            d_v,
            table: self.table,
            exact: None,
            breakpoints: &self.breakpoints,
            labels: self.opts.labels.as_deref(),
            data_colour: self.opts.data_colour.as_deref(),
            shade: self.opts.shading.as_ref().map(|model| RayShading {
                model,
                gradients: self.gradients,
                cut_faces: self.cut_faces.as_ref(),
                spacing: self.place.spacing.as_vec3(),
                view: (d_v * self.place.spacing).normalize_or_zero().as_vec3(),
            }),
        }
    }

    /// The f64 ground truth: exact classification, pieces split at voxel boundaries.
    fn reference(&self, o_v: DVec3, d_v: DVec3, t0: f64, t1: f64, unit: f64) -> RayIntegral {
        let breaks = voxel_crossings(o_v, d_v, t0, t1);
        let p = Integrator::REFERENCE;
        let p = AdaptiveParams {
            h0: p.h0 * unit,
            hmin: p.hmin * unit,
            hmax: p.hmax * unit,
            ..p
        };
        let mut medium = GridRay {
            exact: Some(&self.tf),
            ..self.medium(o_v, d_v)
        };
        adaptive_simpson_pieces(&mut medium, &breaks, &p)
    }

    /// A fixed-step rule over the ray's occupied spans, stopping at the early-termination
    /// opacity.
    fn fixed(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        ends: (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        rule: FixedRule,
    ) -> RayIntegral {
        let stop_depth = match self.opts.early_termination {
            Some(a) if a < 1.0 => -(1.0 - f64::from(a)).ln(),
            _ => f64::INFINITY,
        };
        fixed_intervals(&mut self.medium(o_v, d_v), spans, ends, h, rule, stop_depth)
    }

    /// Adaptive parameters with the steps in world units and the render's early termination.
    pub(super) fn adaptive_in_world(&self, p: &AdaptiveParams) -> AdaptiveParams {
        let unit = self.place.spacing.min_element();
        AdaptiveParams {
            h0: p.h0 * unit,
            hmin: p.hmin * unit,
            hmax: p.hmax * unit,
            early_termination: self.opts.early_termination.map(f64::from),
            ..*p
        }
    }

    /// The tile at (`x0`, `y0`), one ray after the other.
    pub(super) fn tile_ray_by_ray(&self, x0: usize, y0: usize) -> Vec<PixelOut> {
        let (w, h) = (self.opts.width, self.opts.height);
        let mut px = Vec::with_capacity(TILE * TILE);
        let mut spans = Vec::new();
        for y in y0..(y0 + TILE).min(h) {
            for x in x0..(x0 + TILE).min(w) {
                let ray = self.rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                let jitter = if self.opts.jitter {
                    pixel_hash(x, y)
                } else {
                    0.0
                };
                px.push(if self.opts.mip {
                    self.mip(ray.origin, ray.dir)
                } else {
                    self.cast(ray.origin, ray.dir, jitter, &mut spans)
                });
            }
        }
        px
    }

    /// The step table when rays take the fast Riemann path: tiles are then rendered by the
    /// lane stream (`stream.rs`).
    pub(super) fn packet_table(&self) -> Option<&LaneTable> {
        match self.opts.integrator {
            Integrator::Riemann { .. } if self.streams() => self.lane_table.as_ref(),
            _ => None,
        }
    }

    /// The pre-integration table when rays take the lane stream.
    pub(super) fn preintegrated_stream_table(&self) -> Option<&PreintegrationTable> {
        match self.opts.integrator {
            Integrator::Preintegrated { .. } if self.streams() => self.preintegration,
            _ => None,
        }
    }

    /// The trapezoid rule when rays take the lane stream (emission only).
    pub(super) fn trapezoid_stream_rule(&self) -> Option<TrapezoidRule<'_>> {
        match self.opts.integrator {
            Integrator::Trapezoid { step } if self.streams() && self.opts.shading.is_none() => {
                Some(TrapezoidRule {
                    table: self.lane_table.as_ref()?,
                    h: (step * self.place.spacing.min_element()) as f32,
                })
            }
            _ => None,
        }
    }

    /// Whether fixed-step rays can take the lane stream: no isosurfaces, no MIP, and shading
    /// only with the cached gradient volume (on-the-fly gradients are taken ray by ray).
    fn streams(&self) -> bool {
        self.opts.isosurfaces.is_empty()
            && !self.opts.mip
            && (self.opts.shading.is_none() || self.gradients.is_some())
    }

    /// The left Riemann sum (eq. 2.14) of lit rays (shading or isosurfaces), one sample at a
    /// time with early ray termination; emission-only rays take the lane stream (`stream.rs`),
    /// which computes the same sums. Samples sit on the lattice `t0 + (i + jitter) h` whatever
    /// the skipped spans, so skipping empty space changes nothing in the image. Intervals
    /// that own the step past their end (a region of a split render) also composite the
    /// isosurfaces crossed between their last sample and the next lattice point.
    fn riemann(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        (t0, t1): (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        jitter: f64,
    ) -> PixelOut {
        let (o_v, d_v) = (o_v.as_vec3(), d_v.as_vec3());
        let stop = f64::from(self.opts.early_termination.unwrap_or(2.0));
        let view = (d_v * self.place.spacing.as_vec3()).normalize_or_zero();
        let mut acc = RayAccumulator::default();
        let mut n = 0u64;
        let mut prev: Option<(f64, f32)> = None;
        let mut crossings = Vec::new();
        let start = t0 + jitter * h;
        let mut past = t1;
        'spans: for &(a, b) in spans {
            let mut i = first_at_or_after(start, h, a) as u64;
            loop {
                let t = start + h * i as f64;
                if t >= b {
                    past = t;
                    break;
                }
                let p = o_v + d_v * t as f32;
                match self.field.sample(p) {
                    Some(v) => {
                        self.isosurfaces_between(
                            prev,
                            (t, v),
                            (o_v, d_v),
                            &mut crossings,
                            &mut acc,
                        );
                        let c = self.lit_sample(self.table.lookup(v), p, view);
                        riemann_step(&mut acc, c, h.min(t1 - t) as f32);
                        prev = Some((t, v));
                    }
                    None => prev = None,
                }
                n += 1;
                i += 1;
                if acc.alpha() >= stop {
                    break 'spans;
                }
            }
        }
        if past < t1 && self.intervals.is_some_and(|i| i.owns_step_past_end()) {
            n += self.isosurfaces_past(prev, past, (o_v, d_v), &mut crossings, &mut acc);
        }
        PixelOut::composited(&acc, n)
    }

    /// The isosurfaces crossed between the last sample `prev` and the lattice point `past`
    /// after it, when the intervals own that step (a region of a split render); the
    /// samples taken.
    fn isosurfaces_past(
        &self,
        prev: Option<(f64, f32)>,
        past: f64,
        ray: (Vec3, Vec3),
        crossings: &mut Vec<Crossing>,
        acc: &mut RayAccumulator,
    ) -> u64 {
        if prev.is_none() || self.opts.isosurfaces.is_empty() {
            return 0;
        }
        if let Some(v) = self.field.sample(ray.0 + ray.1 * past as f32) {
            self.isosurfaces_between(prev, (past, v), ray, crossings, acc);
        }
        1
    }

    /// A classified sample at voxel position `p` on a ray of world direction `view`, lit when
    /// shading is on and the sample is not transparent.
    pub(super) fn lit_sample(&self, mut c: Classified, p: Vec3, view: Vec3) -> Classified {
        if let Some(rgb) = self.voxel_colour(p) {
            c.rgb = rgb;
        }
        if let (Some(sh), true) = (&self.opts.shading, c.tau > 0.0) {
            c.rgb = sh.shade(c.rgb, self.lighting_gradient(p), view);
        }
        c
    }

    /// A pre-integrated segment's premultiplied RGBA `e`, its average colour lit with the
    /// gradient at its middle `mid` when shading is on.
    pub(super) fn lit_segment(&self, e: [f32; 4], mid: Vec3, view: Vec3) -> [f32; 4] {
        let label = self.voxel_colour(mid);
        let e = match label {
            Some(c) => [c[0] * e[3], c[1] * e[3], c[2] * e[3], e[3]],
            None => e,
        };
        match (&self.opts.shading, e[3] > 0.0) {
            (Some(model), true) => {
                let c = [e[0] / e[3], e[1] / e[3], e[2] / e[3]];
                let lit = model.shade(c, self.lighting_gradient(mid), view);
                [lit[0] * e[3], lit[1] * e[3], lit[2] * e[3], e[3]]
            }
            _ => e,
        }
    }

    /// The colour a voxel carries in place of the TF's at voxel position `p`: its region
    /// label's, else the RGB grid's own ([`crate::data_colour`]).
    fn voxel_colour(&self, p: Vec3) -> Option<[f32; 3]> {
        self.opts
            .labels
            .as_ref()
            .and_then(|l| l.colour_at(p))
            .or_else(|| self.opts.data_colour.as_ref().map(|c| c.colour_at(p)))
    }

    /// The gradient that lights a volume sample at voxel position `p`: the field's, or a
    /// cut's normal on the faces it exposes ([`CutFaces`](crate::shading::CutFaces)).
    fn lighting_gradient(&self, p: Vec3) -> Vec3 {
        let g = self.gradient(p);
        match &self.cut_faces {
            Some(cuts) => cuts.lighting_gradient(p, g),
            None => g,
        }
    }

    /// The world-space gradient at voxel position `p`.
    fn gradient(&self, p: Vec3) -> Vec3 {
        match self.gradients {
            Some(g) => g.gradient(p),
            None => shading::gradient(self.field, p, self.place.spacing.as_vec3()),
        }
    }

    /// Composites the isosurfaces crossed between the previous sample and `(t, v)`, lit when
    /// shading is on (`000`/`001`: surfaces located between samples by root refinement).
    fn isosurfaces_between(
        &self,
        prev: Option<(f64, f32)>,
        (t, v): (f64, f32),
        (o_v, d_v): (Vec3, Vec3),
        crossings: &mut Vec<Crossing>,
        acc: &mut RayAccumulator,
    ) {
        let (Some((tp, vp)), false) = (prev, self.opts.isosurfaces.is_empty()) else {
            return;
        };
        crossings.clear();
        let sample = |tt: f64| self.field.sample(o_v + d_v * tt as f32).unwrap_or(f32::NAN);
        let view = (d_v * self.place.spacing.as_vec3()).normalize_or_zero();
        self.opts
            .isosurfaces
            .crossings(tp, vp, t, v, sample, crossings);
        for c in crossings.iter() {
            let iso = self.opts.isosurfaces.as_slice()[c.iso_index];
            let mut rgb = [iso.rgba[0], iso.rgba[1], iso.rgba[2]];
            if let Some(sh) = self
                .opts
                .shading
                .as_ref()
                .or(self.opts.iso_lighting.as_ref())
            {
                rgb = sh.shade(rgb, self.gradient(o_v + d_v * c.t as f32), view);
            }
            acc.under(rgb, iso.rgba[3]);
        }
    }

    /// Maximum intensity projection along one ray: the TF colour of the largest value, opaque.
    fn mip(&self, origin: DVec3, dir: DVec3) -> PixelOut {
        let Some(ray) = self.mip_ray(origin, dir) else {
            return PixelOut::default();
        };
        let mut n = 0u64;
        let best = mip::max_along(ray.t0, ray.t1, ray.step, |t| {
            n += 1;
            self.field.sample64(ray.o_v + ray.d_v * t).map(|v| v as f32)
        });
        self.mip_pixel(best.map(|b| b.0), n)
    }

    /// A MIP ray's voxel-space origin and direction, extent and step; `None` if it misses.
    pub(super) fn mip_ray(&self, origin: DVec3, dir: DVec3) -> Option<MipRay> {
        let place = &self.place;
        let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
        let (t0, t1) = clip_by_planes(&self.clip, origin, dir, (t0, t1))?;
        let step = match self.opts.integrator {
            Integrator::Riemann { step } | Integrator::Preintegrated { step } => step,
            _ => 0.5,
        } * place.spacing.min_element();
        let (o_v, d_v) = ((origin - place.origin) / place.spacing, dir / place.spacing);
        Some(MipRay {
            o_v,
            d_v,
            t0,
            t1,
            step,
        })
    }

    /// The pixel of a MIP ray whose maximum is `best` (`None`: no defined sample), after
    /// `samples` samples.
    pub(super) fn mip_pixel(&self, best: Option<f32>, samples: u64) -> PixelOut {
        let rgba = best.map_or([0.0; 4], |v| {
            let c = self.tf.color_at(v as f64);
            [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
        });
        PixelOut {
            rgba,
            samples,
            hit: true,
            ..PixelOut::default()
        }
    }
}

impl<F: Field> RayContext<'_, F> {
    /// Pre-integrated classification: segments `[t_i, t_i + h]` on the same lattice as the
    /// Riemann sum, each composited with the table entry for its front and back values; a
    /// shortened last segment takes the fraction of the optical depth it covers. Segments
    /// entirely inside skipped (transparent) space are not visited.
    fn preintegrated(
        &self,
        o_v: DVec3,
        d_v: DVec3,
        (t0, t1): (f64, f64),
        spans: &[(f64, f64)],
        h: f64,
        jitter: f64,
    ) -> PixelOut {
        let Some(table) = self.preintegration else {
            return PixelOut::default();
        };
        let stop = f64::from(self.opts.early_termination.unwrap_or(2.0));
        let start = (t0 + jitter * h - h).max(t0 - h);
        let value = |t: f64| self.field.sample((o_v + d_v * t.clamp(t0, t1)).as_vec3());
        let mut acc = RayAccumulator::default();
        let (mut n, mut next) = (0u64, 0u64);
        'spans: for &(a, b) in spans {
            let mut i = (((a - start) / h).floor().max(0.0) as u64).max(next);
            let mut front = None;
            loop {
                let (ta, tb) = (
                    (start + h * i as f64).max(t0),
                    (start + h * (i + 1) as f64).min(t1),
                );
                if ta >= b || ta >= t1 {
                    break;
                }
                if tb <= ta {
                    // Rounding put the lattice point before `t0` on it: nothing to integrate.
                    i += 1;
                    continue;
                }
                let f = match front {
                    Some(f) => f,
                    None => {
                        n += 1;
                        value(ta)
                    }
                };
                let back = value(tb);
                n += 1;
                if let (Some(sf), Some(sb)) = (f, back) {
                    let mid = (o_v + d_v * (0.5 * (ta + tb))).as_vec3();
                    let view = (d_v * self.place.spacing).normalize_or_zero().as_vec3();
                    let e = self.lit_segment(table.lookup(sf, sb), mid, view);
                    under_partial(&mut acc, e, ((tb - ta) / h) as f32);
                }
                front = Some(back);
                i += 1;
                next = i;
                if acc.alpha() >= stop {
                    break 'spans;
                }
            }
        }
        PixelOut::composited(&acc, n)
    }
}

/// The reference's classification: the TF evaluated exactly, in f64.
#[inline(never)]
fn classify_exact(tf: &TransferFunction, v: f64) -> Medium {
    Medium {
        rgb: tf.color_at(v),
        tau: tf.tau_per_world(v),
        value: v,
    }
}
