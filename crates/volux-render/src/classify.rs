//! Classification: a transfer function tabulated for fast lookup.
//!
//! The table samples the resolved [`TransferFunction`] at `N` evenly spaced values over a
//! domain covering the data range and every control point; lookups interpolate linearly
//! between entries, so a piecewise-linear TF whose breakpoints fall on entries is reproduced
//! exactly and others within `O((domain / N)^2)`.
use volux_core::TransferFunction;

/// A classified sample: linear RGB colour and extinction per world unit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Classified {
    /// Linear RGB emission colour.
    pub rgb: [f32; 3],
    /// Extinction coefficient per world unit.
    pub tau: f32,
}

/// A transfer function tabulated over a value domain.
#[derive(Clone, Debug)]
pub struct ClassifyTable {
    entries: Vec<Classified>,
    /// `opaque_prefix[i]`: number of entries before `i` with non-zero extinction.
    opaque_prefix: Vec<u32>,
    lo: f32,
    scale: f32,
}

impl ClassifyTable {
    /// Default number of entries.
    pub const DEFAULT_SIZE: usize = 4096;

    /// Tabulates `tf` (resolved on `range`) with `size` entries.
    pub fn new(tf: &TransferFunction, range: [f64; 2], size: usize) -> Self {
        let tf = tf.resolved(range);
        let bp = tf.breakpoints();
        let lo = range[0].min(bp.first().copied().unwrap_or(range[0]));
        let hi = range[1].max(bp.last().copied().unwrap_or(range[1]));
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let size = size.max(2);
        let entries: Vec<Classified> = (0..size)
            .map(|i| {
                let s = lo + (hi - lo) * i as f64 / (size - 1) as f64;
                let c = tf.color_at(s);
                Classified {
                    rgb: [c[0] as f32, c[1] as f32, c[2] as f32],
                    tau: tf.tau_per_world(s) as f32,
                }
            })
            .collect();
        let mut opaque_prefix = Vec::with_capacity(size + 1);
        opaque_prefix.push(0u32);
        for e in entries.iter() {
            let e: &Classified = e;
            let last = *opaque_prefix.last().unwrap_or(&0);
            opaque_prefix.push(last + u32::from(e.tau > 0.0));
        }
        Self {
            entries,
            opaque_prefix,
            lo: lo as f32,
            scale: ((size - 1) as f64 / (hi - lo)) as f32,
        }
    }

    /// Whether the extinction is zero for every value in `[lo, hi]` (including the table
    /// entries that lookups in that range interpolate from).
    pub fn is_transparent(&self, lo: f32, hi: f32) -> bool {
        let last = (self.entries.len() - 1) as f32;
        let a = ((lo - self.lo) * self.scale).clamp(0.0, last).floor() as usize;
        let b = ((hi - self.lo) * self.scale).clamp(0.0, last).ceil() as usize;
        self.opaque_prefix[b + 1] == self.opaque_prefix[a]
    }

    /// Colour and extinction at value `s` (clamped to the table's domain).
    #[inline(always)]
    pub fn lookup(&self, s: f32) -> Classified {
        let last = (self.entries.len() - 1) as f32;
        let x = (s - self.lo) * self.scale;
        // Selects rather than clamp (NaN goes to 0), and the floor without a saturating cast
        // for tables under 2^22 entries (see `floor_small`).
        let x = if x > 0.0 { x } else { 0.0 };
        let x = if x < last { x } else { last };
        let i = if last < crate::sampling::FLOOR_SMALL_LIMIT {
            crate::sampling::floor_small(x) as usize
        } else {
            x as usize
        };
        let i = i.min(self.entries.len() - 2);
        let f = x - i as f32;
        let (a, b) = (self.entries[i], self.entries[i + 1]);
        let l = |u: f32, v: f32| u + (v - u) * f;
        Classified {
            rgb: [
                l(a.rgb[0], b.rgb[0]),
                l(a.rgb[1], b.rgb[1]),
                l(a.rgb[2], b.rgb[2]),
            ],
            tau: l(a.tau, b.tau),
        }
    }
}

impl ClassifyTable {
    /// The table for a fixed Riemann step `h` (world units): per entry the premultiplied
    /// colour and opacity `1 - exp(-tau h)` of one slab, so the hot loop needs no `exp`.
    pub fn for_step(&self, h: f32) -> LaneTable {
        self.resampled(|c| {
            let a = 1.0 - (-c.tau * h).exp();
            [c.rgb[0] * a, c.rgb[1] * a, c.rgb[2] * a, a]
        })
    }

    /// The table itself (colour and extinction, `[r, g, b, tau]` per entry) for lane-wise
    /// lookups.
    pub fn for_lanes(&self) -> LaneTable {
        self.resampled(|c| [c.rgb[0], c.rgb[1], c.rgb[2], c.tau])
    }

