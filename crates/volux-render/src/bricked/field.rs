//! Field sampling of a bricked level: trilinear interpolation on the global sample lattice,
//! exact across brick faces (a cell whose corners lie in several chunks gathers each corner
//! from its own chunk), with the same arithmetic as the in-core sampler
//! ([`Trilinear`](crate::sampling::Trilinear)), so that a bricked render equals the in-core
//! render of the same data.
//!
//! Each thread remembers the last bricks it sampled (rays advance through a brick for many
//! samples, and the lanes of a block of pixels share bricks), so the cache's lock is taken
//! about once per brick crossing, not per sample.
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use glam::{DVec3, Vec3};

use super::cache::{Brick, BrickCache};
use crate::sampling::{axis64, Field};

/// Identities of caches for the per-thread memo (a brick of one cache is never taken for
/// another's).
static NEXT_FIELD: AtomicU64 = AtomicU64::new(1);

/// Slots of the per-thread memo: the lanes of the lane stream hold rays at different depths,
/// so a step's samples fall in a few bricks at once; one remembered brick thrashed.
const MEMO_SLOTS: usize = 16;

/// A remembered brick: (field identity, chunk index, brick).
type Memo = Option<(u64, usize, Arc<Brick>)>;

thread_local! {
    /// The bricks this thread sampled last, direct-mapped by chunk index.
    static LAST: RefCell<[Memo; MEMO_SLOTS]> = const { RefCell::new([const { None }; MEMO_SLOTS]) };
}

/// A bricked level as a [`Field`] for one render. A chunk that cannot be read makes its
/// samples undefined, keeps the first error and raises `failed` (the render is stopped and
/// the error returned instead of the image).
pub(crate) struct BrickedField<'a> {
    cache: &'a BrickCache,
    id: u64,
    dims: [usize; 3],
    chunk: [usize; 3],
    hi: [f32; 3],
    cell_max: [u32; 3],
    error: OnceLock<String>,
    failed: Arc<AtomicBool>,
}

