//! The brick cache: the chunks of one level resident in memory, within a byte budget, evicted
//! least recently used first. A miss reads and decodes its chunk without the lock (only the
//! bookkeeping is locked); a chunk is read by one reader at a time: another reader that misses
//! it meanwhile waits for that read instead of decoding it again (the prefetcher and the render
//! threads reach the same chunks), and the prefetcher skips it.
use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};

use volux_core::bricked::{ChunkLayout, ChunkSource};
use volux_core::grid::{Samples, Scalar};

use crate::raycast::cell_blocks::CellBlocks;
/// The cell blocks of the in-core renderer's bricked copy: cells per side, samples per
/// side, samples per cell block, a cell's corners' offsets and reach.
pub(crate) use crate::raycast::cell_blocks::{BLOCK, CELLS, REACH, SIDE};

/// What local coordinate `l` along axis `a` adds to the offset of the first sample of cell
/// `l` in a brick of a level whose chunks have `shape` samples. Bricks hold their samples in
/// cell blocks of `CELLS`³ cells with their far faces (`SIDE`³ samples, x fastest;
/// cell blocks x fastest), the layout of the in-core renderer's bricked copy: a cell's eight
/// corners lie at the fixed displacements `CORNERS` from its first sample, within a few
/// kilobytes. The far faces of the chunk's last cell blocks belong to the next chunk and are
/// not filled: the cells there are sampled corner by corner.
#[inline]
pub fn axis_offset(shape: [usize; 3], a: usize, l: usize) -> usize {
    let m = shape.map(|c| c.div_ceil(CELLS).max(1));
    let stride = [BLOCK, m[0] * BLOCK, m[0] * m[1] * BLOCK][a];
    let step = [1, SIDE, SIDE * SIDE][a];
    (l / CELLS) * stride + (l % CELLS) * step
}

/// Bytes of a brick of a level whose chunks have `shape` samples.
pub fn brick_bytes(shape: [usize; 3]) -> u64 {
    let m = shape.map(|c| c.div_ceil(CELLS).max(1) as u64);
    m.iter().product::<u64>() * (BLOCK * std::mem::size_of::<f32>()) as u64
}

/// One resident chunk: its samples as f32 (the renderer's sample type), and where it sits.
/// Every brick of a level has the same layout (cell blocks: `axis_offset`), so a sample's place in its
/// brick depends only on its coordinates: the field finds it from per-axis tables.
#[derive(Debug)]
pub struct Brick {
    /// The chunk's first sample (grid coordinates).
    pub lo: [usize; 3],
    /// Samples per axis (the chunk's shape clipped to the grid).
    pub size: [usize; 3],
    /// The level's chunk shape, which the layout follows.
    pub shape: [usize; 3],
    /// The samples in cell blocks (`axis_offset` gives the layout).
    pub values: Vec<f32>,
    /// The smallest and largest sample (NaN ignored; infinite when none is finite).
    pub range: [f32; 2],
}