    /// `entry` of the classification at each of the [`LANE_TABLE_SIZE`] entries of a
    /// [`LaneTable`] over the same domain.
    fn resampled(&self, entry: impl Fn(Classified) -> [f32; 4]) -> LaneTable {
        let n = LANE_TABLE_SIZE;
        let last = (self.entries.len() - 1) as f32;
        let mut entries: Vec<[f32; 4]> = (0..n)
            .map(|k| {
                entry(if self.entries.len() == n {
                    self.entries[k]
                } else {
                    self.lookup(self.lo + k as f32 * last / ((n - 1) as f32 * self.scale))
                })
            })
            .collect();
        entries.push(entries[n - 1]);
        LaneTable {
            entries: entries
                .into_boxed_slice()
                .try_into()
                .unwrap_or_else(|_| Box::new([[0.0; 4]; LANE_TABLE_SIZE + 1])),
            lo: self.lo,
            scale: self.scale * (n - 1) as f32 / last,
        }
    }
}

/// Entries of a [`LaneTable`]: a power of two, so that masked indices need no bounds check.
pub const LANE_TABLE_SIZE: usize = 4096;

/// Four channels per value at [`LANE_TABLE_SIZE`] values over the classification table's
/// domain, lookups interpolating linearly between entries, for lane-wise classification:
/// the premultiplied colour and opacity of one fixed-length slab ([`ClassifyTable::for_step`])
/// or colour and extinction ([`ClassifyTable::for_lanes`]).
#[derive(Clone, Debug)]
pub struct LaneTable {
    /// The entries and a copy of the last one after them (never interpolated towards: the
    /// lookups' entry `i` is at most `LANE_TABLE_SIZE - 2`), so that a masked `i` and `i + 1`
    /// need no bounds check and share one address.
    entries: Box<[[f32; 4]; LANE_TABLE_SIZE + 1]>,
    lo: f32,
    scale: f32,
}

impl LaneTable {
    /// The four channels at value `s`.
    #[inline]
    pub fn lookup(&self, s: f32) -> [f32; 4] {
        let (i, f) = self.position(s);
        self.at(i, f)
    }

    /// The entry below `s` and the fraction towards the next, clamped to the domain (a NaN
    /// value reads entry 0). Branch-free, so lanes of values compute it together.
    #[inline(always)]
    pub fn position(&self, s: f32) -> (u32, f32) {
        const LAST: f32 = (LANE_TABLE_SIZE - 1) as f32;
        let x = (s - self.lo) * self.scale;
        // Selects rather than max/min: one instruction each, NaN going to 0.
        let x = if x > 0.0 { x } else { 0.0 };
        let x = if x < LAST { x } else { LAST };
        // The floor without a cast (see `floor_small`); `x <= LAST`, so the entry is clamped
        // by subtracting one where it passes the last pair.
        let i = crate::sampling::floor_small(x);
        let i = i - i32::from(i > LANE_TABLE_SIZE as i32 - 2);
        (i as u32, x - i as f32)
    }

    /// The entries, with the copy of the last one after them (for a GPU table: a backend
    /// interpolates them as [`LaneTable::lookup`] does).
    pub fn entries(&self) -> &[[f32; 4]] {
        &self.entries[..]
    }

    /// The domain as `(lo, scale)`: value `s` sits at entry position `(s - lo) scale`.
    pub fn domain(&self) -> (f32, f32) {
        (self.lo, self.scale)
    }

    /// The entries `i` and `i + 1` interpolated at fraction `f`.
    #[inline(always)]
    pub fn at(&self, i: u32, f: f32) -> [f32; 4] {
        let i = i as usize & (LANE_TABLE_SIZE - 1);
        let (a, b) = (self.entries[i], self.entries[i + 1]);
        [
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
            a[3] + (b[3] - a[3]) * f,
        ]
    }
}

impl LaneTable {
    /// Bounds on the number of `breakpoints` (sorted scalar values) at or below and strictly
    /// below each value, per entry: for the hidden-peak test of adaptive integration, read with
    /// the entry index that classification already computes.
    pub fn breakpoint_ranks(&self, breakpoints: &[f64]) -> BreakpointRanks {
        // Entry k's value, and half an entry of margin for the f32 rounding of `position`.
        let x = |k: usize| f64::from(self.lo) + k as f64 / f64::from(self.scale);
        let margin = 0.5 / f64::from(self.scale);
        let below = |v: f64| breakpoints.iter().filter(|&&b| b < v).count() as f32;
        let at_or_below = |v: f64| breakpoints.iter().filter(|&&b| b <= v).count() as f32;
        let ranks: Vec<[f32; 2]> = (0..LANE_TABLE_SIZE)
            .map(|k| match k {
                // Values below the domain clamp to the first entry, above it to the last pair.
                0 => [0.0, at_or_below(x(1) + margin)],
                k if k >= LANE_TABLE_SIZE - 2 => [below(x(k) - margin), breakpoints.len() as f32],
                k => [below(x(k) - margin), at_or_below(x(k + 1) + margin)],
            })
            .collect();
        BreakpointRanks {
            ranks: ranks
                .into_boxed_slice()
                .try_into()
                .unwrap_or_else(|_| Box::new([[0.0; 2]; LANE_TABLE_SIZE])),
        }
    }
}

