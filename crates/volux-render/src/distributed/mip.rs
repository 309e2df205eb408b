//! Maximum intensity projection split by region, exactly: the single-process MIP
//! (`raycast/mip_stream.rs`, [`refine_peak`]) shows the TF colour of one value per
//! ray, the largest sample of its lattice `t0 + i step <= t1` (the first of equal maxima)
//! refined between that sample and its two neighbours. A maximum of refined values would
//! not do (a smaller lattice peak can refine above the largest one), so each rank keeps,
//! per pixel, the largest lattice sample of the part of the ray in its region, its lattice
//! index, and that sample refined with its neighbours (read across the region's faces,
//! within [`Near`](super::region)'s reach) ([`mip_region`]); the ranks reduce by the
//! largest sample, the smaller index on ties ([`MipPart::merge`], order-independent), and
//! rank 0 colours the winner's refined value ([`MipPart::image`]). Samples are taken at the
//! single-process render's f32 lattice positions, so the image is the same.
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::voi::clip_by_planes;
use volux_core::{Image, TransferFunction};

use super::error::DistributedError;
use super::kdtree::KdSplit;
use crate::integrate::integrator::Integrator;
use crate::mip::refine_peak;
use crate::raycast::{first_at_or_after, local_clip_planes, ray_box, Placement, RenderOptions};
use crate::sampling::{Field, LANES};

/// Values per pixel of a [`MipPart`]: the largest lattice sample (NaN: none), its lattice
/// index (exact in f32 below 2^24 samples per ray), the refined maximum.
pub const MIP_CHANNELS: usize = 3;

/// One rank's MIP of its region, or the reduction of several.
#[derive(Clone, Debug, PartialEq)]
pub struct MipPart {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// [`MIP_CHANNELS`] values per pixel, row by row.
    pub values: Vec<f32>,
}

impl MipPart {
    /// Keeps in `mine`, pixel by pixel, the record of `mine` or `other` with the larger
    /// lattice maximum (the smaller lattice index on ties: the first of equal maxima along
    /// the ray, as one process finds it). Slices of [`MIP_CHANNELS`] values per pixel.
    pub fn merge(mine: &mut [f32], other: &[f32]) {
        let pixels = mine
            .chunks_exact_mut(MIP_CHANNELS)
            .zip(other.chunks_exact(MIP_CHANNELS));
        for (m, o) in pixels {
            let wins =
                !o[0].is_nan() && (m[0].is_nan() || o[0] > m[0] || (o[0] == m[0] && o[1] < m[1]));
            if wins {
                m.copy_from_slice(o);
            }
        }
    }

    /// The picture: the colour of `tf` (resolved against the data range) at each pixel's
    /// refined maximum, opaque; transparent black where no sample was defined.
    pub fn image(&self, tf: &TransferFunction) -> Result<Image, DistributedError> {
        let pixels = self
            .values
            .chunks_exact(MIP_CHANNELS)
            .map(|v| {
                if v[0].is_nan() {
                    return [0.0; 4];
                }
                let c = tf.color_at(f64::from(v[2]));
                [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]
            })
            .collect();
        Image::from_pixels(self.width, self.height, pixels)
            .map_err(|e| DistributedError::Exchange(format!("the MIP image: {e}")))
    }
}

/// The step of the MIP lattice in voxel units, as the single-process MIP takes it: the
/// Riemann or pre-integration step, else half a voxel.
pub fn mip_step(integrator: &Integrator) -> f64 {
    match *integrator {
        Integrator::Riemann { step } | Integrator::Preintegrated { step } => step,
        _ => 0.5,
    }
}

/// Region `region` of `split`'s part of the MIP of `field` placed by `place`: per pixel
/// (row by row), the largest sample of the lattice points in the region, its index and its
/// refined value ([`MIP_CHANNELS`]); NaN where the ray meets no defined sample there.
/// `field` must give the samples one lattice step (and a voxel) past the region's faces.
pub fn mip_region<F: Field>(
    field: &F,
    place: Placement,
    split: &KdSplit,
    region: usize,
    opts: &RenderOptions,
) -> MipPart {
    let (w, h) = (opts.width, opts.height);
    let view = MipView {
        rays: opts.camera.rays(w, h),
        place,
        clip: local_clip_planes(&place, &opts.clip_planes),
        step: mip_step(&opts.integrator) * place.spacing.min_element(),
    };
    let mut values = vec![f32::NAN; MIP_CHANNELS * w * h];
    values
        .par_chunks_mut(MIP_CHANNELS * w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            if cancelled(opts) {
                return;
            }
            for (x, px) in row.chunks_exact_mut(MIP_CHANNELS).enumerate() {
                if let Some(v) = view.pixel(field, split, region, x, y) {
                    px.copy_from_slice(&v);
                }
            }
        });
    MipPart {
        width: w,
        height: h,
        values,
    }
}