impl Brick {
    /// The brick of chunk `c` of `layout` from its samples `s`, checked against the chunk's
    /// size.
    /// `spare`: an evicted brick's buffer to fill (used when it has the right length).
    fn new(
        layout: &ChunkLayout,
        c: [usize; 3],
        s: &Samples,
        spare: Option<Vec<f32>>,
    ) -> Result<Self, String> {
        let (lo, size) = layout.chunk_extent(c);
        let expected: usize = size.iter().product();
        if s.len() != expected || expected == 0 {
            return Err(format!(
                "chunk {c:?} holds {} samples where its shape {size:?} needs {expected}",
                s.len()
            ));
        }
        let shape = layout.chunk;
        let m = shape.map(|c| c.div_ceil(CELLS).max(1));
        let len = m.iter().product::<usize>() * BLOCK;
        // Every sample of the buffer is written below.
        let mut values = match spare {
            Some(v) if v.len() == len => v,
            _ => vec![0.0f32; len],
        };
        let mut range = [f32::INFINITY, f32::NEG_INFINITY];
        volux_core::with_samples!(s, |v| {
            for x in v.iter() {
                let x = x.to_f32();
                if x.is_finite() {
                    range = [range[0].min(x), range[1].max(x)];
                }
            }
            // Each cell block's samples; beyond the chunk's last sample the last is
            // repeated (read only along an axis with one sample, as the in-core sampler does).
            for (b, micro) in values.chunks_exact_mut(BLOCK).enumerate() {
                let o = [b % m[0], b / m[0] % m[1], b / m[0] / m[1]].map(|i| i * CELLS);
                for (r, row) in micro.chunks_exact_mut(SIDE).enumerate() {
                    let y = (o[1] + r % SIDE).min(size[1] - 1);
                    let z = (o[2] + r / SIDE).min(size[2] - 1);
                    let at = size[0] * (y + size[1] * z);
                    for (u, d) in row.iter_mut().enumerate() {
                        *d = v[at + (o[0] + u).min(size[0] - 1)].to_f32();
                    }
                }
            }
        });
        Ok(Self {
            lo,
            size,
            shape,
            values,
            range,
        })
    }

    /// Bytes the brick holds.
    pub fn bytes(&self) -> u64 {
        (self.values.len() * std::mem::size_of::<f32>()) as u64
    }

    /// The sample at grid coordinates (`i`, `j`, `k`), which must lie in the brick.
    pub fn at(&self, i: usize, j: usize, k: usize) -> f32 {
        let l = [i - self.lo[0], j - self.lo[1], k - self.lo[2]];
        let o: usize = (0..3).map(|a| axis_offset(self.shape, a, l[a])).sum();
        self.values[o]
    }
}

/// What a cache did: hits, misses (chunks read), bytes decoded and evictions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheStats {
    /// Lookups answered from memory.
    pub hits: u64,
    /// Chunks read from the source.
    pub misses: u64,
    /// Bytes of f32 samples decoded from those chunks.
    pub bytes_read: u64,
    /// Chunks evicted to stay within the budget.
    pub evictions: u64,
    /// Chunks read again after they were evicted (part of `misses`): a budget too small for
    /// what the views need thrashes.
    pub rereads: u64,
    /// The most bytes resident at once.
    pub peak_bytes: u64,
}

impl CacheStats {
    /// Hits over lookups (1 when there was none).
    pub fn hit_rate(&self) -> f64 {
        let lookups = self.hits + self.misses;
        if lookups == 0 {
            1.0
        } else {
            self.hits as f64 / lookups as f64
        }
    }
}

/// A brick's key in the pool: (level, chunk index), or (level, [`WHOLE`]) for a level's
/// whole copy.
type Key = (usize, usize);

/// The most sample buffers of evicted bricks kept for reuse. A brick read takes one instead
/// of allocating its own, so that a frame that evicts as it reads (a level larger than the
/// budget) does not free and allocate a brick's megabytes per chunk: measured with glibc,
/// whose threshold for giving large blocks their own mapping rises to the size of the
/// largest one freed, that churn left freed bricks in the heap and took the peak RSS of a
/// 1 GiB budget to 1.9 GB.
const SPARES: usize = 4;

/// The chunk index in the key of a level's whole copy.
const WHOLE: usize = usize::MAX;

/// Where a render finds the bricks of a level ([`BrickCache::frame_bricks`]).
pub(crate) enum FrameBricks {
    /// The level's whole bricked copy, the in-core renderer's layout.
    Whole(Arc<CellBlocks>),
    /// A table of the level's bricks by chunk index, the missing ones left for the render's
    /// first reader.
    Table(Vec<OnceLock<Arc<Brick>>>),
}

