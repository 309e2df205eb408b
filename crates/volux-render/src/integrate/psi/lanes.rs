//! The fragment models of [`super`] on [`LANES`] fragments at a time, for rasterizers that
//! shade a run of fragments at once (Projected Tetrahedra shades each cell's fragments in a
//! tile together, seed `000` §4.3, seed `002` §4.3-§4.4).
//!
//! Every function is written as straight-line loops over `[f32; LANES]` arrays with no
//! data-dependent branch inside a lane, which LLVM turns into SIMD instructions; the only
//! scalar step is the gather of the ψ table's four nodes per lane. Lane `k` of a result is
//! what the scalar function gives for lane `k` of the inputs, to rounding: the same
//! formulas, with both sides of the scalar thin-cell branch computed and one selected.
use super::{clamp_or_lo, coords_of_depths, one_minus_psi_series, opacity, PsiTable, THIN};

/// Fragments per lane group.
pub const LANES: usize = 4;
// Lane groups are `glam::Vec4`s where a mask is wanted.
const _: () = assert!(LANES == 4);

/// One value per lane.
pub type Lanes = [f32; LANES];

/// `f(k)` for every lane `k`.
#[inline(always)]
pub fn lanes(mut f: impl FnMut(usize) -> f32) -> Lanes {
    let mut out = [0.0; LANES];
    for (k, v) in out.iter_mut().enumerate() {
        *v = f(k);
    }
    out
}

impl PsiTable {
    /// `1 - psi` of the table ([`PsiTable::psi_of_depths`]) for every lane's optical
    /// thicknesses `a` (front) and `b` (back): the same bilinear interpolation.
    #[inline(always)]
    fn one_minus_psi_lanes(&self, a: &Lanes, b: &Lanes) -> Lanes {
        let n = self.n;
        let last = (n - 1) as f32;
        let top = (n - 2) as i32;
        let mut row = [0i32; LANES];
        let mut col = [0i32; LANES];
        let mut fi = [0.0f32; LANES];
        let mut fj = [0.0f32; LANES];
        for k in 0..LANES {
            let (vf, vb) = coords_of_depths(a[k], b[k]);
            let (x, y) = (vf.clamp(0.0, 1.0) * last, vb.clamp(0.0, 1.0) * last);
            let (i, j) = ((x as i32).min(top), (y as i32).min(top));
            row[k] = i;
            col[k] = j;
            fi[k] = x - i as f32;
            fj[k] = y - j as f32;
        }
        // The gather: four nodes per lane.
        let t = &self.one_minus_psi;
        let mut e = [[0.0f32; LANES]; 4];
        for k in 0..LANES {
            let r0 = row[k] as usize * n + col[k] as usize;
            let (lo, hi) = (&t[r0..r0 + 2], &t[r0 + n..r0 + n + 2]);
            e[0][k] = lo[0];
            e[1][k] = lo[1];
            e[2][k] = hi[0];
            e[3][k] = hi[1];
        }
        lanes(|k| {
            let top = e[0][k] + (e[1][k] - e[0][k]) * fj[k];
            let bottom = e[2][k] + (e[3][k] - e[2][k]) * fj[k];
            top + (bottom - top) * fi[k]
        })
    }
}

/// `1 - exp(-d)` for `0 <= d < THIN / 2` by its Taylor series (the truncation, below
/// `d^5 / 720 < 1.3e-9` relative, is under f32 rounding): [`opacity`] without its range
/// reduction, for lane groups of thin segments only.
#[inline(always)]
fn opacity_thin(d: f32) -> f32 {
    d * (1.0 - d * (0.5 - d * (1.0 / 6.0 - d * (1.0 / 24.0 - d * (1.0 / 120.0)))))
}

