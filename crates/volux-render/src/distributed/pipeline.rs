//! Adaptive Simpson on several ranks, exactly: its steps, its streak of successes, its
//! lookahead and its accept/reject decisions (which read the absolute transmittance) depend
//! on the whole ray so far (`001_...txt` ch. 4, Algorithms 3 and 4), so a region cannot
//! integrate its part of a ray on its own. Instead the ranks pass the rays' states
//! ([`RayState`]) along the view's visibility order of the k-d regions (seed `003`'s blocks,
//! front to back: the order of the binary swap, one order for every ray from the eye):
//! each rank resumes every ray where the regions in front of it stopped, takes the steps
//! that start in its region (a step straddling its far face is its own, its samples past
//! the face read from the neighbour's chunks within the reach of `Near`), and hands the
//! states on.
//! The image is cut into bands of rows, run as a wavefront ([`pipeline`]): the first rank
//! starts band `k + 1` while the second resumes band `k`. The last rank holds the finished
//! pixels and sends them to rank 0. The image is the single-process render's, bit for bit,
//! early termination included (a state carries its opacity).
use std::time::Instant;

use volux_core::Image;

use super::error::DistributedError;
use super::exchange::Exchange;
use super::kdtree::KdSplit;
use super::region::{is_pipelined, reach, region_options, Near, RegionRays, SpanRule};
use super::states::{decode, encode};
use super::swap::CompositeStats;
use crate::integrate::adaptive::state::RayState;
use crate::raycast::{with_band_caster, Placement, RenderOptions};
use crate::sampling::Field;
use crate::tiles::TILE;

/// What one rank did in a distributed frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RankTimes {
    /// Time spent rendering its region (summed over the bands), seconds.
    pub render_seconds: f64,
    /// Its messages and bytes, and the rest of its time (waiting, sending, compositing).
    pub composite: CompositeStats,
}

/// Renders region `region` of `split` of `field` (placed by `place`, classified over
/// `range`) with adaptive Simpson in the pipeline of the ranks of `ex` in the visibility
/// order `order` (the same on every rank): rank 0 gets the image, equal to the
/// single-process render of `opts` (early termination as `opts` have it), the others `None`.
/// Every rank must call it.
pub fn render_pipelined<F: Field, E: Exchange + ?Sized>(
    field: &F,
    (place, range): (Placement, [f64; 2]),
    (split, region): (&KdSplit, usize),
    opts: &RenderOptions,
    ex: &mut E,
    order: &[usize],
) -> Result<(Option<Image>, RankTimes), DistributedError> {
    let opts = region_options(opts)?;
    if region >= split.len() || !is_pipelined(&opts) {
        return Err(DistributedError::Unsupported(format!(
            "the pipeline of {} in region {region} of a split into {}",
            opts.integrator.name(),
            split.len()
        )));
    }
    let rays = RegionRays {
        split,
        region,
        rule: SpanRule::Samples,
    };
    match Near::new(field, split, region, reach(&opts, &place)) {
        Some(near) => run(&near, (place, range), &rays, &opts, (ex, order)),
        None => run(field, (place, range), &rays, &opts, (ex, order)),
    }
}

/// The pipeline over `field` (a region's, or the whole).
fn run<F: Field, E: Exchange + ?Sized>(
    field: &F,
    (place, range): (Placement, [f64; 2]),
    rays: &RegionRays<'_>,
    opts: &RenderOptions,
    (ex, order): (&mut E, &[usize]),
) -> Result<(Option<Image>, RankTimes), DistributedError> {
    with_band_caster(field, place, range, rays, opts, |caster| {
        let size = (opts.width, opts.height);
        pipeline(ex, order, size, |y0, states| Ok(caster.resume(y0, states)?))
    })?
}

/// The rows of a band: a row of tiles.
const BAND: usize = TILE;

