//! The exact 2D orientation predicate (Shewchuk's adaptive-precision `orient2d`, with an
//! exact big-integer fallback): the sign of `(b - a) × (c - a)` for any finite `f64` input.
//! Projected Tetrahedra classifies projected cells with it (seed `000` §4.1, figure 4.3).
use glam::DVec2;
use std::ops::Neg;

// -------------------------------------------------------------------------------------------
// Sign
// -------------------------------------------------------------------------------------------

/// The sign of an orientation determinant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(i8)]
pub enum Sign {
    /// Clockwise (in a y-up frame): the determinant is negative.
    Negative = -1,
    /// Collinear (or coincident) points: the determinant is exactly zero.
    Zero = 0,
    /// Counter-clockwise (in a y-up frame): the determinant is positive.
    Positive = 1,
}

impl Sign {
    /// `-1`, `0` or `1`.
    pub const fn as_i8(self) -> i8 {
        self as i8
    }

    /// The sign of an integer.
    pub const fn from_i8(x: i8) -> Sign {
        if x > 0 {
            Sign::Positive
        } else if x < 0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }

    /// The seeds' test value `sign + 1`: 0 (negative), 1 (zero) or 2 (positive).
    pub const fn ternary(self) -> u8 {
        (self as i8 + 1) as u8
    }

    /// Inverse of [`Sign::ternary`]; `None` above 2.
    pub const fn from_ternary(t: u8) -> Option<Sign> {
        match t {
            0 => Some(Sign::Negative),
            1 => Some(Sign::Zero),
            2 => Some(Sign::Positive),
            _ => None,
        }
    }

    /// The product of two signs.
    pub const fn product(self, other: Sign) -> Sign {
        Sign::from_i8(self.as_i8() * other.as_i8())
    }

    fn of_f64(x: f64) -> Sign {
        if x > 0.0 {
            Sign::Positive
        } else if x < 0.0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }
}

impl Neg for Sign {
    type Output = Sign;
    fn neg(self) -> Sign {
        Sign::from_i8(-self.as_i8())
    }
}

// -------------------------------------------------------------------------------------------
// Exact orientation predicate
// -------------------------------------------------------------------------------------------

/// `2^-53`: half an ulp of 1, the unit roundoff of binary64.
const EPS: f64 = 1.0 / 9_007_199_254_740_992.0;
/// Shewchuk's `ccwerrboundA`: bound on the error of the filtered determinant, relative to
/// `|detleft| + |detright|`.
const CCW_ERRBOUND_A: f64 = (3.0 + 16.0 * EPS) * EPS;
/// `2^-900`: below this `|detleft| + |detright|` the products may have underflowed and the
/// filter's relative bound is not trusted.
const FILTER_MIN: f64 = f64::from_bits((1023 - 900) << 52);
/// `2^-485` and `2^509`: with every non-zero coordinate in `[2^-485, 2^509)` the products of
/// two coordinates and their error terms are representable (no overflow, no underflow), so
/// the floating-point expansion arithmetic below is exact.
const EXPANSION_MIN: f64 = f64::from_bits((1023 - 485) << 52);
const EXPANSION_MAX: f64 = f64::from_bits((1023 + 509) << 52);
/// `2^27 + 1`, Dekker's splitter for binary64.
const SPLITTER: f64 = 134_217_729.0;

