//! Adaptive Simpson resumed piece by piece over the rays of a band of image rows
//! ([`BandCaster`]): each ray continues from the state an earlier piece of it left and stops
//! before its first step that would start past the end of its part in this piece, so that
//! the pieces, integrated one after the other, take the whole ray's steps and decisions
//! (`001_...txt` ch. 4, Algorithms 3 and 4). The distributed renderer's regions are the
//! pieces (seed `003`'s blocks, made exact).
use super::context::{pixel, Derived, RayContext};
use super::options::{Placement, RenderOptions};
use super::traverse::with_context;
use crate::error::RenderError;
use crate::integrate::adaptive::state::RayState;
use crate::integrate::adaptive::{adaptive_simpson_resume, Resumed};
use crate::integrate::Integrator;
use crate::intervals::IntervalSource;
use crate::sampling::Field;
use crate::tiles::{render_tiles, TileGrid, TILE};

/// Scratch space for a ray's spans.
type Spans = Vec<(f64, f64)>;

/// The rays of a render resumed in one piece of the volume (one interval per ray, as
/// [`IntervalSource::occupied`] gives it), band by band.
pub(crate) struct BandCaster<'c, 'a, F> {
    ctx: &'c RayContext<'a, F>,
    piece: &'c dyn IntervalSource,
}

/// Runs `body` with the caster of `field` (placed by `place`, classified over `range`)
/// resuming adaptive Simpson in `piece`, the rays and the integrator's path (f32 lanes or
/// f64) those of [`render_field`](super::render_field) with the same options.
pub(crate) fn with_band_caster<F: Field, R>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    piece: &dyn IntervalSource,
    opts: &RenderOptions,
    body: impl FnOnce(&BandCaster<'_, '_, F>) -> R,
) -> Result<R, RenderError> {
    opts.validate()?;
    let derived = Derived {
        lanes: true,
        ..Default::default()
    };
    Ok(with_context(field, place, range, opts, derived, |ctx| {
        body(&BandCaster { ctx, piece })
    }))
}

impl<F: Field> BandCaster<'_, '_, F> {
    /// Resumes the rays of the image rows from `y0` (a multiple of the tile side) whose
    /// states are `states` (whole rows), in parallel over tiles: the states they leave.
    pub(crate) fn resume(
        &self,
        y0: usize,
        states: &[RayState],
    ) -> Result<Vec<RayState>, RenderError> {
        let w = self.ctx.opts.width;
        let grid = TileGrid::new(w, states.len() / w.max(1), TILE);
        let tiled = render_tiles(&grid, &self.ctx.opts.control, |_, r| {
            let input: Vec<RayState> = (r.y0..r.y1)
                .flat_map(|y| &states[y * w + r.x0..y * w + r.x1])
                .copied()
                .collect();
            let at = (r.x0, y0 + r.y0);
            let out = match self.ctx.adaptive_stream_params() {
                Some(p) => self.ctx.adaptive_stream_resume(p, self.piece, at, &input),
                None => self.ctx.resume_rays(self.piece, at, r.width(), &input),
            };
            (out, ())
        })?;
        Ok(tiled.pixels)
    }
}

impl<F: Field> RayContext<'_, F> {
    /// The f64 path: the tile at `(x0, y0)`, `tw` pixels wide, ray by ray.
    fn resume_rays(
        &self,
        piece: &dyn IntervalSource,
        (x0, y0): (usize, usize),
        tw: usize,
        states: &[RayState],
    ) -> Vec<RayState> {
        let (mut spans, mut part) = (Vec::new(), Vec::new());
        let mut out = states.to_vec();
        for (i, s) in out.iter_mut().enumerate() {
            let (x, y) = (x0 + i % tw, y0 + i / tw);
            *s = self.resume_ray(piece, (x, y), *s, (&mut spans, &mut part));
        }
        out
    }

    /// Pixel `(x, y)`'s ray resumed from `state` in its part of `piece`.
    fn resume_ray(
        &self,
        piece: &dyn IntervalSource,
        (x, y): (usize, usize),
        state: RayState,
        (spans, part): (&mut Spans, &mut Spans),
    ) -> RayState {
        let Integrator::AdaptiveSimpson(p) = self.opts.integrator else {
            return state;
        };
        let from = match &state {
            RayState::Start => None,
            RayState::F64(s) => Some(s),
            _ => return state,
        };
        let ray = self.rays.ray(x as f64 + 0.5, y as f64 + 0.5);
        let Some((o_v, d_v, t0, t1, _)) = self.setup(ray.origin, ray.dir, spans) else {
            return state;
        };
        piece.occupied(o_v, d_v, t0, t1, part);
        let Some(&(_, stop)) = part.first() else {
            return state;
        };
        if from.is_some_and(|s| s.t >= stop) {
            return state;
        }
        let p = self.adaptive_in_world(&p);
        let mut medium = self.medium(o_v, d_v);
        match adaptive_simpson_resume(&mut medium, (t0, t1), stop, &p, from) {
            Resumed::Paused(s) => RayState::F64(s),
            Resumed::Finished(integral) => RayState::Done(pixel(&integral).rgba),
        }
    }
}