/// Per [`LaneTable`] entry `i`, a lower bound of the number of breakpoints at or below any
/// value in `[x_i, x_(i+1)]` (those below `x_i`, less half an entry for rounding) and an upper
/// bound of the number strictly below it (those at or below `x_(i+1)`, plus half an entry).
/// Bounds rather than counts: a test built on them may flag a step whose values come within
/// two entries of a breakpoint, and never misses one.
#[derive(Clone, Debug)]
pub struct BreakpointRanks {
    ranks: Box<[[f32; 2]; LANE_TABLE_SIZE]>,
}

impl BreakpointRanks {
    /// The bounds `[at or below, below]` for a value at entry `i` (from
    /// [`LaneTable::position`]).
    #[inline(always)]
    pub fn at(&self, i: u32) -> [f32; 2] {
        self.ranks[i as usize & (LANE_TABLE_SIZE - 1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_table_is_the_slab_opacity_of_each_entry() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0,0,0,0],[100,1,0.5,0.25]], "extinction": [[0,0],[40,0.2],[100,1]]}"#,
        )
        .unwrap();
        let h = 0.7f32;
        for size in [ClassifyTable::DEFAULT_SIZE, 1001] {
            let t = ClassifyTable::new(&tf, [0.0, 100.0], size);
            let st = t.for_step(h);
            for s in [0.0f32, 13.7, 40.0, 77.3, 99.99, 100.0] {
                let c = t.lookup(s);
                let a = 1.0 - (-c.tau * h).exp();
                let e = st.lookup(s);
                let want = [c.rgb[0] * a, c.rgb[1] * a, c.rgb[2] * a, a];
                for k in 0..4 {
                    // Both interpolate linearly between entries; premultiplication and the
                    // exponential make them differ to second order in the entry spacing.
                    assert!((e[k] - want[k]).abs() < 1e-4, "size {size} s {s} k {k}");
                }
            }
            // Out of range values clamp; NaN reads the first entry.
            assert_eq!(st.lookup(-50.0), st.lookup(0.0));
            assert_eq!(st.lookup(500.0), st.lookup(100.0));
            assert_eq!(st.lookup(f32::NAN), st.lookup(0.0));
        }
    }

    /// The rank bounds hold for every value, and are exact within the domain away from the
    /// breakpoints.
    #[test]
    fn breakpoint_ranks_bound_the_counts() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0,0,0,0],[100,1,0.5,0.25]], "extinction": [[0,0],[40,0.2],[41,3],[42.5,0],[100,1]]}"#,
        )
        .unwrap();
        let bp = tf.resolved([0.0, 100.0]).breakpoints();
        let table = ClassifyTable::new(&tf, [0.0, 100.0], ClassifyTable::DEFAULT_SIZE).for_lanes();
        let ranks = table.breakpoint_ranks(&bp);
        let entry = 100.0 / (LANE_TABLE_SIZE - 1) as f64;
        let mut exact = 0;
        for i in 0..=20_000 {
            let v = -5.0 + 110.0 * f64::from(i) / 20_000.0;
            let [at_or_below, below] = ranks.at(table.position(v as f32).0);
            let le = bp.iter().filter(|&&b| b <= v).count() as f32;
            let lt = bp.iter().filter(|&&b| b < v).count() as f32;
            assert!(
                at_or_below <= le && below >= lt,
                "{v}: {at_or_below} {below} {le} {lt}"
            );
            let inside = (0.0..=100.0).contains(&v);
            if inside && bp.iter().all(|b| (b - v).abs() > 3.0 * entry) {
                assert_eq!((at_or_below, below), (le, lt), "{v}");
                exact += 1;
            }
        }
        assert!(exact > 17_000, "{exact}");
    }

    #[test]
    fn table_matches_tf() {
        let tf = TransferFunction::from_json(
            r#"{"color": [[0,0,0,0],[100,1,0.5,0.25]], "extinction": [[0,0],[40,0.2],[100,1]]}"#,
        )
        .unwrap();
        let t = ClassifyTable::new(&tf, [0.0, 100.0], 1001);
        for s in [0.0f32, 13.7, 40.0, 77.3, 100.0, 150.0, -3.0] {
            let c = t.lookup(s);
            let d = s.clamp(0.0, 100.0) as f64;
            assert!((c.tau as f64 - tf.tau_per_world(d)).abs() < 1e-4, "{s}");
            assert!((c.rgb[1] as f64 - tf.color_at(d)[1]).abs() < 1e-4, "{s}");
        }
    }
}
