//! The bricks each rendering thread sampled last: a small table per thread, looked up once
//! per lane, so that the brick cache's lock is taken about once per brick a thread enters,
//! not per sample, and no reference count is touched on a hit (two threads sharing a brick
//! would bounce its count between their caches at every sample).
//!
//! Entries are keyed by the field's identity and the chunk's index, and placed by a
//! multiplicative hash of the index: chunk `(i, j, k)` and `(i, j, k + 1)` then land in
//! different slots (direct mapping by `index % slots` put a ray's successive bricks along
//! `z` on one slot when the chunks per slice were a multiple of the slots).
use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use super::cache::Brick;

/// The most slots a thread's memo has (a field uses fewer when its bricks are large:
/// [`slots_for`]).
pub(crate) const MAX_SLOTS: usize = 32;

/// The fewest slots: the 16 lanes of the lane stream hold rays at different depths, so a
/// step's samples fall in a few bricks at once.
const MIN_SLOTS: usize = 4;

/// A remembered brick: (field identity, chunk index, brick).
pub(crate) type Entry = Option<(u64, usize, Arc<Brick>)>;

/// Identities of fields (a brick of one field is never taken for another's).
static NEXT_FIELD: AtomicU64 = AtomicU64::new(1);

thread_local! {
    static MEMO: RefCell<[Entry; MAX_SLOTS]> = const { RefCell::new([const { None }; MAX_SLOTS]) };
}

/// A new field identity.
pub(crate) fn new_id() -> u64 {
    NEXT_FIELD.fetch_add(1, Ordering::Relaxed)
}

/// How many slots a field whose bricks take `brick_bytes` uses so that the memos of
/// `threads` threads hold at most `share` bytes (between [`MIN_SLOTS`] and [`MAX_SLOTS`]).
pub(crate) fn slots_for(share: u64, brick_bytes: u64, threads: usize) -> usize {
    let fit = share / brick_bytes.max(1) / (threads.max(1) as u64);
    (fit as usize).clamp(MIN_SLOTS, MAX_SLOTS)
}

/// The slot of chunk `index` among `slots` (Fibonacci hashing, then a multiply-high onto
/// `0..slots`).
#[inline(always)]
pub(crate) fn slot_of(index: usize, slots: usize) -> usize {
    let h = (index as u32).wrapping_mul(0x9E37_79B1);
    ((u64::from(h) * slots as u64) >> 32) as usize
}

/// Runs `f` with this thread's memo (`f` must not call `with_memo` again).
#[inline(always)]
pub(crate) fn with_memo<R>(f: impl FnOnce(&mut [Entry; MAX_SLOTS]) -> R) -> R {
    MEMO.with(|m| f(&mut m.borrow_mut()))
}

/// Drops field `id`'s bricks from every memo of the current rayon pool (asynchronously, on
/// each thread when it is next idle) and from this thread's: once a render ends, its bricks
/// are held by the cache alone, which may then evict them.
pub(crate) fn forget(id: u64) {
    let clear = move || {
        // A thread busy in another memo borrow cannot be here: borrows do not span calls.
        MEMO.with(|m| {
            if let Ok(mut m) = m.try_borrow_mut() {
                for e in m.iter_mut() {
                    if matches!(e, Some((of, _, _)) if *of == id) {
                        *e = None;
                    }
                }
            }
        })
    };
    clear();
    rayon::spawn_broadcast(move |_| clear());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_chunks_along_every_axis_take_different_slots() {
        // 4 x 4 chunks per slice: `index % 16` put (i, j, k) and (i, j, k + 1) together.
        let index = |i: usize, j: usize, k: usize| i + 4 * (j + 4 * k);
        for slots in [16, MAX_SLOTS] {
            for k in 0..3 {
                let a = slot_of(index(1, 2, k), slots);
                for n in [index(2, 2, k), index(1, 3, k), index(1, 2, k + 1)] {
                    assert_ne!(a, slot_of(n, slots), "slots {slots}, k {k}");
                }
            }
        }
        assert!((0..10_000).all(|i| slot_of(i, 7) < 7));
    }

    #[test]
    fn large_bricks_get_fewer_slots() {
        assert_eq!(slots_for(1 << 40, 1 << 10, 2), MAX_SLOTS);
        assert_eq!(slots_for(1 << 30, 8 << 20, 16), 8);
        assert_eq!(slots_for(0, 8 << 20, 16), MIN_SLOTS);
    }
}
