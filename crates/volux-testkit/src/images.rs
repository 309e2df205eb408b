//! Image comparison for tests, with stated tolerances, that explains itself on failure (the
//! habit of OSPRay's and Inviwo's image tests): the expected image, the rendering and their
//! difference are written to `target/test-failures/` and named in the panic message.
use std::path::PathBuf;

use volux_core::image::{ImageDiff, PngOptions};
use volux_core::Image;

/// What a comparison allows: largest and mean absolute error per channel (linear,
/// premultiplied values), and the fraction of pixels with a channel off by more than
/// `threshold`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Largest absolute error allowed in any channel.
    pub max_error: f64,
    /// Mean absolute error allowed over all channels.
    pub mean_error: f64,
    /// Per-channel error above which a pixel counts as different.
    pub threshold: f64,
    /// Fraction (0..1) of pixels allowed over `threshold`.
    pub fraction_over: f64,
}

impl Tolerance {
    /// Every channel within `max_error`, and so the mean too.
    pub fn max(max_error: f64) -> Self {
        Self {
            max_error,
            mean_error: max_error,
            threshold: max_error,
            fraction_over: 0.0,
        }
    }
}

/// The folder failure images go to.
pub fn failure_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/test-failures")
}

/// Compares `actual` with `expected` and panics, after writing both and their difference
/// (x10) as PNG files, when `tol` is exceeded; returns the measured difference otherwise
/// (also printed, so that test logs show the margin).
pub fn assert_images_close(
    name: &str,
    actual: &Image,
    expected: &Image,
    tol: Tolerance,
) -> ImageDiff {
    let d = actual
        .compare(expected, tol.threshold)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    eprintln!(
        "{name}: max |error| {:.3e} (allowed {:.1e}), mean {:.3e} (allowed {:.1e}), {:.3} % of pixels over {:.1e} (allowed {:.3} %)",
        d.max_error,
        tol.max_error,
        d.mean_error,
        tol.mean_error,
        100.0 * d.fraction_over,
        tol.threshold,
        100.0 * tol.fraction_over
    );
    let ok = d.max_error <= tol.max_error
        && d.mean_error <= tol.mean_error
        && d.fraction_over <= tol.fraction_over;
    if !ok {
        let dir = failure_dir();
        let _ = std::fs::create_dir_all(&dir);
        let file = |kind: &str| dir.join(format!("{name}-{kind}.png"));
        let opts = PngOptions::default();
        let _ = expected.write_png(&file("expected"), &opts);
        let _ = actual.write_png(&file("actual"), &opts);
        if let Ok(diff) = actual.difference(expected, 10.0) {
            let _ = diff.write_png(&file("diff"), &opts);
        }
        panic!(
            "{name}: images differ beyond {tol:?}: {d:?}; see {}",
            file("{expected,actual,diff}").display()
        );
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_difference_beyond_the_tolerance_fails_and_leaves_images() {
        let a = Image::from_pixels(1, 1, vec![[0.5, 0.5, 0.5, 1.0]]).unwrap();
        let mut b = a.clone();
        b.pixels_mut()[0][1] = 0.52;
        assert_images_close("testkit-pass", &a, &b, Tolerance::max(0.03));
        let r = std::panic::catch_unwind(|| {
            assert_images_close("testkit-fail", &a, &b, Tolerance::max(0.01))
        });
        assert!(r.is_err());
        assert!(failure_dir().join("testkit-fail-diff.png").exists());
    }
}
