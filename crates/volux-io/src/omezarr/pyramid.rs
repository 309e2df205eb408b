//! 2x averaging, one output chunk at a time, and the element types the writer stores.
use volux_core::grid::{Buffer, Samples};

/// An element type the writer stores: the four sample types of a [`Samples`].
pub trait Elem:
    zarrs::array::Element + zarrs::array::ElementOwned + Copy + Default + Send + Sync + 'static
{
    /// The value as f64.
    fn to_f64(self) -> f64;
    /// The nearest value of this type to `v` (rounded and clamped for integers).
    fn from_f64(v: f64) -> Self;
    /// The samples' values when they are of this type.
    fn slice(s: &Samples) -> Option<&[Self]>;
    /// Values of this type as samples.
    fn samples(v: Vec<Self>) -> Samples;
}

macro_rules! int_elem {
    ($t:ty, $var:ident) => {
        impl Elem for $t {
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn from_f64(v: f64) -> Self {
                v.round().clamp(<$t>::MIN as f64, <$t>::MAX as f64) as $t
            }
            fn slice(s: &Samples) -> Option<&[Self]> {
                match s {
                    Samples::$var(b) => Some(b.as_slice()),
                    _ => None,
                }
            }
            fn samples(v: Vec<Self>) -> Samples {
                Samples::$var(Buffer::owned(v))
            }
        }
    };
}
int_elem!(u8, U8);
int_elem!(u16, U16);
int_elem!(i16, I16);

impl Elem for f32 {
    fn to_f64(self) -> f64 {
        self as f64
    }
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn slice(s: &Samples) -> Option<&[Self]> {
        match s {
            Samples::F32(b) => Some(b.as_slice()),
            _ => None,
        }
    }
    fn samples(v: Vec<Self>) -> Samples {
        Samples::F32(Buffer::owned(v))
    }
}

/// Halves a block of `dims` samples (x fastest) along every axis by averaging 2x2x2
/// neighbourhoods; along an odd axis the last output sample averages the one input sample
/// that exists there (so a 5-sample axis becomes 3: means of 0-1, 2-3 and 4 alone). An axis
/// of one sample stays one sample. Integers are rounded to nearest.
pub fn halve<T: Elem>(src: &[T], dims: [usize; 3]) -> (Vec<T>, [usize; 3]) {
    let out: [usize; 3] = std::array::from_fn(|a| dims[a].div_ceil(2));
    let mut v = Vec::with_capacity(out.iter().product());
    for k in 0..out[2] {
        for j in 0..out[1] {
            for i in 0..out[0] {
                let (mut sum, mut n) = (0.0f64, 0u32);
                for z in 2 * k..(2 * k + 2).min(dims[2]) {
                    for y in 2 * j..(2 * j + 2).min(dims[1]) {
                        for x in 2 * i..(2 * i + 2).min(dims[0]) {
                            sum += src[x + dims[0] * (y + dims[1] * z)].to_f64();
                            n += 1;
                        }
                    }
                }
                v.push(T::from_f64(sum / n as f64));
            }
        }
    }
    (v, out)
}

/// The smallest and largest finite value of `v` (`[0, 0]` when none is finite).
pub fn range_of<T: Elem>(v: &[T]) -> [f64; 2] {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            let x = x.to_f64();
            if x.is_finite() {
                (lo.min(x), hi.max(x))
            } else {
                (lo, hi)
            }
        });
    if lo.is_finite() {
        [lo, hi]
    } else {
        [0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_axes_average_what_exists() {
        // 3 x 1 x 1: [1, 3, 8] -> [2, 8].
        let (v, d) = halve(&[1.0f32, 3.0, 8.0], [3, 1, 1]);
        assert_eq!((v, d), (vec![2.0, 8.0], [2, 1, 1]));
        // u8 rounds to nearest: (1 + 2) / 2 = 1.5 -> 2.
        let (v, _) = halve(&[1u8, 2], [2, 1, 1]);
        assert_eq!(v, vec![2]);
        assert_eq!(range_of(&[f32::NAN, 2.0, -1.0]), [-1.0, 2.0]);
    }
}
