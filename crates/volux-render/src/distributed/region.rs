//! One rank's part of a distributed render: rays sampled only inside the rank's region
//! ([`RegionRays`], an [`IntervalSource`] on the global sample lattice), rendered into a
//! partial image of premultiplied RGBA before any background, or under MIP into the
//! region's maxima ([`render_region`]).
use glam::{DVec3, Vec3};

use super::error::DistributedError;
use super::kdtree::KdSplit;
use super::mip::{mip_region, mip_step};
use super::part::Part;
use crate::integrate::integrator::Integrator;
use crate::intervals::IntervalSource;
use crate::raycast::{first_at_or_after, render_field_in, Placement, RenderOptions};
use crate::sampling::{Field, LANES};

/// How the integrator takes the ray apart, which says where a region's span must start so
/// that neighbouring regions share nothing and lose nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpanRule {
    /// Point samples `t_i = t0 + i h` taken where `a <= t_i < b` (Riemann, adaptive Simpson):
    /// the region's interval as it is.
    Samples,
    /// Steps `[t_i, t_i + h]` of length `h` (world units) owned by the region holding their
    /// start `t_i` (trapezoid, Simpson, pre-integration): a region entered at `a > t0` starts
    /// its span a quarter step after the first lattice point at or after `a`, where every
    /// path (floor of the step index, or the first segment ending after the start) begins
    /// with that point's step; the step straddling the region's far face is its own (its end
    /// sample is read from the neighbour's chunks).
    Steps {
        /// The step, world units.
        h: f64,
    },
}

impl SpanRule {
    /// The rule of `opts`' integrator on `place`; an error for those a split render cannot
    /// honour (the reference path integrates the whole ray whatever the intervals).
    pub fn of(opts: &RenderOptions, place: &Placement) -> Result<Self, DistributedError> {
        let unit = place.spacing.min_element();
        Ok(match opts.integrator {
            Integrator::Riemann { .. } | Integrator::AdaptiveSimpson(_) => SpanRule::Samples,
            Integrator::Trapezoid { step }
            | Integrator::Simpson { step }
            | Integrator::Preintegrated { step } => SpanRule::Steps { h: step * unit },
            Integrator::Reference => {
                return Err(DistributedError::Unsupported(
                    "the reference integrator (it integrates each ray whole); use adaptive-simpson"
                        .into(),
                ))
            }
        })
    }
}

/// The part of every ray inside one region of a [`KdSplit`], as the ray caster's interval
/// seam: one span per ray (regions are convex), adjusted by the [`SpanRule`].
pub struct RegionRays<'a> {
    /// The split.
    pub split: &'a KdSplit,
    /// The region rendered.
    pub region: usize,
    /// How the integrator consumes spans.
    pub rule: SpanRule,
}

impl IntervalSource for RegionRays<'_> {
    fn occupied(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, out: &mut Vec<(f64, f64)>) {
        out.clear();
        let Some((a, b)) = self.split.clip_ray(self.region, o, d, t0, t1) else {
            return;
        };
        match self.rule {
            SpanRule::Steps { h } if a > t0 => {
                let k = first_at_or_after(t0, h, a);
                let tk = t0 + h * f64::from(k);
                if tk < b {
                    // May lie past `b`: the span then holds just the step starting at `t_k`.
                    out.push((tk + 0.25 * h, b));
                }
            }
            _ => out.push((a, b)),
        }
    }

    /// The region owns the step from its last sample on a ray to the next lattice point,
    /// across its far face (read from the neighbour's chunks, within `reach`): the
    /// isosurfaces crossed in that step are found and refined here, once, and the next
    /// region starts without a previous sample.
    fn owns_step_past_end(&self) -> bool {
        true
    }

    /// Reported as all empty, so that the ray caster always walks these intervals.
    fn empty_fraction(&self) -> f64 {
        1.0
    }
}