fn cancelled(opts: &RenderOptions) -> bool {
    opts.control
        .cancel
        .as_ref()
        .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
}

/// What every ray of a split MIP shares.
struct MipView {
    rays: volux_core::camera::RayGenerator,
    place: Placement,
    clip: Vec<volux_core::voi::ClipPlane>,
    /// World units.
    step: f64,
}

impl MipView {
    /// Pixel (`x`, `y`)'s part in `region`: (largest sample, its index, refined), or `None`.
    fn pixel<F: Field>(
        &self,
        field: &F,
        split: &KdSplit,
        region: usize,
        x: usize,
        y: usize,
    ) -> Option<[f32; MIP_CHANNELS]> {
        let place = &self.place;
        let r = self.rays.ray(x as f64 + 0.5, y as f64 + 0.5);
        let (origin, dir) = (place.point_to_local(r.origin), place.vector_to_local(r.dir));
        let (t0, t1) = ray_box(origin, dir, place.origin, place.origin + place.extent())?;
        let (t0, t1) = clip_by_planes(&self.clip, origin, dir, (t0, t1))?;
        let (o_v, d_v) = ((origin - place.origin) / place.spacing, dir / place.spacing);
        let (a, b) = split.clip_ray(region, o_v, d_v, t0, t1)?;
        let n = lattice_count(t0, t1, self.step);
        let lo = first_at_or_after(t0, self.step, a).min(n);
        // The last region holds the sample at `t1` itself (the lattice ends at `t <= t1`).
        let hi = if b >= t1 {
            n
        } else {
            first_at_or_after(t0, self.step, b).min(n)
        };
        if lo >= hi {
            return None;
        }
        let ray = LatticeRay::new(o_v, d_v, t0, self.step);
        // Samples lo - 1 ..= hi (the neighbours of the region's first and last), within
        // the lattice.
        let first = (lo - 1).max(0);
        let last = (hi + 1).min(n);
        let v = ray.samples(field, first, last);
        let at = |i: i32| v[(i - first) as usize];
        let mut best: Option<(f32, i32)> = None;
        for i in lo..hi {
            let s = at(i);
            if s > best.map_or(f32::NEG_INFINITY, |b| b.0) {
                best = Some((s, i));
            }
        }
        let (max, i) = best?;
        let defined = |v: f32| (!v.is_nan()).then_some(v);
        let before = (i > 0).then(|| at(i - 1)).and_then(defined);
        let after = (i + 1 < n).then(|| at(i + 1)).and_then(defined);
        let t = t0 + self.step * f64::from(i);
        let (refined, _) = refine_peak((max, t), (before, after), self.step, |t| {
            field.sample64(o_v + d_v * t).map(|v| v as f32)
        });
        Some([max, i as f32, refined])
    }
}

/// A ray's MIP lattice as the lane stream places it: sample `i` at the f32 point
/// `base + step * i` (`base` the entry point, `step` the voxel-space step).
struct LatticeRay {
    base: Vec3,
    step: Vec3,
}

impl LatticeRay {
    fn new(o_v: DVec3, d_v: DVec3, t0: f64, step: f64) -> Self {
        Self {
            base: (o_v + d_v * t0).as_vec3(),
            step: (d_v * step).as_vec3(),
        }
    }

    /// The samples `first..last` (NaN where undefined or not finite), [`LANES`] at a time.
    fn samples<F: Field>(&self, field: &F, first: i32, last: i32) -> Vec<f32> {
        let mut out = Vec::with_capacity((last - first).max(0) as usize);
        let mut i = first;
        while i < last {
            let idx: [i32; LANES] = std::array::from_fn(|l| (i + l as i32).min(last - 1));
            let p: [[f32; LANES]; 3] = std::array::from_fn(|a| {
                std::array::from_fn(|l| self.base[a] + self.step[a] * idx[l] as f32)
            });
            let v = field.sample_lanes(&p);
            let take = ((last - i) as usize).min(LANES);
            out.extend(
                v[..take]
                    .iter()
                    .map(|&v| if v.is_finite() { v } else { f32::NAN }),
            );
            i += LANES as i32;
        }
        out
    }
}

/// The number of lattice points `t0 + i step <= t1`, at least 1 and at most `i32::MAX / 2`
/// (the single-process MIP's lattice, `mip::max_along`).
fn lattice_count(t0: f64, t1: f64, step: f64) -> i32 {
    let t = |i: i64| t0 + step * i as f64;
    let limit = i64::from(i32::MAX / 2);
    let mut n = (((t1 - t0) / step).max(0.0).min(limit as f64) as i64) + 1;
    while n < limit && t(n) <= t1 {
        n += 1;
    }
    while n > 1 && t(n - 1) > t1 {
        n -= 1;
    }
    n as i32
}