/// The bookkeeping under the lock: resident bricks of every level sharing the pool, with
/// their last use, in use order.
#[derive(Default)]
struct Resident {
    bricks: HashMap<Key, (Arc<Brick>, u64)>,
    /// Sample buffers of evicted bricks, reused by the next reads.
    spares: Vec<Vec<f32>>,
    /// Chunks being read.
    reading: HashSet<Key>,
    /// Whole copies of levels, by level, with their last use.
    wholes: HashMap<usize, (Arc<CellBlocks>, u64)>,
    by_use: BTreeMap<u64, Key>,
    bytes: u64,
    /// Bytes resident per level.
    level_bytes: HashMap<usize, u64>,
    clock: u64,
}

impl Resident {
    /// The resident brick `key`, marked as used now.
    fn touch(&mut self, key: Key) -> Option<Arc<Brick>> {
        self.clock += 1;
        let now = self.clock;
        let (brick, used) = self.bricks.get_mut(&key)?;
        let (brick, old) = (brick.clone(), std::mem::replace(used, now));
        self.by_use.remove(&old);
        self.by_use.insert(now, key);
        Some(brick)
    }

    /// The whole copy of level `level`, marked as used now.
    fn touch_whole(&mut self, level: usize) -> Option<Arc<CellBlocks>> {
        self.clock += 1;
        let now = self.clock;
        let (whole, used) = self.wholes.get_mut(&level)?;
        let (whole, old) = (whole.clone(), std::mem::replace(used, now));
        self.by_use.remove(&old);
        self.by_use.insert(now, (level, WHOLE));
        Some(whole)
    }

    /// Makes `whole` level `level`'s copy in place of its bricks.
    fn replace_bricks(&mut self, level: usize, whole: Arc<CellBlocks>) {
        let keys: Vec<Key> = self
            .bricks
            .keys()
            .filter(|k| k.0 == level)
            .copied()
            .collect();
        for key in keys {
            if let Some((b, used)) = self.bricks.remove(&key) {
                self.by_use.remove(&used);
                self.account(level, b.bytes(), false);
            }
        }
        self.clock += 1;
        let now = self.clock;
        self.account(level, whole.bytes(), true);
        self.wholes.insert(level, (whole, now));
        self.by_use.insert(now, (level, WHOLE));
    }

    /// Evicts the least recently used brick or copy; its bytes, or `None` when nothing
    /// but the last one is left.
    fn evict_one(&mut self) -> Option<u64> {
        if self.bricks.len() + self.wholes.len() <= 1 {
            return None;
        }
        let (_, victim) = self.by_use.pop_first()?;
        let bytes = if victim.1 == WHOLE {
            self.wholes.remove(&victim.0).map(|(w, _)| w.bytes())
        } else {
            self.bricks.remove(&victim).map(|(b, _)| self.recycle(b))
        }?;
        self.account(victim.0, bytes, false);
        Some(bytes)
    }

    /// Keeps the samples of an evicted brick that no reader holds any more for the next
    /// brick read (at most [`SPARES`] of them), and returns the brick's bytes.
    fn recycle(&mut self, brick: Arc<Brick>) -> u64 {
        let bytes = brick.bytes();
        if self.spares.len() < SPARES {
            if let Ok(b) = Arc::try_unwrap(brick) {
                self.spares.push(b.values);
            }
        }
        bytes
    }

    /// Adds or takes away `bytes` of level `level`.
    fn account(&mut self, level: usize, bytes: u64, add: bool) {
        let l = self.level_bytes.entry(level).or_default();
        if add {
            self.bytes += bytes;
            *l += bytes;
        } else {
            self.bytes -= bytes;
            *l -= bytes;
        }
    }
}

/// The memory the caches of a pyramid's levels share: one budget and one least-recently-used
/// order over all their bricks (the viewer renders coarse levels, then finer ones: the
/// coarse bricks are evicted first once the finer ones need the room).
struct Pool {
    budget: u64,
    resident: Mutex<Resident>,
    /// Signalled when a read ends (its chunk made resident, or failed).
    read_done: Condvar,
    peak: AtomicU64,
}