impl<'a> BrickedField<'a> {
    /// The field of `cache`'s level; `failed` is raised on the first chunk error.
    pub(crate) fn new(cache: &'a BrickCache, failed: Arc<AtomicBool>) -> Self {
        let layout = cache.layout();
        let dims = layout.dims;
        Self {
            cache,
            id: NEXT_FIELD.fetch_add(1, Ordering::Relaxed),
            dims,
            chunk: layout.chunk,
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| u32::try_from(n.saturating_sub(2)).unwrap_or(u32::MAX)),
            error: OnceLock::new(),
            failed,
        }
    }

    /// The first chunk error of the render, if any.
    pub(crate) fn error(&self) -> Option<&String> {
        self.error.get()
    }

    /// `f` of the brick holding sample (`i`, `j`, `k`), from this thread's memo or the cache
    /// (no reference count is touched on a hit: two threads sharing a brick would bounce
    /// its count between their caches at every sample). `f` must not sample this field.
    #[inline]
    fn with_brick<R>(
        &self,
        i: usize,
        j: usize,
        k: usize,
        f: impl FnOnce(&Brick) -> R,
    ) -> Option<R> {
        let c = [i / self.chunk[0], j / self.chunk[1], k / self.chunk[2]];
        let index = self.cache.layout().chunk_index(c);
        LAST.with(|memo| {
            let mut memo = memo.borrow_mut();
            let m = &mut memo[index % MEMO_SLOTS];
            let hit = matches!(&*m, Some((id, at, _)) if *id == self.id && *at == index);
            if !hit {
                match self.cache.get(c) {
                    Ok(b) => *m = Some((self.id, index, b)),
                    Err(e) => {
                        let _ = self.error.set(e);
                        self.failed.store(true, Ordering::Relaxed);
                        return None;
                    }
                }
            }
            m.as_ref().map(|(_, _, b)| f(b))
        })
    }

    /// The cell of `p` (clamped as [`Trilinear::sample_raw`](crate::sampling::Trilinear)
    /// clamps), its fractions, and its eight corners (x fastest: corner `q` at `+ (q & 1,
    /// q >> 1 & 1, q >> 2 & 1)`, the +1 neighbour being the sample itself along an axis with
    /// one sample). `None` when a chunk cannot be read.
    #[inline]
    fn cell(&self, p: Vec3) -> Option<([f32; 8], [f32; 3])> {
        let x = p.x.max(0.0).min(self.hi[0]);
        let y = p.y.max(0.0).min(self.hi[1]);
        let z = p.z.max(0.0).min(self.hi[2]);
        let [ci, cj, ck] = self.cell_max;
        let (i, j, k) = ((x as u32).min(ci), (y as u32).min(cj), (z as u32).min(ck));
        let f = [x - i as f32, y - j as f32, z - k as f32];
        let (i, j, k) = (i as usize, j as usize, k as usize);
        let n = [
            i + usize::from(self.dims[0] > 1),
            j + usize::from(self.dims[1] > 1),
            k + usize::from(self.dims[2] > 1),
        ];
        let at = |q: usize| {
            [
                if q & 1 == 1 { n[0] } else { i },
                if q >> 1 & 1 == 1 { n[1] } else { j },
                if q >> 2 & 1 == 1 { n[2] } else { k },
            ]
        };
        // The cell in one brick (most cells), else each corner from its own.
        let one = self.with_brick(i, j, k, |b| {
            (0..3).all(|a| n[a] < b.lo[a] + b.size[a]).then(|| {
                std::array::from_fn(|q| {
                    let [x, y, z] = at(q);
                    b.at(x, y, z)
                })
            })
        })?;
        let v = match one {
            Some(v) => v,
            None => {
                let mut v = [0.0f32; 8];
                for (q, v) in v.iter_mut().enumerate() {
                    let [x, y, z] = at(q);
                    *v = self.with_brick(x, y, z, |b| b.at(x, y, z))?;
                }
                v
            }
        };
        Some((v, f))
    }
}

impl Field for BrickedField<'_> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The in-core sampler's arithmetic: x pairs, then y, then z.
    #[inline]
    fn sample(&self, p: Vec3) -> Option<f32> {
        let (v, [fx, fy, fz]) = self.cell(p)?;
        let lerp = |a: f32, c: f32| a + (c - a) * fx;
        let (c00, c10) = (lerp(v[0], v[1]), lerp(v[2], v[3]));
        let (c01, c11) = (lerp(v[4], v[5]), lerp(v[6], v[7]));
        let c0 = c00 + (c10 - c00) * fy;
        let c1 = c01 + (c11 - c01) * fy;
        let r = c0 + (c1 - c0) * fz;
        r.is_finite().then_some(r)
    }

    /// The in-core f64 path's arithmetic on the same corners.
    fn sample64(&self, p: DVec3) -> Option<f64> {
        let (i, fx) = axis64(p.x, self.dims[0]);
        let (j, fy) = axis64(p.y, self.dims[1]);
        let (k, fz) = axis64(p.z, self.dims[2]);
        let n = [
            i + usize::from(self.dims[0] > 1),
            j + usize::from(self.dims[1] > 1),
            k + usize::from(self.dims[2] > 1),
        ];
        let mut v = [0.0f64; 8];
        for (q, v) in v.iter_mut().enumerate() {
            let x = if q & 1 == 1 { n[0] } else { i };
            let y = if q >> 1 & 1 == 1 { n[1] } else { j };
            let z = if q >> 2 & 1 == 1 { n[2] } else { k };
            *v = f64::from(self.with_brick(x, y, z, |b| b.at(x, y, z))?);
        }
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c0 = lerp(lerp(v[0], v[1], fx), lerp(v[2], v[3], fx), fy);
        let c1 = lerp(lerp(v[4], v[5], fx), lerp(v[6], v[7], fx), fy);
        let r = lerp(c0, c1, fz);
        r.is_finite().then_some(r)
    }
}
