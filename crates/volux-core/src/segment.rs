//! Distances in the plane, shared by the screen-space tools (the eraser's swept disc) and
//! the image drawing (anti-aliased segments).
use glam::DVec2;

/// The distance from `q` to the segment `[a, b]` (to `a` when they coincide).
pub fn segment_distance(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((q - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q - (a + ab * t)).length()
}