/// Runs the wavefront over the bands of an image of `(width, height)` on this rank:
/// receives each band's states from the rank in front (the first rank starts from
/// [`RayState::Start`]), resumes them with `band(y0, states)`, sends them to the rank
/// behind; the last rank keeps the pixels and sends the image to rank 0, which returns it.
/// A rank that fails (or hears of a failure in front) passes a failure on for its
/// remaining bands, so that no rank waits forever; every rank then returns an error.
pub fn pipeline<E: Exchange + ?Sized>(
    ex: &mut E,
    order: &[usize],
    (width, height): (usize, usize),
    mut band: impl FnMut(usize, &[RayState]) -> Result<Vec<RayState>, DistributedError>,
) -> Result<(Option<Image>, RankTimes), DistributedError> {
    let started = Instant::now();
    let me = ex.rank();
    let pos = check_order(ex, order)?;
    let (prev, next) = (pos.checked_sub(1).map(|i| order[i]), order.get(pos + 1));
    let mut stats = RankTimes::default();
    let mut failed: Option<DistributedError> = None;
    let mut pixels = Vec::new();
    for y0 in (0..height).step_by(BAND) {
        let n = width * (height.min(y0 + BAND) - y0);
        let input = match prev {
            None => Some(vec![RayState::Start; n]),
            Some(from) => receive(ex, from, n, &mut stats.composite, &mut failed)?,
        };
        let t = Instant::now();
        let output = match input {
            Some(states) if failed.is_none() => band(y0, &states)
                .and_then(|out| check_len(out, n))
                .map_err(|e| failed = Some(e))
                .ok(),
            _ => None,
        };
        stats.render_seconds += t.elapsed().as_secs_f64();
        stats.composite.rounds += 1;
        match (next, output) {
            (Some(&to), output) => {
                let mut msg = vec![f32::from(u8::from(output.is_none()))];
                if let Some(out) = &output {
                    encode(out, &mut msg);
                }
                send(ex, to, &msg, &mut stats.composite)?;
            }
            (None, Some(out)) => pixels.extend(out.iter().map(RayState::rgba)),
            (None, None) => {}
        }
    }
    let last = order[order.len() - 1];
    let image = gather(ex, (me, last), (width, height), pixels, &failed, &mut stats);
    stats.composite.seconds = started.elapsed().as_secs_f64() - stats.render_seconds;
    match failed {
        Some(e) => Err(e),
        None => Ok((image?, stats)),
    }
}

/// This rank's position in `order`, which must be an order of all the ranks.
fn check_order<E: Exchange + ?Sized>(ex: &E, order: &[usize]) -> Result<usize, DistributedError> {
    let mut sorted = order.to_vec();
    sorted.sort_unstable();
    if sorted != (0..ex.size()).collect::<Vec<_>>() || order.is_empty() {
        return Err(DistributedError::Exchange(format!(
            "the visibility order {order:?} is not an order of the {} ranks",
            ex.size()
        )));
    }
    Ok(order.iter().position(|&r| r == ex.rank()).unwrap_or(0))
}

/// The states of a band from rank `from` (`None`: it failed, or the message was wrong,
/// which this rank then reports in `failed`).
fn receive<E: Exchange + ?Sized>(
    ex: &mut E,
    from: usize,
    n: usize,
    stats: &mut CompositeStats,
    failed: &mut Option<DistributedError>,
) -> Result<Option<Vec<RayState>>, DistributedError> {
    let msg = ex.recv(from)?;
    stats.bytes_received += 4 * msg.len() as u64;
    let decoded = match msg.split_first() {
        Some((flag, words)) if *flag == 0.0 => decode(words, n),
        _ => Err(DistributedError::Exchange(format!(
            "rank {from}, in front in the pipeline, failed"
        ))),
    };
    Ok(decoded.map_err(|e| failed.get_or_insert(e)).ok())
}

fn check_len(out: Vec<RayState>, n: usize) -> Result<Vec<RayState>, DistributedError> {
    if out.len() != n {
        return Err(DistributedError::Exchange(format!(
            "a band resumed {} rays of {n}",
            out.len()
        )));
    }
    Ok(out)
}

fn send<E: Exchange + ?Sized>(
    ex: &mut E,
    to: usize,
    msg: &[f32],
    stats: &mut CompositeStats,
) -> Result<(), DistributedError> {
    ex.send(to, msg)?;
    stats.messages += 1;
    stats.bytes_sent += 4 * msg.len() as u64;
    Ok(())
}

/// The last rank's pixels (`me == last`) on rank 0, as an image.
fn gather<E: Exchange + ?Sized>(
    ex: &mut E,
    (me, last): (usize, usize),
    (width, height): (usize, usize),
    pixels: Vec<[f32; 4]>,
    failed: &Option<DistributedError>,
    stats: &mut RankTimes,
) -> Result<Option<Image>, DistributedError> {
    let pixels = if me == last && me != 0 {
        let mut msg = vec![f32::from(u8::from(failed.is_some()))];
        if failed.is_none() {
            msg.extend(pixels.iter().flatten());
        }
        send(ex, 0, &msg, &mut stats.composite)?;
        return Ok(None);
    } else if me == 0 && last != 0 {
        let msg = ex.recv(last)?;
        stats.composite.bytes_received += 4 * msg.len() as u64;
        match msg.split_first() {
            Some((flag, words)) if *flag == 0.0 && words.len() == 4 * width * height => words
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            _ => {
                return Err(DistributedError::Exchange(format!(
                    "rank {last}, last in the pipeline, sent no image"
                )))
            }
        }
    } else if me == 0 {
        pixels
    } else {
        return Ok(None);
    };
    Image::from_pixels(width, height, pixels)
        .map(Some)
        .map_err(|e| DistributedError::Exchange(format!("the pipeline's image: {e}")))
}