/// The exact orientation of the triangle `a b c`: the sign of `(b - a) × (c - a)`.
///
/// [`Sign::Positive`] when `a b c` turn counter-clockwise in a y-up frame, [`Sign::Zero`] when
/// the three points are collinear or two of them coincide.
///
/// # Why it is robust
///
/// The result is the sign of the determinant of the exact input values (every finite `f64`
/// is a rational number), never of a rounded approximation, so consistent decisions follow:
/// antisymmetry, invariance under cyclic permutation and the identity between the four
/// faces of a tetrahedron hold exactly, which is what the ternary table relies on. It is
/// evaluated in stages, each exact or certified:
///
/// 1. When a coordinate difference is exactly zero the determinant reduces to one product of
///    differences whose signs are exact (rounding never changes the sign of a difference):
///    this answers axis-aligned degeneracies, frequent in meshes from regular grids, at once.
/// 2. Shewchuk's static filter: `det = (a - c) × (b - c)` in `f64` and the a-priori error
///    bound `(3ε + 16ε²)(|detleft| + |detright|)`; when `|det|` exceeds it, its sign is exact.
///    The filter is skipped when an intermediate overflowed or may have underflowed.
/// 3. Otherwise, when every non-zero coordinate lies in `[2^-485, 2^509)`, the determinant
///    `a_x b_y - a_y b_x + b_x c_y - b_y c_x + c_x a_y - c_y a_x` is summed exactly as a
///    floating-point expansion (Dekker's two-product, Knuth's two-sum, Shewchuk's
///    grow-expansion with zero elimination), whose sign is that of its largest component.
/// 4. Otherwise (huge, tiny or subnormal coordinates), each `f64` is decomposed as
///    `m · 2^e` and the six products are accumulated exactly in a 4224-bit two's-complement
///    fixed-point integer on the stack: exact for every finite input.
///
/// NaN or infinite coordinates have no orientation: the function returns [`Sign::Zero`]
/// (callers such as [`crate::pt::classify::classify`] check finiteness first). It never panics and never
/// allocates.
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return Sign::Zero;
    }
    let acx = a.x - c.x;
    let bcx = b.x - c.x;
    let acy = a.y - c.y;
    let bcy = b.y - c.y;
    // Stage 1: the sign of a rounded difference is the sign of the exact difference, and it
    // is zero exactly when the operands are equal.
    if acx == 0.0 || bcy == 0.0 {
        return -(Sign::of_f64(acy).product(Sign::of_f64(bcx)));
    }
    if acy == 0.0 || bcx == 0.0 {
        return Sign::of_f64(acx).product(Sign::of_f64(bcy));
    }
    // Stage 2: static filter.
    let detleft = acx * bcy;
    let detright = acy * bcx;
    let det = detleft - detright;
    let detsum = detleft.abs() + detright.abs();
    if detsum.is_finite() && detsum >= FILTER_MIN {
        let bound = CCW_ERRBOUND_A * detsum;
        if det > bound {
            return Sign::Positive;
        }
        if det < -bound {
            return Sign::Negative;
        }
    }
    orient2d_exact(a, b, c)
}

/// Exact orientation, stages 3 and 4 of [`orient2d`] (finite inputs).
fn orient2d_exact(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    let safe = |x: f64| x == 0.0 || (x.abs() >= EXPANSION_MIN && x.abs() < EXPANSION_MAX);
    if [a.x, a.y, b.x, b.y, c.x, c.y].into_iter().all(safe) {
        orient2d_expansion(a, b, c)
    } else {
        orient2d_bignum(a, b, c)
    }
}

/// `a + b = x + y` exactly (Knuth's two-sum; exact for all finite results).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    let br = b - bv;
    let ar = a - av;
    (x, ar + br)
}

/// Dekker's split of `a` into two non-overlapping 26-bit halves.
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = SPLITTER * a;
    let abig = c - a;
    let hi = c - abig;
    (hi, a - hi)
}

/// `a · b = x + y` exactly (Dekker's two-product; exact without overflow or underflow).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    let (ahi, alo) = split(a);
    let (bhi, blo) = split(b);
    let err1 = x - ahi * bhi;
    let err2 = err1 - alo * bhi;
    let err3 = err2 - ahi * blo;
    (x, alo * blo - err3)
}

/// Adds `b` to the non-overlapping expansion `e[..n]` (increasing magnitude), in place, with
/// zero elimination; returns the new length (at most `n + 1`, and at most `e.len()`).
fn grow_expansion(e: &mut [f64; 12], n: usize, b: f64) -> usize {
    let n = n.min(e.len());
    let mut q = b;
    let mut out = 0;
    for i in 0..n {
        let (s, h) = two_sum(q, e[i]);
        q = s;
        if h != 0.0 {
            e[out] = h;
            out += 1;
        }
    }
    if (q != 0.0 || out == 0) && out < e.len() {
        e[out] = q;
        out += 1;
    }
    out
}