impl Pool {
    fn new(budget: u64) -> Arc<Self> {
        Arc::new(Self {
            budget,
            resident: Mutex::new(Resident::default()),
            read_done: Condvar::new(),
            peak: AtomicU64::new(0),
        })
    }

    fn lock(&self) -> MutexGuard<'_, Resident> {
        // A panic while holding the lock leaves consistent maps (no update is half done).
        self.resident.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// A chunk being read: marked in the pool while it lives, unmarked (and the waiting readers
/// woken) when it is dropped, whether the read succeeded, failed or panicked.
struct Reading<'a> {
    pool: &'a Pool,
    key: Key,
}

impl Drop for Reading<'_> {
    fn drop(&mut self) {
        self.pool.lock().reading.remove(&self.key);
        self.pool.read_done.notify_all();
    }
}

/// What a lookup found: the resident brick, or the right to read the chunk.
enum Lookup<'a> {
    Resident(Arc<Brick>),
    Read(Reading<'a>),
}

/// The resident chunks of one level, within a byte budget that it may share with the other
/// levels of its pyramid ([`BrickCache::shared`]); at least one brick is always kept,
/// whatever the budget (a brick in use is held by its reader).
pub struct BrickCache {
    source: Arc<dyn ChunkSource>,
    level: usize,
    pool: Arc<Pool>,
    hits: AtomicU64,
    misses: AtomicU64,
    bytes_read: AtomicU64,
    evictions: AtomicU64,
    rereads: AtomicU64,
    /// One bit per chunk: read at least once.
    ever_read: Vec<AtomicU64>,
}

impl BrickCache {
    /// A cache of `source`'s chunks within `budget` bytes.
    pub fn new(source: Arc<dyn ChunkSource>, budget: u64) -> Self {
        Self::in_pool(source, 0, Pool::new(budget))
    }

    /// Caches of each of `levels` sharing `budget` bytes and one eviction order.
    pub fn shared(levels: &[Arc<dyn ChunkSource>], budget: u64) -> Vec<Self> {
        let pool = Pool::new(budget);
        levels
            .iter()
            .enumerate()
            .map(|(l, s)| Self::in_pool(s.clone(), l, pool.clone()))
            .collect()
    }

    fn in_pool(source: Arc<dyn ChunkSource>, level: usize, pool: Arc<Pool>) -> Self {
        let words = source.layout().chunk_count().div_ceil(64);
        Self {
            source,
            level,
            pool,
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            bytes_read: AtomicU64::new(0),
            evictions: AtomicU64::new(0),
            rereads: AtomicU64::new(0),
            ever_read: (0..words).map(|_| AtomicU64::new(0)).collect(),
        }
    }

    /// Marks chunk `index` as read; whether it had been read before.
    fn read_before(&self, index: usize) -> bool {
        let bit = 1u64 << (index % 64);
        self.ever_read
            .get(index / 64)
            .is_some_and(|w| w.fetch_or(bit, Ordering::Relaxed) & bit != 0)
    }

    /// The level's geometry.
    pub fn layout(&self) -> &ChunkLayout {
        self.source.layout()
    }

    /// The level read chunk by chunk.
    pub fn source(&self) -> &Arc<dyn ChunkSource> {
        &self.source
    }

    /// The byte budget (shared with the pyramid's other levels when made by
    /// [`BrickCache::shared`]).
    pub fn budget(&self) -> u64 {
        self.pool.budget
    }

    /// The figures so far: this level's hits, misses, bytes read and the evictions its reads
    /// caused; the most bytes resident at once in the whole pool.
    pub fn stats(&self) -> CacheStats {
        CacheStats {
            hits: self.hits.load(Ordering::Relaxed),
            misses: self.misses.load(Ordering::Relaxed),
            bytes_read: self.bytes_read.load(Ordering::Relaxed),
            evictions: self.evictions.load(Ordering::Relaxed),
            rereads: self.rereads.load(Ordering::Relaxed),
            peak_bytes: self.pool.peak.load(Ordering::Relaxed),
        }
    }

