//! Sort-last compositing of partial images ([`composite`]): binary swap over the ranks in
//! visibility order, with the ranks beyond the largest power of two folded into their
//! neighbours in that order first (as IceT does for other counts), then a gather of the
//! pieces to rank 0.
//!
//! Every step composites a front piece *under*-style with the piece behind it (premultiplied
//! RGBA: `C = C_front + (1 - A_front) C_back`), the exact composition of two parts of a ray
//! integral, so the result is the single-process ray's colour (seed `003` reset opacity at
//! every block boundary instead). The same swap reduces other per-pixel records with
//! another merge ([`reduce`]: the split MIP's maxima).
use std::time::Instant;

use volux_core::Image;

use super::error::DistributedError;
use super::exchange::Exchange;
use crate::composite::under;

/// What one rank did while compositing.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CompositeStats {
    /// Messages sent.
    pub messages: u64,
    /// Bytes sent.
    pub bytes_sent: u64,
    /// Bytes received.
    pub bytes_received: u64,
    /// Binary-swap rounds this rank took part in.
    pub rounds: u32,
    /// Wall time, seconds.
    pub seconds: f64,
}

/// The pixels `[start, end)` that participant `v` of a binary swap of `m` ranks (a power of
/// two) holds at the end, of an image of `n` pixels: halved once per round, the first half
/// kept by the participant whose bit of that round is 0.
pub fn piece(v: usize, m: usize, n: usize) -> (usize, usize) {
    let (mut s, mut e) = (0, n);
    let mut k = 0;
    while (1usize << k) < m {
        let mid = s + (e - s) / 2;
        if v >> k & 1 == 0 {
            e = mid;
        } else {
            s = mid;
        }
        k += 1;
    }
    (s, e)
}

/// Who takes part in the swap after folding: `p` ranks in visibility order `order`, `m` the
/// largest power of two at most `p`, `e = p - m` extra ranks. Order positions `2i` and
/// `2i + 1` (`i < e`) fold into one participant (the back one sends its image to the front
/// one), the others take part alone; participants keep the visibility order.
struct Plan {
    m: usize,
    e: usize,
}

impl Plan {
    fn new(p: usize) -> Self {
        let m = if p.is_power_of_two() {
            p
        } else {
            p.next_power_of_two() / 2
        };
        Self { m, e: p - m }
    }

    /// The rank of participant `v`.
    fn rank_of(&self, order: &[usize], v: usize) -> usize {
        if v < self.e {
            order[2 * v]
        } else {
            order[v + self.e]
        }
    }
}

/// Composites the ranks' partial images (premultiplied RGBA, no background, the same size
/// on every rank) front to back in `order` (the ranks front to back, the same on every
/// rank). Rank 0 gets the whole image; the others `None`. Every rank must call it.
pub fn composite<E: Exchange + ?Sized>(
    ex: &mut E,
    order: &[usize],
    partial: &Image,
) -> Result<(Option<Image>, CompositeStats), DistributedError> {
    let started = Instant::now();
    let (w, h) = (partial.width(), partial.height());
    let buf: Vec<f32> = partial.pixels().iter().flatten().copied().collect();
    let (image, mut stats) = reduce(ex, order, buf, 4, over_back)?;
    let image = match image {
        Some(image) => {
            let pixels = image
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect();
            let image = Image::from_pixels(w, h, pixels)
                .map_err(|e| DistributedError::Exchange(format!("the gathered image: {e}")))?;
            Some(image)
        }
        None => None,
    };
    stats.seconds = started.elapsed().as_secs_f64();
    Ok((image, stats))
}