/// Stage 3: the determinant as an exact floating-point expansion.
fn orient2d_expansion(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    let products = [
        two_product(a.x, b.y),
        two_product(-a.y, b.x),
        two_product(b.x, c.y),
        two_product(-b.y, c.x),
        two_product(c.x, a.y),
        two_product(-c.y, a.x),
    ];
    let mut e = [0.0; 12];
    let mut n = 0;
    for (hi, lo) in products {
        n = grow_expansion(&mut e, n, lo);
        n = grow_expansion(&mut e, n, hi);
    }
    // Non-overlapping, increasing magnitude: the largest non-zero component has the sign.
    e[..n]
        .iter()
        .rev()
        .find(|&&x| x != 0.0)
        .map_or(Sign::Zero, |&x| Sign::of_f64(x))
}

/// Number of 64-bit limbs of the stage-4 accumulator: products of two finite `f64` are
/// multiples of `2^-2148` below `2^2048`, six of them sum below `2^2051`: 4200 bits with the
/// sign fit in 66 limbs.
const LIMBS: usize = 66;
/// `-(lowest product exponent)`: bit 0 of the accumulator weighs `2^-2148`.
const BIAS: i32 = 2148;

/// `x = ±m · 2^e` with `m < 2^53` (finite `x`).
fn decompose(x: f64) -> (bool, u64, i32) {
    let bits = x.to_bits();
    let negative = bits >> 63 != 0;
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        (negative, frac, -1074)
    } else {
        (negative, frac | (1u64 << 52), biased - 1075)
    }
}

/// Adds `± x · y` to the fixed-point accumulator, exactly.
fn accumulate_product(acc: &mut [u64; LIMBS], x: f64, y: f64, negate: bool) {
    let (nx, mx, ex) = decompose(x);
    let (ny, my, ey) = decompose(y);
    let m = u128::from(mx) * u128::from(my);
    if m == 0 {
        return;
    }
    let negative = nx ^ ny ^ negate;
    // ex + ey >= -2148 and <= 1942, so 0 <= offset <= 4090.
    let offset = (ex + ey + BIAS).max(0) as usize;
    let limb = offset / 64;
    let shift = offset % 64;
    let lo = m as u64;
    let hi = (m >> 64) as u64;
    let words = if shift == 0 {
        [lo, hi, 0]
    } else {
        [
            lo << shift,
            (lo >> (64 - shift)) | (hi << shift),
            hi >> (64 - shift),
        ]
    };
    let mut carry = false;
    for (k, limb_value) in acc.iter_mut().enumerate().skip(limb) {
        let w = words.get(k - limb).copied().unwrap_or(0);
        if k - limb >= words.len() && !carry {
            break;
        }
        if negative {
            let (d1, b1) = limb_value.overflowing_sub(w);
            let (d2, b2) = d1.overflowing_sub(u64::from(carry));
            *limb_value = d2;
            carry = b1 || b2;
        } else {
            let (s1, c1) = limb_value.overflowing_add(w);
            let (s2, c2) = s1.overflowing_add(u64::from(carry));
            *limb_value = s2;
            carry = c1 || c2;
        }
    }
}

/// Stage 4: exact orientation of any finite input with a fixed-size big integer.
fn orient2d_bignum(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    let mut acc = [0u64; LIMBS];
    accumulate_product(&mut acc, a.x, b.y, false);
    accumulate_product(&mut acc, a.y, b.x, true);
    accumulate_product(&mut acc, b.x, c.y, false);
    accumulate_product(&mut acc, b.y, c.x, true);
    accumulate_product(&mut acc, c.x, a.y, false);
    accumulate_product(&mut acc, c.y, a.x, true);
    if acc.iter().all(|&w| w == 0) {
        Sign::Zero
    } else if acc[LIMBS - 1] >> 63 != 0 {
        Sign::Negative
    } else {
        Sign::Positive
    }
}

#[cfg(test)]
mod tests;