    /// Bytes of this level resident now.
    pub fn resident_bytes(&self) -> u64 {
        let r = self.pool.lock();
        r.level_bytes.get(&self.level).copied().unwrap_or(0)
    }

    /// Whether chunk `c` is resident, as a brick or in the level's whole copy (its last use
    /// left as it was).
    pub fn is_resident(&self, c: [usize; 3]) -> bool {
        let key = (self.level, self.layout().chunk_index(c));
        let r = self.pool.lock();
        r.bricks.contains_key(&key) || r.wholes.contains_key(&self.level)
    }

    /// Bytes resident now in the whole pool.
    pub fn pool_bytes(&self) -> u64 {
        self.pool.lock().bytes
    }

    /// Where a render finds the level's bricks, when the whole level fits beside what the
    /// pool holds (so that reading the missing ones during the render evicts nothing and
    /// the table's references keep no evicted brick alive); `None` when it does not fit
    /// (the render then goes through per-thread memos).
    ///
    /// - The level's whole copy when it is resident.
    /// - Else, when every brick of the level is resident and the copy fits beside them, the
    ///   copy is made from them (the in-core renderer's layout: one offset per sample, no
    ///   brick to find, no far faces to patch; a frame of a warm level then costs what an
    ///   in-core frame does) and replaces them in the pool.
    /// - Else a table of the level's bricks by chunk index: the resident ones filled in
    ///   (and marked as used), the others left for the render's first reader.
    ///
    /// Each chunk found resident counts as one hit.
    pub(crate) fn frame_bricks(&self) -> Option<FrameBricks> {
        let layout = self.layout();
        let count = layout.chunk_count();
        let whole_bytes = CellBlocks::bytes_for(layout.dims);
        let budget = self.pool.budget;
        if (count as u64).saturating_mul(brick_bytes(layout.chunk)) > budget {
            return None;
        }
        let mut r = self.pool.lock();
        if let Some(whole) = r.touch_whole(self.level) {
            self.hits.fetch_add(count as u64, Ordering::Relaxed);
            return Some(FrameBricks::Whole(whole));
        }
        let held = (0..count)
            .filter(|&i| r.bricks.contains_key(&(self.level, i)))
            .count();
        let need = ((count - held) as u64).saturating_mul(brick_bytes(layout.chunk));
        if r.bytes.saturating_add(need) > budget {
            return None;
        }
        let table: Vec<OnceLock<Arc<Brick>>> = (0..count)
            .map(|i| {
                let slot = OnceLock::new();
                if let Some(b) = r.touch((self.level, i)) {
                    let _ = slot.set(b);
                }
                slot
            })
            .collect();
        self.hits.fetch_add(held as u64, Ordering::Relaxed);
        let room = budget.saturating_sub(r.bytes);
        drop(r);
        if held < count || whole_bytes > room {
            return Some(FrameBricks::Table(table));
        }
        match self.whole_copy(&table, room) {
            Some(whole) => {
                let whole = Arc::new(whole);
                self.pool.lock().replace_bricks(self.level, whole.clone());
                Some(FrameBricks::Whole(whole))
            }
            None => Some(FrameBricks::Table(table)),
        }
    }

    /// The level's whole copy from `table`, which holds every brick (`None` if it would
    /// take more than `room` bytes or the in-core layout cannot address it).
    fn whole_copy(&self, table: &[OnceLock<Arc<Brick>>], room: u64) -> Option<CellBlocks> {
        let layout = self.layout();
        let (chunk, counts) = (layout.chunk, layout.chunks_per_axis());
        let stride = [1, counts[0], counts[0] * counts[1]];
        // Per axis and sample: what it adds to its chunk's index and to its brick offset.
        let axes: [Vec<(usize, usize)>; 3] = std::array::from_fn(|a| {
            (0..layout.dims[a])
                .map(|i| {
                    let (c, l) = (i / chunk[a], i % chunk[a]);
                    (c * stride[a], axis_offset(chunk, a, l))
                })
                .collect()
        });
        let bricks: Vec<&Brick> = table
            .iter()
            .map(|slot| slot.get().map(|b| &**b))
            .collect::<Option<_>>()?;
        CellBlocks::build_from(layout.dims, room, |x, y, z| {
            let (a, b, c) = (axes[0][x], axes[1][y], axes[2][z]);
            bricks[a.0 + b.0 + c.0].values[a.1 + b.1 + c.1]
        })
    }

