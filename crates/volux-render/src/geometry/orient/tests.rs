//! Tests of the orientation predicate against exact integer and big-integer arithmetic, at
//! ulp distance from collinearity and at extreme magnitudes; every stage agrees.
use super::*;
use volux_testkit::TestRng;

fn v2(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

/// Exact orientation of integer points (|coordinates| < 2^62) with `i128`.
fn orient_i128(a: (i128, i128), b: (i128, i128), c: (i128, i128)) -> Sign {
    let d = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    Sign::from_i8(d.signum() as i8)
}

/// Exact orientation of `f64` points that are all integer multiples of `2^e` with small
/// enough quotients: scales by `2^-e` exactly and uses `i128`.
fn orient_scaled_i128(a: DVec2, b: DVec2, c: DVec2, e: i32) -> Sign {
    let s = |x: f64| {
        let y = x * 2f64.powi(-e);
        assert_eq!(y, y.trunc(), "{x} is not a multiple of 2^{e}");
        assert!(y.abs() < 2f64.powi(62));
        y as i128
    };
    orient_i128((s(a.x), s(a.y)), (s(b.x), s(b.y)), (s(c.x), s(c.y)))
}

fn naive_sign(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    Sign::of_f64((b - a).perp_dot(c - a))
}

// -------------------------------------------------------------------------------------------
// Orientation predicate
// -------------------------------------------------------------------------------------------

#[test]
fn orient2d_basic_and_symmetries() {
    let a = v2(0.0, 0.0);
    let b = v2(1.0, 0.0);
    let c = v2(0.0, 1.0);
    assert_eq!(orient2d(a, b, c), Sign::Positive);
    assert_eq!(orient2d(a, c, b), Sign::Negative);
    assert_eq!(orient2d(a, b, v2(2.0, 0.0)), Sign::Zero);
    assert_eq!(orient2d(a, a, c), Sign::Zero);
    assert_eq!(orient2d(a, a, a), Sign::Zero);
    // Cyclic invariance and antisymmetry on near-degenerate random triples.
    let mut rng = TestRng::new(7);
    for _ in 0..20_000 {
        let p = v2(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let q = v2(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let t = rng.range(-2.0, 3.0);
        let r = p + (q - p) * t; // rounded: nearly collinear
        let s = orient2d(p, q, r);
        assert_eq!(s, orient2d(q, r, p));
        assert_eq!(s, orient2d(r, p, q));
        assert_eq!(s, -orient2d(q, p, r));
        assert_eq!(s, -orient2d(p, r, q));
        assert_eq!(s, orient2d_bignum(p, q, r));
    }
}

#[test]
fn orient2d_matches_i128_on_integers() {
    let mut rng = TestRng::new(11);
    for round in 0..50_000 {
        // Small grids give many exact collinearities; large ones exercise the exact stages.
        let r = if round % 2 == 0 { 5 } else { (1i64 << 52) - 1 };
        let p: [(i64, i64); 3] = std::array::from_fn(|_| (rng.int(-r, r), rng.int(-r, r)));
        let f = p.map(|(x, y)| v2(x as f64, y as f64));
        let i = p.map(|(x, y)| (i128::from(x), i128::from(y)));
        let truth = orient_i128(i[0], i[1], i[2]);
        assert_eq!(orient2d(f[0], f[1], f[2]), truth, "{p:?}");
        assert_eq!(orient2d_expansion(f[0], f[1], f[2]), truth, "{p:?}");
        assert_eq!(orient2d_bignum(f[0], f[1], f[2]), truth, "{p:?}");
    }
    // Exactly collinear large integers, and one unit off the line.
    let n = (1i64 << 50) + 3;
    let a = (0i64, 0i64);
    let b = (n, n - 1);
    let c = (2 * n, 2 * n - 2);
    let f = |p: (i64, i64)| v2(p.0 as f64, p.1 as f64);
    assert_eq!(orient2d(f(a), f(b), f(c)), Sign::Zero);
    assert_eq!(orient2d(f(a), f(b), f((c.0, c.1 + 1))), Sign::Positive);
    assert_eq!(orient2d(f(a), f(b), f((c.0, c.1 - 1))), Sign::Negative);
}

/// Kettner et al.'s classic failure of the naive predicate: points near (0.5, 0.5) on a
/// 256 × 256 grid of ulps against the line through (12, 12) and (24, 24).
#[test]
fn orient2d_nearly_collinear_ulp_grid() {
    let u = 2f64.powi(-53);
    let q = v2(12.0, 12.0);
    let r = v2(24.0, 24.0);
    let mut naive_wrong = 0;
    let (mut zeros, mut pos, mut neg) = (0, 0, 0);
    for i in 0..256 {
        for j in 0..256 {
            let p = v2(0.5 + f64::from(i) * u, 0.5 + f64::from(j) * u);
            let truth = orient_scaled_i128(p, q, r, -53);
            let s = orient2d(p, q, r);
            assert_eq!(s, truth, "i={i} j={j}");
            assert_eq!(orient2d(q, r, p), truth);
            assert_eq!(orient2d(r, p, q), truth);
            match truth {
                Sign::Zero => zeros += 1,
                Sign::Positive => pos += 1,
                Sign::Negative => neg += 1,
            }
            if naive_sign(p, q, r) != truth {
                naive_wrong += 1;
            }
        }
    }
    // The exactly collinear ones are the diagonal i == j.
    assert_eq!(zeros, 256);
    assert!(pos > 0 && neg > 0);
    assert!(
        naive_wrong > 1000,
        "the naive predicate should fail here ({naive_wrong})"
    );
}

#[test]
fn orient2d_exactly_collinear_dyadic_and_one_ulp_off() {
    let mut rng = TestRng::new(5);
    for _ in 0..20_000 {
        // a, a + d, a + 2d with dyadic values of 20 bits: all sums exact.
        let k = rng.int(-40, 40) as i32;
        let s = 2f64.powi(k);
        let g = |rng: &mut TestRng| rng.int(-(1 << 20), 1 << 20) as f64 * s;
        let a = v2(g(&mut rng), g(&mut rng));
        let d = v2(g(&mut rng), g(&mut rng));
        let b = a + d;
        let c = a + d * 2.0;
        assert_eq!(orient2d(a, b, c), Sign::Zero);
        assert_eq!(orient2d(c, a, b), Sign::Zero);
        if d == DVec2::ZERO {
            continue;
        }
        // One ulp off the line in y: the exact sign is the sign of d.x (moving c up turns
        // a b c counter-clockwise when d points right).
        let up = v2(c.x, c.y.next_up());
        let down = v2(c.x, c.y.next_down());
        let sx = Sign::of_f64(d.x);
        assert_eq!(orient2d(a, b, up), sx);
        assert_eq!(orient2d(a, b, down), -sx);
        assert_eq!(orient2d_bignum(a, b, up), sx);
    }
}

#[test]
fn orient2d_extreme_magnitudes() {
    // Huge: the naive determinant overflows.
    let a = v2(-1e300, -1e300);
    let b = v2(0.0, 0.0);
    let c = v2(1e300, 1e300);
    assert!(!((b - a).perp_dot(c - a)).is_finite() || naive_sign(a, b, c) == Sign::Zero);
    assert_eq!(orient2d(a, b, c), Sign::Zero);
    assert_eq!(
        orient2d(a, b, v2(1e300, 1e300_f64.next_up())),
        Sign::Positive
    );
    assert_eq!(
        orient2d(a, b, v2(1e300, 1e300_f64.next_down())),
        Sign::Negative
    );
    let big = f64::MAX;
    assert_eq!(
        orient2d(v2(-big, -big), v2(big, -big), v2(big, big)),
        Sign::Positive
    );
    assert_eq!(
        orient2d(v2(-big, -big), v2(0.0, 0.0), v2(big, big)),
        Sign::Zero
    );
    // Subnormal: the naive products underflow to zero.
    let t = f64::from_bits(1); // 2^-1074
    assert_eq!(
        orient2d(v2(0.0, 0.0), v2(t, t), v2(2.0 * t, 2.0 * t)),
        Sign::Zero
    );
    assert_eq!(
        orient2d(v2(0.0, 0.0), v2(t, t), v2(2.0 * t, 3.0 * t)),
        Sign::Positive
    );
    assert_eq!(
        naive_sign(v2(0.0, 0.0), v2(t, t), v2(2.0 * t, 3.0 * t)),
        Sign::Zero
    );
    assert_eq!(
        orient2d(v2(1e-300, 1e-300), v2(3e-300, 2e-300), v2(-1e-300, 0.0)),
        orient2d_bignum(v2(1e-300, 1e-300), v2(3e-300, 2e-300), v2(-1e-300, 0.0))
    );
    // Mixed magnitudes: 1e300 and 1e-300 in one triangle (stage 4).
    let a = v2(1e-300, 0.0);
    let b = v2(1e300, 1e-300);
    let c = v2(-1e300, -1e-300);
    // c = -b exactly, so the line b c passes through the origin and
    // O(b, c, a) = O(b, c, 0) + (c - b) × a = 0 + (-2e300)(0) - (-2e-300)(1e-300) > 0.
    assert_eq!(orient2d(a, b, c), Sign::Positive);
    assert_eq!(orient2d_bignum(a, b, c), Sign::Positive);
    assert_eq!(orient2d(b, a, c), Sign::Negative);
    assert_eq!(orient2d(v2(0.0, 0.0), b, c), Sign::Zero);
    // Non-finite: no panic, Zero.
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            orient2d(v2(bad, 0.0), v2(1.0, 0.0), v2(0.0, 1.0)),
            Sign::Zero
        );
        assert_eq!(
            orient2d(v2(0.0, 0.0), v2(1.0, bad), v2(0.0, 1.0)),
            Sign::Zero
        );
    }
}

/// The expansion stage (3) and the big-integer stage (4) are independent exact methods: they
/// agree on random near-degenerate input across the whole range where stage 3 applies, and
/// the full predicate agrees with stage 4 everywhere, subnormals and huge values included.
#[test]
fn orient2d_stages_agree() {
    let mut rng = TestRng::new(99);
    for i in 0..40_000 {
        let k = if i % 2 == 0 {
            rng.int(-480, 500) as i32
        } else {
            rng.int(-1074, 1000) as i32
        };
        let s = 2f64.powi(k / 2) * 2f64.powi(k - k / 2);
        let p = v2(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * s;
        let q = v2(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * s;
        let t = rng.range(-2.0, 2.0);
        let mut r = p + (q - p) * t;
        match rng.int(0, 3) {
            0 => r.x = r.x.next_up(),
            1 => r.y = r.y.next_down(),
            _ => {}
        }
        if !(p.is_finite() && q.is_finite() && r.is_finite()) {
            continue;
        }
        let exact = orient2d_bignum(p, q, r);
        assert_eq!(orient2d(p, q, r), exact, "{p:?} {q:?} {r:?}");
        let in_range = [p.x, p.y, q.x, q.y, r.x, r.y]
            .into_iter()
            .all(|x| x == 0.0 || (x.abs() >= EXPANSION_MIN && x.abs() < EXPANSION_MAX));
        if in_range {
            assert_eq!(orient2d_expansion(p, q, r), exact, "{p:?} {q:?} {r:?}");
        }
    }
}