/// Binary swap of per-pixel records of `channels` values (`buf`, the same size on every
/// rank) in `order`, `combine(front, back)` merging the records of the pixels of a piece
/// behind (`back`) into those in front (`front`); then a gather to rank 0, which gets the
/// whole result (the others `None`). Compositing ([`composite`]) merges by *under*; the
/// split MIP by maximum ([`MipPart::merge`](super::mip::MipPart::merge)).
pub fn reduce<E: Exchange + ?Sized>(
    ex: &mut E,
    order: &[usize],
    mut buf: Vec<f32>,
    channels: usize,
    combine: fn(&mut [f32], &[f32]),
) -> Result<(Option<Vec<f32>>, CompositeStats), DistributedError> {
    let started = Instant::now();
    let p = ex.size();
    let mut sorted = order.to_vec();
    sorted.sort_unstable();
    if p == 0 || sorted != (0..p).collect::<Vec<_>>() {
        return Err(DistributedError::Exchange(format!(
            "the visibility order {order:?} is not an order of the {p} ranks"
        )));
    }
    let c = channels.max(1);
    let n = buf.len() / c;
    let mut stats = CompositeStats::default();
    let me = ex.rank();
    let pos = order.iter().position(|&r| r == me).unwrap_or(0);
    let plan = Plan::new(p);
    // Fold the extra ranks into their front neighbours.
    let v = if pos < 2 * plan.e {
        if pos % 2 == 1 {
            send(ex, order[pos - 1], &buf, &mut stats)?;
            None
        } else {
            let back = recv(ex, order[pos + 1], c * n, &mut stats)?;
            combine(&mut buf, &back);
            Some(pos / 2)
        }
    } else {
        Some(pos - plan.e)
    };
    // Binary swap among the m participants.
    if let Some(v) = v {
        let (s, e) = swap(ex, order, &plan, v, (&mut buf, c), combine, &mut stats)?;
        if me != 0 {
            send(ex, 0, &buf[c * s..c * e], &mut stats)?;
        }
    }
    if me != 0 {
        stats.seconds = started.elapsed().as_secs_f64();
        return Ok((None, stats));
    }
    // Gather the pieces on rank 0.
    let mut whole = vec![0.0f32; c * n];
    for u in 0..plan.m {
        let (s, e) = piece(u, plan.m, n);
        let r = plan.rank_of(order, u);
        if r == 0 {
            whole[c * s..c * e].copy_from_slice(&buf[c * s..c * e]);
        } else {
            let got = recv(ex, r, c * (e - s), &mut stats)?;
            whole[c * s..c * e].copy_from_slice(&got);
        }
    }
    stats.seconds = started.elapsed().as_secs_f64();
    Ok((Some(whole), stats))
}

/// The rounds of binary swap of participant `v`: returns the pixels `[s, e)` it ends with.
fn swap<E: Exchange + ?Sized>(
    ex: &mut E,
    order: &[usize],
    plan: &Plan,
    v: usize,
    (buf, c): (&mut [f32], usize),
    combine: fn(&mut [f32], &[f32]),
    stats: &mut CompositeStats,
) -> Result<(usize, usize), DistributedError> {
    let (mut s, mut e) = (0, buf.len() / c);
    let mut k = 0;
    while (1usize << k) < plan.m {
        let mid = s + (e - s) / 2;
        let partner_v = v ^ (1 << k);
        let partner = plan.rank_of(order, partner_v);
        let (keep, give) = if v >> k & 1 == 0 {
            ((s, mid), (mid, e))
        } else {
            ((mid, e), (s, mid))
        };
        let got = ex.exchange(partner, &buf[c * give.0..c * give.1])?;
        stats.messages += 1;
        stats.bytes_sent += 4 * (c * (give.1 - give.0)) as u64;
        check_len(got.len(), c * (keep.1 - keep.0), partner)?;
        stats.bytes_received += 4 * got.len() as u64;
        let mine = &mut buf[c * keep.0..c * keep.1];
        if v < partner_v {
            combine(mine, &got);
        } else {
            let mut acc = got;
            combine(&mut acc, mine);
            mine.copy_from_slice(&acc);
        }
        (s, e) = keep;
        k += 1;
        stats.rounds += 1;
    }
    Ok((s, e))
}

/// Composites `back` behind `front`, pixel by pixel, into `front`.
fn over_back(front: &mut [f32], back: &[f32]) {
    for (f, b) in front.chunks_exact_mut(4).zip(back.chunks_exact(4)) {
        let mut acc = [f[0], f[1], f[2], f[3]];
        under(&mut acc, [b[0], b[1], b[2], b[3]]);
        f.copy_from_slice(&acc);
    }
}

fn send<E: Exchange + ?Sized>(
    ex: &mut E,
    to: usize,
    data: &[f32],
    stats: &mut CompositeStats,
) -> Result<(), DistributedError> {
    ex.send(to, data)?;
    stats.messages += 1;
    stats.bytes_sent += 4 * data.len() as u64;
    Ok(())
}

fn recv<E: Exchange + ?Sized>(
    ex: &mut E,
    from: usize,
    len: usize,
    stats: &mut CompositeStats,
) -> Result<Vec<f32>, DistributedError> {
    let got = ex.recv(from)?;
    check_len(got.len(), len, from)?;
    stats.bytes_received += 4 * got.len() as u64;
    Ok(got)
}

fn check_len(got: usize, want: usize, from: usize) -> Result<(), DistributedError> {
    if got != want {
        return Err(DistributedError::Exchange(format!(
            "rank {from} sent {got} values where {want} were expected (images of different sizes?)"
        )));
    }
    Ok(())
}
