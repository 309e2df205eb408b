//! The traversal seam of grid ray casting (Open VKL's interval iterator): a ray asks its
//! volume for the parts of it worth sampling, each an [`Interval`] of distances with the
//! range of values the field takes there. The macrocell grid of a regular grid provides them
//! ([`Occupancy`](crate::macrocell::Occupancy)); a bricked or out-of-core grid provides its
//! own ([`IntervalSource`]), brick by brick, and the ray loops do not change.

/// A part of a ray worth sampling: distances along the ray and the range of values the field
/// takes there (every sample in it lies in `values`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Entry and exit distances along the ray (`t[0] <= t[1]`).
    pub t: [f64; 2],
    /// The smallest and largest value of the field over the interval.
    pub values: [f32; 2],
}

/// What a volume tells the grid traversal about a ray: where to sample it.
pub trait IntervalSource: Sync {
    /// The `t` ranges of the occupied intervals of the voxel-space ray `o + t d`, `t` in
    /// `[t0, t1]`, front to back, into `out` (cleared first).
    fn occupied(&self, o: glam::DVec3, d: glam::DVec3, t0: f64, t1: f64, out: &mut Vec<(f64, f64)>);

    /// The first of [`IntervalSource::occupied`]'s ranges, at least those starting before
    /// `limit`, into `out` (cleared first); returns where they stop: `t1` when the whole ray
    /// was walked, else a distance in empty space (no range crosses it) from which a later
    /// call continues. A ray that stops early (opaque) then never walks the rest. By default
    /// the whole ray.
    fn occupied_until(
        &self,
        o: glam::DVec3,
        d: glam::DVec3,
        (t0, t1): (f64, f64),
        _limit: f64,
        out: &mut Vec<(f64, f64)>,
    ) -> f64 {
        self.occupied(o, d, t0, t1, out);
        t1
    }

    /// Whether the ray's last sample in these intervals owns the step to the next sample of
    /// its lattice beyond them (a region of a split render: the isosurfaces crossed in that
    /// step are found there, the next region starting afresh). `false` by default.
    fn owns_step_past_end(&self) -> bool {
        false
    }

    /// The fraction of the volume known to be empty (renderers skip empty space only when it
    /// pays: walking the intervals costs time too).
    fn empty_fraction(&self) -> f64;
}
