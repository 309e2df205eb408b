//! The plane form against the thick vertex of the seeds' classification and against the
//! closed-form thickness of a split parallelepiped.
use glam::Vec3;

use super::*;
use crate::pt::classify::classify;
use crate::pt::project::{fan_vertices, screen_points, TetVertices};
use crate::pt::raster::Triangle;
use crate::tiles::Rect;

/// A xorshift generator of floats in `[0, 1)`.
fn rng(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A coordinate snapped to the sub-pixel grid, as projected vertices are.
fn snap(v: f64) -> f32 {
    ((v * 256.0).round() / 256.0) as f32
}

/// `(z_f, s_f, z_b, s_b)` of the ray through screen point `(x, y)` from the cell's planes.
fn entry_exit(c: &CellPlanes, x: f32, y: f32, perspective: bool) -> (f64, f64, f64, f64) {
    let (dx, dy) = (x - c.origin[0], y - c.origin[1]);
    let pick = |mask: u8, farthest: bool| {
        let v = (0..4)
            .filter(|j| mask & (1 << j) != 0)
            .map(|j| f64::from(c.faces[j].at(dx, dy)));
        // Farthest: least `w = 1/z` under perspective, greatest `z` otherwise.
        if farthest == perspective {
            v.fold(f64::INFINITY, f64::min)
        } else {
            v.fold(f64::NEG_INFINITY, f64::max)
        }
    };
    let (wf, wb) = (pick(c.front, true), pick(c.back, false));
    let sigma = f64::from(c.sigma.at(dx, dy));
    let value = |w: f64| {
        let n = sigma + f64::from(c.gamma) * (w - f64::from(c.w0));
        f64::from(c.offset) + if perspective { n / w } else { n }
    };
    let z = |w: f64| if perspective { 1.0 / w } else { w };
    (z(wf), value(wf), z(wb), value(wb))
}

#[test]
fn entry_and_exit_match_the_thick_vertex() {
    let mut rnd = rng(0x5eed_1234_abcd_0001);
    let mut checked = 0;
    for i in 0..4000 {
        let perspective = i % 2 == 0;
        let screen: [[f32; 3]; 4] = std::array::from_fn(|_| {
            [
                snap(40.0 * rnd()),
                snap(40.0 * rnd()),
                (2.0 + 2.0 * rnd()) as f32,
            ]
        });
        let scalars: [f32; 4] = std::array::from_fn(|_| (rnd() * 2.0 - 1.0) as f32);
        let c = classify(screen_points(&screen));
        let tv = TetVertices {
            screen,
            scalars,
            gradients: [Vec3::ZERO; 4],
            perspective,
            _marker: std::marker::PhantomData,
        };
        let (Some(fan), Some(planes)) = (
            fan_vertices(&tv, &c),
            CellPlanes::new(&screen, &scalars, perspective),
        ) else {
            continue;
        };
        let t = fan[4];
        // Slivers (a thick vertex less than a tenth of the depth range deep) are
        // ill-conditioned for both constructions; the draw test below covers them.
        let depth = screen.iter().map(|v| v[2]).fold(0.0f32, f32::max)
            - screen.iter().map(|v| v[2]).fold(f32::INFINITY, f32::min);
        if t.z_b - t.z_f < 0.1 * depth {
            continue;
        }
        // The fan's thick point is snapped; its attributes are those of the exact crossing.
        let at = c.thick.expect("a fan has a thick vertex").position;
        let (zf, sf, zb, sb) = entry_exit(&planes, at.x as f32, at.y as f32, perspective);
        let close = |a: f64, b: f32| (a - f64::from(b)).abs() < 2e-3;
        assert!(
            close(zf, t.z_f) && close(zb, t.z_b) && close(sf, t.s_f) && close(sb, t.s_b),
            "{screen:?} {scalars:?}: planes {:?}, thick {t:?}",
            (zf, sf, zb, sb)
        );
        // At a thin vertex the ray only touches the cell.
        for v in screen.iter().filter(|v| [v[0], v[1]] != t.xy) {
            let (zf, _, zb, _) = entry_exit(&planes, v[0], v[1], perspective);
            assert!((zb - zf).abs() < 2e-3, "thin vertex: {zf} {zb}");
        }
        checked += 1;
    }
    assert!(checked > 1000, "only {checked} cells checked");
}

/// The unit cube's corners (index `x + 2y + 4z`) and its split into five tetrahedra.
const CUBE: [[u32; 4]; 5] = [
    [1, 2, 4, 7],
    [0, 1, 2, 4],
    [3, 1, 2, 7],
    [5, 1, 4, 7],
    [6, 2, 4, 7],
];

/// The affine map of the cube into `(x, y, w)` screen space.
fn map(p: [f64; 3]) -> [f64; 3] {
    [
        4.5 + 16.0 * p[0] + 7.0 * p[2] + 1.25 * p[1],
        3.25 + 15.0 * p[1] + 5.0 * p[2] - 2.5 * p[0],
        0.5 + 0.125 * p[2] + 0.0625 * p[0] - 0.03125 * p[1],
    ]
}

/// The interval of `w` along the screen point `(x, y)` inside the mapped cube.
fn cube_interval(x: f64, y: f64) -> Option<(f64, f64)> {
    // p = A^-1 ((x, y, w) - b) is affine in w: p(w) = p(0) + w p'.
    let cols = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(map);
    let b = map([0.0; 3]);
    let a = |i: usize, j: usize| cols[j][i] - b[i];
    let m = [
        [a(0, 0), a(0, 1), a(0, 2)],
        [a(1, 0), a(1, 1), a(1, 2)],
        [a(2, 0), a(2, 1), a(2, 2)],
    ];
    let solve = |r: [f64; 3]| {
        let d = det3(m);
        [0, 1, 2].map(|k| {
            let mut mk = m;
            for (row, &v) in mk.iter_mut().zip(&r) {
                row[k] = v;
            }
            det3(mk) / d
        })
    };
    let p0 = solve([x - b[0], y - b[1], -b[2]]);
    let p1 = solve([x - b[0], y - b[1], 1.0 - b[2]]);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let d = p1[k] - p0[k];
        let (t0, t1) = ((0.0 - p0[k]) / d, (1.0 - p0[k]) / d);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    (lo < hi).then_some((lo, hi))
}

#[test]
fn split_cube_is_drawn_once_with_its_exact_thickness() {
    let corners: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            let p = map([f64::from(i & 1), f64::from((i >> 1) & 1), f64::from(i >> 2)]);
            [p[0] as f32, p[1] as f32, p[2] as f32]
        })
        .collect();
    let (w, h) = (40usize, 40usize);
    let clip = Rect {
        x0: 0,
        y0: 0,
        x1: w,
        y1: h,
    };
    for perspective in [false, true] {
        // Under perspective the third coordinate is `w = 1/z`: store depths.
        let screen_of = |i: u32| {
            let [x, y, v] = corners[i as usize];
            [x, y, if perspective { 1.0 / v } else { v }]
        };
        let mut thickness = vec![0.0f64; w * h];
        let mut cells_at = vec![0u32; w * h];
        for tet in CUBE {
            let screen = tet.map(screen_of);
            let planes = CellPlanes::new(&screen, &[0.0; 4], perspective).expect("a solid cell");
            let mut drawn = vec![false; w * h];
            for face in planes.draws() {
                let Some(t) = Triangle::new(face.tri, clip) else {
                    continue;
                };
                t.for_each(|x, y, _| {
                    let p = y * w + x;
                    assert!(!drawn[p], "pixel {x},{y} drawn twice by one cell");
                    drawn[p] = true;
                    let (zf, _, zb, _) =
                        entry_exit(&planes, x as f32 + 0.5, y as f32 + 0.5, perspective);
                    let wv = |z: f64| if perspective { 1.0 / z } else { z };
                    thickness[p] += (wv(zb) - wv(zf)).abs();
                    cells_at[p] += 1;
                });
            }
        }
        let mut inside = 0;
        for y in 0..h {
            for x in 0..w {
                let p = y * w + x;
                let expected = cube_interval(x as f64 + 0.5, y as f64 + 0.5);
                match expected {
                    Some((lo, hi)) => {
                        inside += 1;
                        assert!(cells_at[p] > 0, "gap at {x},{y}");
                        assert!(
                            (thickness[p] - (hi - lo)).abs() < 1e-5,
                            "{x},{y}: {} vs {}",
                            thickness[p],
                            hi - lo
                        );
                    }
                    // Outside, or on the silhouette (drawn by the fill rule, with no depth).
                    None => assert!(thickness[p] < 1e-5, "{x},{y} outside the cube drawn"),
                }
            }
        }
        assert!(inside > 300, "{inside} pixels inside");
    }
}

/// The 3 x 3 determinant of rows `m`.
fn det3(m: [[f64; 3]; 3]) -> f64 {
    dot3(m[0], cross3(m[1], m[2]))
}
