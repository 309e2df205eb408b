//! The per-tetrahedron classification of the tile loop, from fixed-point positions.
//!
//! [`classify`] takes arbitrary `f64` positions: its orientation tests go through
//! floating-point filters and exact expansions, and its parameters are computed on positions
//! rescaled by a power of two so that nothing overflows. The tile loop's positions are
//! snapped to the `1/SUBPIXEL` grid inside the guard band, so `SUBPIXEL` times a coordinate
//! is an integer well below `2^29`: there the four tests are exact in `i64` (products of
//! differences stay below `2^61`), and the rescaling is not needed, since scaling by a power
//! of two changes neither the sign nor, without overflow or underflow, the rounding of any
//! of the parameter computations (every product, difference and ratio is scaled exactly).
//! [`classify_fixed`] therefore returns exactly what [`classify`] returns, more cheaply, and
//! falls back to it for positions that are not on the grid or not in range.
use glam::DVec2;

use super::classify::{
    classify, projection_tests, ternary_code, thick_vertex_scaled, Classification, Sign,
    TERNARY_TABLE,
};
use super::project::SUBPIXEL;
use super::raster::fixed;

/// Fixed-point coordinates must stay below this in magnitude for exact `i64` tests.
const MAX_FIXED: i64 = 1 << 29;

/// The exact orientation of `a b c` (fixed point; `|coordinates| < MAX_FIXED`).
#[inline(always)]
fn orient(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> Sign {
    let d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    Sign::from_i8(d.signum() as i8)
}

/// Whether `q` is exactly `SUBPIXEL * projected`, within the range of exact `i64` tests.
#[inline(always)]
fn on_grid(projected: &[DVec2; 4], q: &[[i64; 2]; 4]) -> bool {
    let scale = f64::from(SUBPIXEL);
    projected.iter().zip(q).all(|(p, q)| {
        q[0].abs() < MAX_FIXED
            && q[1].abs() < MAX_FIXED
            && q[0] as f64 == p.x * scale
            && q[1] as f64 == p.y * scale
    })
}

/// The four tests of [`projection_tests`] on fixed-point positions.
#[inline(always)]
fn tests_fixed(q: &[[i64; 2]; 4]) -> [Sign; 4] {
    [
        orient(q[0], q[1], q[2]),
        orient(q[0], q[1], q[3]),
        orient(q[0], q[2], q[3]),
        orient(q[1], q[2], q[3]),
    ]
}

/// [`projection_tests`] of the projected vertices `screen` (`[x, y, depth]`), exact in `i64`
/// when they are on the sub-pixel grid (the same result, more cheaply).
#[inline]
pub fn projection_tests_screen(screen: &[[f32; 3]; 4]) -> [Sign; 4] {
    let projected = screen.map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])));
    let q = screen.map(|p| fixed([p[0], p[1]]));
    if on_grid(&projected, &q) {
        tests_fixed(&q)
    } else {
        projection_tests(projected)
    }
}

/// [`classify`] of `projected`, given its fixed-point positions `q` (`q = SUBPIXEL *
/// projected` when on the grid). The result is the same as [`classify`]'s.
#[inline]
pub fn classify_fixed(projected: [DVec2; 4], q: [[i64; 2]; 4]) -> Classification {
    if !on_grid(&projected, &q) {
        return classify(projected);
    }
    let tests = tests_fixed(&q);
    let code = ternary_code(tests);
    let entry = &TERNARY_TABLE[usize::from(code) % TERNARY_TABLE.len()];
    let thick = thick_vertex_scaled(&projected, &projected, entry);
    Classification {
        code: Some(code),
        class: entry.class,
        fan: entry.fan,
        thick,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_classify_on_grid_points() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % n
        };
        for i in 0..200_000 {
            // Small grids make every degenerate class frequent; large spans and big offsets
            // exercise the rounding of the parameters.
            let (span, step) = match i % 4 {
                0 => (4, 64),
                1 => (64, 1),
                2 => (1 << 16, 1),
                _ => (1 << 26, 1),
            };
            let off = if i % 8 < 4 { 0 } else { 1 << 20 };
            let mut pt = || {
                let x = (rnd(span) * step) as f32 / SUBPIXEL + off as f32 / SUBPIXEL;
                let y = (rnd(span) * step) as f32 / SUBPIXEL - off as f32 / SUBPIXEL;
                [x, y]
            };
            let xy = [pt(), pt(), pt(), pt()];
            let projected = xy.map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])));
            let q = xy.map(fixed);
            assert_eq!(classify_fixed(projected, q), classify(projected), "{xy:?}");
            let screen = xy.map(|p| [p[0], p[1], 1.0]);
            assert_eq!(
                projection_tests_screen(&screen),
                projection_tests(projected)
            );
        }
    }

    #[test]
    fn falls_back_off_the_grid() {
        let projected = [
            DVec2::new(0.1, 0.2),
            DVec2::new(5.3, 0.7),
            DVec2::new(1.9, 4.4),
            DVec2::new(1.5, 1.5),
        ];
        let q = projected.map(|p| fixed([p.x as f32, p.y as f32]));
        assert_eq!(classify_fixed(projected, q), classify(projected));
    }
}
