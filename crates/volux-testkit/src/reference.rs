//! Brute-force references, written independently of the renderers' integrators.
use volux_core::TransferFunction;

/// The emission-absorption integral of a ray segment of length `len` along which the scalar
/// goes linearly from `s_f` to `s_b`, for a resolved `tf`, by brute force: composite Simpson
/// rules for the depth and colour integrals with `steps` steps in all, split at the TF
/// breakpoints (where the integrand has kinks), sampling the TF directly. Premultiplied RGBA.
pub fn segment_simpson(
    tf: &TransferFunction,
    s_f: f64,
    s_b: f64,
    len: f64,
    steps: usize,
) -> [f64; 4] {
    let mut ts = vec![0.0, len];
    if s_b != s_f {
        for x in tf.breakpoints() {
            let t = len * (x - s_f) / (s_b - s_f);
            if t > 0.0 && t < len {
                ts.push(t);
            }
        }
    }
    ts.sort_by(f64::total_cmp);
    let at = |t: f64| {
        let s = s_f + (s_b - s_f) * t / len;
        (tf.color_at(s), tf.tau_per_world(s))
    };
    let (mut c, mut depth) = ([0.0f64; 3], 0.0f64);
    for w in ts.windows(2) {
        let m = ((steps as f64 * (w[1] - w[0]) / len).ceil() as usize).max(2);
        let h = (w[1] - w[0]) / m as f64;
        for k in 0..m {
            let t0 = w[0] + k as f64 * h;
            let (c0, a0) = at(t0);
            let (cm, am) = at(t0 + 0.5 * h);
            let (c1, a1) = at(t0 + h);
            let dm = depth + h / 24.0 * (5.0 * a0 + 8.0 * am - a1);
            let d1 = depth + h / 6.0 * (a0 + 4.0 * am + a1);
            let (g0, gm, g1) = (a0 * (-depth).exp(), am * (-dm).exp(), a1 * (-d1).exp());
            for ch in 0..3 {
                c[ch] += h / 6.0 * (c0[ch] * g0 + 4.0 * cm[ch] * gm + c1[ch] * g1);
            }
            depth = d1;
        }
    }
    [c[0], c[1], c[2], 1.0 - (-depth).exp()]
}

/// The largest absolute difference between two arrays.
pub fn max_diff<const N: usize>(a: [f64; N], b: [f64; N]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