/// Whether `opts` render through the state pipeline
/// ([`render_pipelined`](super::pipeline::render_pipelined)): adaptive Simpson, not under
/// MIP.
pub fn is_pipelined(opts: &RenderOptions) -> bool {
    matches!(opts.integrator, Integrator::AdaptiveSimpson(_)) && !opts.mip
}

/// Checks that `opts` can be rendered split, and returns them with early termination off,
/// except for adaptive Simpson (not under MIP), whose rays pass their states, opacity
/// included, from region to region ([`pipeline`](super::pipeline)). Refused: jitter,
/// sculpt masks and labels (and, by [`SpanRule::of`], the reference integrator).
pub fn region_options(opts: &RenderOptions) -> Result<RenderOptions, DistributedError> {
    let refuse = |what: &str| Err(DistributedError::Unsupported(what.into()));
    if opts.jitter {
        return refuse("jitter (the lattice of a ray would differ per region)");
    }
    if opts.mask.is_some() || opts.labels.is_some() {
        return refuse("sculpt masks or labels (voxel layers of in-core grids)");
    }
    let mut o = opts.clone();
    if is_pipelined(opts) {
        return Ok(o);
    }
    o.early_termination = None;
    if let Integrator::AdaptiveSimpson(p) = &mut o.integrator {
        p.early_termination = None;
    }
    Ok(o)
}

/// Renders region `region` of `split` of `field` (placed by `place`, classified over
/// `range`): every ray sampled only inside the region on the global lattice, early
/// termination off ([`region_options`]). The part is a partial image of premultiplied RGBA
/// with no background (the ray caster applies none: front ends add it when writing), ready
/// for [`composite`](super::swap::composite), or under MIP the region's maxima
/// ([`mip_region`]); [`Part::combine`] combines either. Riemann, trapezoid, Simpson,
/// pre-integration and MIP give exactly the single-process render's samples, and so do
/// isosurfaces (a crossing in the step from a region's last sample to the next region's
/// first is found by the front region, [`IntervalSource::owns_step_past_end`], refined
/// between the same two samples as in one process, and composited last in its part).
/// Adaptive Simpson (not under MIP) is refused here: its steps depend on the whole ray so
/// far, and it renders exactly through the state pipeline instead
/// ([`render_pipelined`](super::pipeline::render_pipelined)); so is the reference
/// integrator.
pub fn render_region<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    split: &KdSplit,
    region: usize,
    opts: &RenderOptions,
) -> Result<Part, DistributedError> {
    let opts = region_options(opts)?;
    if region >= split.len() {
        return Err(DistributedError::Unsupported(format!(
            "region {region} of a split into {}",
            split.len()
        )));
    }
    if opts.mip {
        let part = match Near::new(field, split, region, reach(&opts, &place)) {
            Some(near) => mip_region(&near, place, split, region, &opts),
            None => mip_region(field, place, split, region, &opts),
        };
        return Ok(Part::Mip(part, opts.tf.resolved(range)));
    }
    if is_pipelined(&opts) {
        return Err(DistributedError::Unsupported(
            "adaptive Simpson region by region (it renders through the state pipeline, render_pipelined)".into(),
        ));
    }
    let rule = SpanRule::of(&opts, &place)?;
    let rays = RegionRays {
        split,
        region,
        rule,
    };
    let rendered = match Near::new(field, split, region, reach(&opts, &place)) {
        Some(near) => render_field_in(&near, place, range, Some(&rays), &opts)?,
        None => render_field_in(field, place, range, Some(&rays), &opts)?,
    };
    Ok(Part::Over(rendered.image))
}

/// How far past a region face (voxels, per axis) a sample the region needs can lie: a step
/// (or the largest adaptive step, or the MIP step to the maximum's neighbour) straddling
/// the face, and a voxel for gradients.
pub(super) fn reach(opts: &RenderOptions, place: &Placement) -> [f64; 3] {
    let unit = place.spacing.min_element();
    let h = match opts.integrator {
        _ if opts.mip => mip_step(&opts.integrator),
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Simpson { step }
        | Integrator::Preintegrated { step } => step,
        Integrator::AdaptiveSimpson(p) => p.hmax,
        Integrator::Reference => f64::INFINITY,
    } * unit;
    std::array::from_fn(|a| h / place.spacing[a] + 1.0)
}