/// [`super::psi_rgba`] for every lane: premultiplied RGBA (channel-major) of segments of
/// length `l` from classified front and back samples `[r, g, b, tau]` (channel-major).
/// Expects finite inputs and `l >= 0` (a lane with `l = 0` gives transparent black).
#[inline(always)]
pub fn psi_rgba_lanes(
    table: &PsiTable,
    front: &[Lanes; 4],
    back: &[Lanes; 4],
    l: &Lanes,
) -> [Lanes; 4] {
    let a = lanes(|k| (front[3][k] * l[k]).max(0.0));
    let b = lanes(|k| (back[3][k] * l[k]).max(0.0));
    let series = lanes(|k| one_minus_psi_series(a[k], b[k]));
    let thick = (glam::Vec4::from(a) + glam::Vec4::from(b))
        .cmpge(glam::Vec4::splat(THIN))
        .any();
    let (alpha, w) = if thick {
        let tabled = table.one_minus_psi_lanes(&a, &b);
        (
            lanes(|k| opacity(0.5 * (a[k] + b[k]))),
            lanes(|k| {
                if a[k] + b[k] < THIN {
                    series[k]
                } else {
                    tabled[k]
                }
            }),
        )
    } else {
        (lanes(|k| opacity_thin(0.5 * (a[k] + b[k]))), series)
    };
    // 1 - psi <= 1 - zeta: clamping keeps both weights non-negative despite table error.
    let w = lanes(|k| clamp_or_lo(w[k], 0.0, alpha[k]));
    let wb = lanes(|k| alpha[k] - w[k]);
    let c = |i: usize| lanes(|k| front[i][k] * w[k] + back[i][k] * wb[k]);
    [c(0), c(1), c(2), alpha]
}

/// [`super::average_rgba`] for every lane (channel-major inputs and result). Expects finite
/// inputs and `l >= 0`.
#[inline(always)]
pub fn average_rgba_lanes(front: &[Lanes; 4], back: &[Lanes; 4], l: &Lanes) -> [Lanes; 4] {
    let alpha = lanes(|k| opacity(0.5 * l[k] * (front[3][k] + back[3][k])));
    let c = |i: usize| lanes(|k| (front[i][k] + back[i][k]) * (0.5 * alpha[k]));
    [c(0), c(1), c(2), alpha]
}

#[cfg(test)]
mod tests {
    use super::super::{average_rgba, psi_rgba};
    use super::*;

    fn rnd(seed: &mut u64) -> f32 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Random samples `[r, g, b, tau]` and lengths spanning thin and thick cells.
    fn inputs(seed: &mut u64) -> ([Lanes; 4], [Lanes; 4], Lanes) {
        let mut sample = || {
            let tau = 10f32.powf(6.0 * rnd(seed) - 3.0) * f32::from(u8::from(rnd(seed) > 0.1));
            [rnd(seed), rnd(seed), rnd(seed), tau]
        };
        let (mut f, mut b) = ([[0.0; LANES]; 4], [[0.0; LANES]; 4]);
        for k in 0..LANES {
            let (x, y) = (sample(), sample());
            for c in 0..4 {
                f[c][k] = x[c];
                b[c][k] = y[c];
            }
        }
        let l =
            lanes(|_| 10f32.powf(4.0 * rnd(seed) - 3.0) * f32::from(u8::from(rnd(seed) > 0.05)));
        (f, b, l)
    }

    fn lane(v: &[Lanes; 4], k: usize) -> [f32; 4] {
        [v[0][k], v[1][k], v[2][k], v[3][k]]
    }

    #[test]
    fn thin_opacity_matches_the_range_reduced_one() {
        for i in 0..=10_000 {
            let d = 0.5 * THIN * i as f32 / 10_000.0 * (1.0 - 1e-7);
            let (want, got) = (opacity(d), opacity_thin(d));
            assert!((want - got).abs() <= 2e-7 * want, "{d}: {want} {got}");
        }
    }

    #[test]
    fn lanes_match_the_scalar_models() {
        let table = PsiTable::new();
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            let (f, b, l) = inputs(&mut seed);
            let psi = psi_rgba_lanes(&table, &f, &b, &l);
            let avg = average_rgba_lanes(&f, &b, &l);
            for (k, &lk) in l.iter().enumerate() {
                let (fk, bk) = (lane(&f, k), lane(&b, k));
                let want = psi_rgba(&table, fk, bk, lk);
                let got = lane(&psi, k);
                for c in 0..4 {
                    let tol = 1e-6 * want[c].abs().max(1e-3);
                    assert!((want[c] - got[c]).abs() <= tol, "psi {want:?} {got:?}");
                }
                let want = average_rgba(fk, bk, lk);
                let got = lane(&avg, k);
                for c in 0..4 {
                    assert!((want[c] - got[c]).abs() <= 1e-6, "average {want:?} {got:?}");
                }
            }
        }
    }
}
