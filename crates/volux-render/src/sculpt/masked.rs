//! The sculpt mask as part of field sampling: a [`Field`] that is undefined (NaN) wherever the
//! mask hides the point, so that every path of the grid ray caster (every integrator, MIP,
//! isosurfaces) skips masked samples as it skips undefined ones: a NaN sample adds nothing,
//! nor does a segment that ends in one (seed `004` sec. 4.4.1: the mask interpolated and
//! thresholded at 0.5).
use glam::{DVec3, Vec3};
use volux_core::sculpt::SculptMask;

use crate::sampling::{Field, LANES};

/// `inner` seen through `mask`: [`SculptMask::visible`] decides each sample.
pub(crate) struct Masked<'a, F> {
    pub(crate) inner: &'a F,
    pub(crate) mask: &'a SculptMask,
}

impl<F: Field> Field for Masked<'_, F> {
    fn dims(&self) -> [usize; 3] {
        self.inner.dims()
    }

    #[inline]
    fn sample(&self, p: Vec3) -> Option<f32> {
        if self.mask.visible(p.to_array()) {
            self.inner.sample(p)
        } else {
            None
        }
    }

    #[inline(always)]
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        let mut v = self.inner.sample_lanes(p);
        let mut keep = [true; LANES];
        self.mask.visible_lanes(p, &mut keep);
        for (v, keep) in v.iter_mut().zip(keep) {
            if !keep {
                *v = f32::NAN;
            }
        }
        v
    }

    #[inline(always)]
    fn sample_lanes_unhidden(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        self.inner.sample_lanes(p)
    }

    /// Only lanes in partly removed macrocells are asked for (a few along the cut surfaces),
    /// so the others pay nothing for the mask ([`SculptMask::hidden_lanes`]). Out of line: it
    /// runs on a minority of steps (a quarter on the masked CT frame of `volux bench --suite
    /// voi`), and the step loop stays small; inlined, it measured no faster.
    #[inline(never)]
    fn hide_lanes(&self, p: &[[f32; LANES]; 3], v: &mut [f32; LANES], lanes: u32) {
        let hidden = self.mask.hidden_lanes(p, lanes);
        for (l, v) in v.iter_mut().enumerate() {
            if hidden >> l & 1 == 1 {
                *v = f32::NAN;
            }
        }
    }

    #[inline(always)]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        let mut v = self.inner.sample4(p);
        let mut keep = [true; 4];
        self.mask.visible_lanes(p, &mut keep);
        for (v, keep) in v.iter_mut().zip(keep) {
            if !keep {
                *v = f32::NAN;
            }
        }
        v
    }

    fn sample64(&self, p: DVec3) -> Option<f64> {
        if self.mask.visible(p.as_vec3().to_array()) {
            self.inner.sample64(p)
        } else {
            None
        }
    }
}