/// The field as a region sees it: undefined farther than the chunks next to the region's
/// faces, so that a rank never reads another chunk. No sample a region's rays need lies
/// there ([`reach`] is within a chunk); what does is what the lane streams' idle lanes
/// sample while they wait (their results unused), which would otherwise read chunks on the
/// volume's surface anywhere along their last ray.
pub(super) struct Near<'a, F> {
    inner: &'a F,
    /// Per axis, the allowed coordinates `[lo, hi)` (clamped as the samplers clamp).
    lo: [f32; 3],
    hi: [f32; 3],
    top: [f32; 3],
}

impl<'a, F: Field> Near<'a, F> {
    /// `None` (no filter) when a sample could reach beyond the neighbouring chunks.
    pub(super) fn new(
        inner: &'a F,
        split: &KdSplit,
        region: usize,
        reach: [f64; 3],
    ) -> Option<Self> {
        let b = split.regions().get(region)?;
        let (chunk, n) = (split.chunk_shape(), split.chunks_per_axis());
        if (0..3).any(|a| reach[a] + 1.0 >= chunk[a] as f64) {
            return None;
        }
        let dims = inner.dims();
        Some(Self {
            inner,
            lo: std::array::from_fn(|a| match b.lo[a] {
                0 => f32::NEG_INFINITY,
                c => ((c - 1) * chunk[a]) as f32,
            }),
            // The cell at `x` reads `floor(x) + 1`: below the chunk after the next.
            hi: std::array::from_fn(|a| {
                if b.hi[a] >= n[a] {
                    f32::INFINITY
                } else {
                    ((b.hi[a] + 1) * chunk[a] - 1) as f32
                }
            }),
            top: dims.map(|d| d.saturating_sub(1) as f32),
        })
    }

    /// `sample` of `p` with the lanes that are not near moved onto a near one, then NaN.
    #[inline]
    fn lanes<const N: usize>(
        &self,
        p: &[[f32; N]; 3],
        sample: impl FnOnce(&[[f32; N]; 3]) -> [f32; N],
    ) -> [f32; N] {
        let near: [bool; N] =
            std::array::from_fn(|l| self.near(Vec3::new(p[0][l], p[1][l], p[2][l])));
        let Some(at) = near.iter().position(|&n| n) else {
            return [f32::NAN; N];
        };
        let q: [[f32; N]; 3] = std::array::from_fn(|a| {
            std::array::from_fn(|l| if near[l] { p[a][l] } else { p[a][at] })
        });
        let mut v = sample(&q);
        for (v, near) in v.iter_mut().zip(near) {
            if !near {
                *v = f32::NAN;
            }
        }
        v
    }

    #[inline]
    fn near(&self, p: Vec3) -> bool {
        (0..3).all(|a| {
            let x = p[a].max(0.0).min(self.top[a]);
            self.lo[a] <= x && x < self.hi[a]
        })
    }
}

impl<F: Field> Field for Near<'_, F> {
    fn dims(&self) -> [usize; 3] {
        self.inner.dims()
    }

    #[inline]
    fn sample(&self, p: Vec3) -> Option<f32> {
        if self.near(p) {
            self.inner.sample(p)
        } else {
            None
        }
    }

    /// The inner field's lanes, those too far moved onto a near lane first (so that they
    /// read nothing more) and then made undefined.
    #[inline]
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        self.lanes(p, |q| self.inner.sample_lanes(q))
    }

    #[inline]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        self.lanes(p, |q| self.inner.sample4(q))
    }

    fn sample64(&self, p: DVec3) -> Option<f64> {
        if self.near(p.as_vec3()) {
            self.inner.sample64(p)
        } else {
            None
        }
    }
}
