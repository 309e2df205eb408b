//! Value histograms, used by `volux info` and by the automatic default transfer function.
use crate::grid::{Grid, Scalar};
use crate::with_samples;
use rayon::prelude::*;

/// The bins of the histogram a store records beside its range (a chunk source's
/// `value_histogram`), as many as the transfer-function presets are fitted on.
pub const STORED_BINS: usize = 256;

/// A histogram of `counts.len()` equal bins over `[min, max]`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub min: f64,
    /// Upper edge of the last bin.
    pub max: f64,
    /// Count per bin.
    pub counts: Vec<u64>,
}

impl Histogram {
    /// Histogram of arbitrary values over `range` with `bins` bins.
    pub fn from_values<T: Scalar>(values: &[T], range: [f64; 2], bins: usize) -> Self {
        let bins = bins.max(1);
        let (lo, hi) = (range[0], range[1]);
        let scale = if hi > lo {
            bins as f64 / (hi - lo)
        } else {
            0.0
        };
        let counts = values
            .par_chunks(1 << 16)
            .map(|c| {
                let mut h = vec![0u64; bins];
                for v in c {
                    let b = ((v.to_f32() as f64 - lo) * scale) as isize;
                    h[b.clamp(0, bins as isize - 1) as usize] += 1;
                }
                h
            })
            .reduce(
                || vec![0u64; bins],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        Self {
            min: lo,
            max: hi,
            counts,
        }
    }

    /// Histogram of a grid's values.
    pub fn of_grid(grid: &Grid, bins: usize) -> Self {
        with_samples!(grid.samples(), |s| Self::from_values(s, grid.range(), bins))
    }

    /// Total count.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Value below which a fraction `q` (0..1) of the samples lie (bin upper edge).
    pub fn quantile(&self, q: f64) -> f64 {
        let target = (q.clamp(0.0, 1.0) * self.total() as f64).ceil() as u64;
        let width = (self.max - self.min) / self.counts.len() as f64;
        let mut acc = 0;
        for (i, c) in self.counts.iter().enumerate() {
            acc += c;
            if acc >= target.max(1) {
                return self.min + width * (i + 1) as f64;
            }
        }
        self.max
    }

    /// Centre value of the most populated bin.
    pub fn mode(&self) -> f64 {
        let (i, _) = self
            .counts
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| **c)
            .unwrap_or((0, &0));
        let width = (self.max - self.min) / self.counts.len() as f64;
        self.min + width * (i as f64 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn counts_and_quantiles() {
        let v: Vec<u8> = (0..100).collect();
        let h = Histogram::from_values(&v, [0.0, 100.0], 10);
        assert_eq!(h.counts, vec![10; 10]);
        assert!((h.quantile(0.5) - 50.0).abs() < 1e-9);
        assert_eq!(h.total(), 100);
    }
}
