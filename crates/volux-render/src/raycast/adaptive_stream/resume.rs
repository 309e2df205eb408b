//! The lane path of adaptive Simpson resumed piece by piece: each ray of a tile continues
//! from the state an earlier piece left ([`RayState`]) and pauses before its first step that
//! would start past the end of its piece, the steps and decisions those of the whole ray
//! (`001_...txt` ch. 4, Algorithm 3). A distributed render's region hands the states on
//! in visibility order (seed `003`'s blocks, made exact).
use super::{Flight, LanePath, Slot};
use crate::integrate::adaptive::lanes::RAYS;
use crate::integrate::adaptive::state::RayState;
use crate::intervals::IntervalSource;
use crate::raycast::context::{pixel, RayContext};
use crate::raycast::stream::block_order;
use crate::sampling::Field;
use crate::tiles::TILE;

/// A tile of rays resumed: where each begins its piece, and the states in and out.
struct Resume<'s> {
    piece: &'s dyn IntervalSource,
    x0: usize,
    y0: usize,
    tw: usize,
    states: &'s mut [RayState],
}

impl<F: Field> RayContext<'_, F> {
    /// Resumes the rays of the tile at (`x0`, `y0`) from `states` (the tile's pixels, row by
    /// row), each until its next step would start past the end of its part in `piece`
    /// (one interval per ray), into the states returned. A ray that does not cross
    /// `piece`, or whose next step starts past it, keeps its state.
    pub(in crate::raycast) fn adaptive_stream_resume(
        &self,
        path: LanePath<'_>,
        piece: &dyn IntervalSource,
        (x0, y0): (usize, usize),
        states: &[RayState],
    ) -> Vec<RayState> {
        let (w, h) = (self.opts.width, self.opts.height);
        let (tw, th) = ((x0 + TILE).min(w) - x0, (y0 + TILE).min(h) - y0);
        let mut out = states.to_vec();
        let mut job = Resume {
            piece,
            x0,
            y0,
            tw,
            states: &mut out,
        };
        let mut queue = block_order(tw, th).into_iter();
        let mut f = Flight::new(&path);
        for r in 0..RAYS {
            self.load_resumed(&mut f, r, &mut job, &mut queue);
            self.advance_resumed(&mut f, r, &mut job, &mut queue);
        }
        while f.lanes.is_busy() {
            self.round(&mut f, &path);
            for r in 0..RAYS {
                self.advance_resumed(&mut f, r, &mut job, &mut queue);
            }
        }
        out
    }

    /// Hands slot `r`'s ray back while it has paused or finished, and loads the next.
    fn advance_resumed(
        &self,
        f: &mut Flight,
        r: usize,
        job: &mut Resume<'_>,
        queue: &mut impl Iterator<Item = usize>,
    ) {
        loop {
            let Some(slot) = f.slots[r].as_mut() else {
                return f.lanes.idle(r);
            };
            let state = if f.lanes.is_paused(r) {
                RayState::Lanes(f.lanes.export(r))
            } else if f.lanes.needs_span(r) {
                let span = slot.spans.get(slot.next).copied();
                slot.next += 1;
                match span {
                    Some(s) if !f.lanes.is_opaque(r) => {
                        f.lanes.enter(r, s);
                        continue;
                    }
                    _ => RayState::Done(pixel(&f.lanes.result(r)).rgba),
                }
            } else {
                return;
            };
            job.states[slot.pixel] = state;
            self.load_resumed(f, r, job, queue);
        }
    }

    /// Loads the tile's next ray that continues in the piece into slot `r` (the others keep
    /// their states), or empties the slot.
    fn load_resumed(
        &self,
        f: &mut Flight,
        r: usize,
        job: &mut Resume<'_>,
        queue: &mut impl Iterator<Item = usize>,
    ) {
        let mut spans = f.slots[r].take().map(|s| s.spans).unwrap_or_default();
        let mut part = Vec::with_capacity(1);
        for pixel in queue.by_ref() {
            let state = job.states[pixel];
            if matches!(state, RayState::Done(_) | RayState::F64(_)) {
                continue;
            }
            let (gx, gy) = (job.x0 + pixel % job.tw, job.y0 + pixel / job.tw);
            let ray = self.rays.ray(gx as f64 + 0.5, gy as f64 + 0.5);
            let Some((o_v, d_v, t0, t1, _)) = self.setup(ray.origin, ray.dir, &mut spans) else {
                continue;
            };
            job.piece.occupied(o_v, d_v, t0, t1, &mut part);
            let Some(&(_, stop)) = part.first() else {
                continue;
            };
            let next = match state {
                RayState::Start => {
                    f.lanes
                        .start(r, spans.iter().map(|(a, b)| (b - a).max(0.0)).sum());
                    0
                }
                RayState::Lanes(s) if f64::from(s.t) < stop => {
                    f.lanes.import(r, &s, stop);
                    1
                }
                _ => continue,
            };
            f.lanes.stop_at(r, stop);
            self.aim(f, r, o_v, d_v);
            f.slots[r] = Some(Slot { pixel, spans, next });
            return;
        }
        f.slots[r] = None;
        f.lanes.idle(r);
    }
}
