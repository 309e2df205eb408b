//! Random transfer functions for property tests of the integrators.
use volux_core::transfer::Space;
use volux_core::TransferFunction;

use crate::TestRng;

/// A random valid TF in value space over `[0, 100]`: `min_knots` to `min_knots + 5` colour
/// points with random colours and as many extinction points with extinction in `[0, 2)`.
pub fn random_tf(rng: &mut TestRng, min_knots: usize) -> TransferFunction {
    let k = min_knots + (rng.unit() * 6.0) as usize;
    let mut xs: Vec<f64> = (0..k).map(|_| rng.unit() * 100.0).collect();
    xs.sort_by(f64::total_cmp);
    let color: Vec<[f64; 4]> = xs
        .iter()
        .map(|&x| [x, rng.unit(), rng.unit(), rng.unit()])
        .collect();
    let mut ys: Vec<f64> = (0..k).map(|_| rng.unit() * 100.0).collect();
    ys.sort_by(f64::total_cmp);
    let extinction: Vec<[f64; 2]> = ys.iter().map(|&y| [y, rng.unit() * 2.0]).collect();
    let t = TransferFunction {
        space: Space::Value,
        color,
        extinction,
        opacity: Vec::new(),
        opacity_step: 1.0,
        opacity_scale: 1.0,
        unit_length: 1.0,
    };
    t.validate().expect("a random TF is valid");
    t
}

/// A TF from its JSON text (panics with the parse error).
pub fn tf(json: &str) -> TransferFunction {
    TransferFunction::from_json(json).expect("test TF JSON")
}