    /// The brick of chunk `c`, read from the source on a miss (the least recently used
    /// bricks of the pool are evicted to make room). Errors name the chunk.
    pub fn get(&self, c: [usize; 3]) -> Result<Arc<Brick>, String> {
        match self.lookup(c, true) {
            Some(Lookup::Resident(brick)) => Ok(brick),
            Some(Lookup::Read(reading)) => self.read(c, reading),
            // `lookup` waits for other readers when asked to: never here.
            None => Err(format!("chunk {c:?}: not read")),
        }
    }

    /// Reads chunk `c` ahead of the readers that will need it, unless it is resident or
    /// being read (then `Ok(false)`).
    pub(crate) fn prefetch(&self, c: [usize; 3]) -> Result<bool, String> {
        match self.lookup(c, false) {
            Some(Lookup::Read(reading)) => self.read(c, reading).map(|_| true),
            _ => Ok(false),
        }
    }

    /// The resident brick of chunk `c` (a hit), or the right to read it; while another
    /// reader reads it, waits for that read when `wait` (else `None`).
    fn lookup(&self, c: [usize; 3], wait: bool) -> Option<Lookup<'_>> {
        let key = (self.level, self.layout().chunk_index(c));
        let mut r = self.pool.lock();
        loop {
            if let Some(brick) = r.touch(key) {
                self.hits.fetch_add(1, Ordering::Relaxed);
                return Some(Lookup::Resident(brick));
            }
            if !r.reading.contains(&key) {
                r.reading.insert(key);
                return Some(Lookup::Read(Reading {
                    pool: &self.pool,
                    key,
                }));
            }
            if !wait {
                return None;
            }
            r = self
                .pool
                .read_done
                .wait(r)
                .unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Reads chunk `c`, which `reading` marks as being read, and makes it resident.
    fn read(&self, c: [usize; 3], reading: Reading<'_>) -> Result<Arc<Brick>, String> {
        let key = reading.key;
        let samples = self
            .source
            .read_chunk(c)
            .map_err(|e| format!("chunk {c:?}: {e}"))?;
        let spare = self.pool.lock().spares.pop();
        let brick = Arc::new(Brick::new(self.layout(), c, &samples, spare)?);
        drop(samples);
        self.misses.fetch_add(1, Ordering::Relaxed);
        if self.read_before(key.1) {
            self.rereads.fetch_add(1, Ordering::Relaxed);
        }
        self.bytes_read.fetch_add(brick.bytes(), Ordering::Relaxed);
        let brick = self.insert(key, brick);
        drop(reading);
        Ok(brick)
    }

    /// Makes `brick` resident as `key` (or returns the one another reader made resident
    /// meanwhile), evicting the pool's least recently used others beyond the budget.
    fn insert(&self, key: Key, brick: Arc<Brick>) -> Arc<Brick> {
        let mut r = self.pool.lock();
        if let Some(kept) = r.touch(key) {
            return kept;
        }
        r.clock += 1;
        let now = r.clock;
        r.account(key.0, brick.bytes(), true);
        r.bricks.insert(key, (brick.clone(), now));
        r.by_use.insert(now, key);
        while r.bytes > self.pool.budget && r.evict_one().is_some() {
            self.evictions.fetch_add(1, Ordering::Relaxed);
        }
        self.pool.peak.fetch_max(r.bytes, Ordering::Relaxed);
        brick
    }
}
