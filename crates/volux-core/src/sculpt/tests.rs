use glam::{DMat3, DVec3};

use super::*;
use crate::camera::{Camera, CameraSpec};
use crate::grid::{Buffer, Grid, Samples};

/// A `dims` grid with anisotropic spacing, an origin off zero and (when `turned`) a rotated
/// direction.
fn grid(dims: [usize; 3], turned: bool) -> Grid {
    let n = dims.iter().product();
    let g = Grid::new(
        dims,
        [0.7, 1.0, 1.6],
        [-5.0, 3.0, 10.0],
        Samples::F32(Buffer::owned(vec![0.0f32; n])),
    )
    .unwrap();
    if turned {
        g.with_direction(DMat3::from_rotation_z(0.5) * DMat3::from_rotation_x(0.3))
            .unwrap()
    } else {
        g
    }
}

fn camera(g: &Grid, spec: &str) -> Camera {
    CameraSpec::from_json(spec)
        .unwrap()
        .resolve(&g.bounds())
        .unwrap()
}

/// The voxels kept, one bool each.
fn kept(mask: &SculptMask) -> Vec<bool> {
    let [nx, ny, nz] = mask.dims();
    let mut out = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                out.push(mask.voxel(i, j, k));
            }
        }
    }
    out
}

/// Brute force: whether voxel `ijk` projects within `r` pixels of the polyline `pts`.
fn in_stroke(
    g: &Grid,
    cam: &Camera,
    size: (usize, usize),
    pts: &[[f64; 2]],
    r: f64,
    ijk: [usize; 3],
) -> bool {
    let w = g.index_to_world(DVec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64));
    let (px, py, depth) = cam.project(w, size.0, size.1);
    let perspective = matches!(
        cam.projection,
        crate::camera::Projection::Perspective { .. }
    );
    if perspective && depth <= 0.0 {
        return false;
    }
    let q = glam::DVec2::new(px, py);
    let segs: Vec<_> = if pts.len() == 1 {
        vec![(pts[0], pts[0])]
    } else {
        pts.windows(2).map(|w| (w[0], w[1])).collect()
    };
    segs.iter().any(|(a, b)| {
        let (a, b) = (glam::DVec2::from(*a), glam::DVec2::from(*b));
        let ab = b - a;
        let t = if ab.length_squared() > 0.0 {
            ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (q - (a + ab * t)).length() <= r
    })
}

#[test]
fn the_eraser_removes_exactly_the_voxels_projecting_into_the_swept_disc() {
    for (turned, spec) in [
        (false, r#"{"azimuth": 30, "elevation": 20}"#),
        (
            true,
            r#"{"azimuth": -50, "elevation": -10, "projection": "orthographic"}"#,
        ),
        (false, r#"{"azimuth": 10, "zoom": 3}"#),
    ] {
        let g = grid([37, 29, 21], turned);
        let cam = camera(&g, spec);
        let size = (120, 90);
        let pts = [[40.0, 30.0], [75.0, 52.0], [80.0, 70.0]];
        let mut mask = SculptMask::new(g.dims()).unwrap();
        let stroke = ScreenStroke::new(&cam, size, &pts, 9.5, VoxelFrame::of(&g)).unwrap();
        let edit = mask.remove(&stroke);
        let mut expect_removed = 0u64;
        let [nx, ny, nz] = g.dims();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let gone = in_stroke(&g, &cam, size, &pts, 9.5, [i, j, k]);
                    expect_removed += u64::from(gone);
                    assert_eq!(mask.voxel(i, j, k), !gone, "voxel {i},{j},{k} ({spec})");
                }
            }
        }
        assert!(
            expect_removed > 500,
            "the stroke should remove something: {expect_removed}"
        );
        assert_eq!(edit.removed_voxels(), expect_removed);
        assert_eq!(mask.removed_count(), expect_removed);
    }
}

/// Large enough that whole boxes of bricks and whole octants of bricks are settled without
/// their voxels ([`cut`](super::cut)), with a second stroke cutting bricks the first left
/// partly kept.
#[test]
fn strokes_on_a_larger_grid_remove_the_union_of_what_brute_force_projects_into_them() {
    let g = grid([150, 131, 90], true);
    let cam = camera(&g, r#"{"azimuth": 40, "elevation": 25, "zoom": 1.4}"#);
    let size = (200, 160);
    let strokes: [(&[[f64; 2]], f64); 2] = [
        (&[[100.0, 80.0]], 31.0),
        (&[[60.0, 40.0], [120.0, 95.0], [150.0, 60.0]], 12.5),
    ];
    let mut mask = SculptMask::new(g.dims()).unwrap();
    let mut removed = 0;
    for (pts, r) in strokes {
        let stroke = ScreenStroke::new(&cam, size, pts, r, VoxelFrame::of(&g)).unwrap();
        removed += mask.remove(&stroke).removed_voxels();
    }
    let [nx, ny, nz] = g.dims();
    let mut expect_removed = 0u64;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let gone = strokes
                    .iter()
                    .any(|(pts, r)| in_stroke(&g, &cam, size, pts, *r, [i, j, k]));
                expect_removed += u64::from(gone);
                assert_eq!(mask.voxel(i, j, k), !gone, "voxel {i},{j},{k}");
            }
        }
    }
    assert!(expect_removed > 100_000, "removed {expect_removed}");
    assert_eq!(removed, expect_removed);
}

#[test]
fn a_ball_removes_the_voxels_within_its_world_radius_and_undo_restores_bit_for_bit() {
    let g = grid([40, 33, 25], true);
    let frame = VoxelFrame::of(&g);
    let mut mask = SculptMask::new(g.dims()).unwrap();
    let cam = camera(&g, r#"{"azimuth": 15}"#);
    let first = ScreenStroke::new(&cam, (64, 64), &[[30.0, 30.0]], 6.0, frame).unwrap();
    let e1 = mask.remove(&first);
    let before = mask.clone();
    let centre = g.index_to_world(DVec3::new(17.3, 12.1, 9.8));
    let ball = Ball::new(centre, 7.5, frame).unwrap();
    let e2 = mask.remove(&ball);
    assert!(e2.removed_voxels() > 100 && !e2.is_empty());
    let [nx, ny, nz] = g.dims();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let w = g.index_to_world(DVec3::new(i as f64, j as f64, k as f64));
                let expect = before.voxel(i, j, k) && (w - centre).length() > 7.5;
                assert_eq!(mask.voxel(i, j, k), expect, "voxel {i},{j},{k}");
            }
        }
    }
    assert_ne!(mask.generation(), before.generation());
    mask.restore(&e2);
    assert_eq!(kept(&mask), kept(&before));
    mask.restore(&e1);
    assert!(mask.is_untouched());
    assert_eq!(mask.removed_count(), 0);
}

/// The mask's value at `p` from its voxels, corner by corner (the independent reference of
/// [`SculptMask::value`]).
fn trilinear_of_voxels(mask: &SculptMask, p: [f32; 3]) -> f32 {
    let d = mask.dims();
    let c: [usize; 3] = std::array::from_fn(|a| (p[a].floor() as usize).min(d[a] - 2));
    let f: [f32; 3] = std::array::from_fn(|a| p[a] - c[a] as f32);
    let mut sum = 0.0;
    for corner in 0..8usize {
        let at = |a: usize| c[a] + (corner >> a & 1);
        let w: f32 = (0..3)
            .map(|a| {
                if corner >> a & 1 == 1 {
                    f[a]
                } else {
                    1.0 - f[a]
                }
            })
            .product();
        sum += w * f32::from(u8::from(mask.voxel(at(0), at(1), at(2))));
    }
    sum
}

#[test]
fn visibility_is_the_interpolated_mask_at_one_half_and_block_states_agree() {
    let g = grid([30, 26, 19], false);
    let frame = VoxelFrame::of(&g);
    let mut mask = SculptMask::new(g.dims()).unwrap();
    for (c, r) in [
        ([10.0, 9.0, 8.0], 6.0),
        ([15.0, 13.0, 9.0], 14.0),
        ([3.0, 3.0, 15.0], 4.0),
    ] {
        let centre = g.index_to_world(DVec3::from(c));
        mask.remove(&Ball::new(centre, r, frame).unwrap());
    }
    let mut state = 12345u64;
    let mut rnd = |hi: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * (hi - 1) as f64
    };
    let mut partial_seen = 0;
    for _ in 0..20000 {
        let p = [rnd(30) as f32, rnd(26) as f32, rnd(19) as f32];
        let v = mask.value(p);
        let want = trilinear_of_voxels(&mask, p);
        assert!(
            (v - want).abs() < 1e-6,
            "at {p:?}: value {v}, voxels give {want}"
        );
        assert_eq!(mask.visible(p), v >= 0.5, "at {p:?}: value {v}");
        partial_seen += usize::from(v > 0.0 && v < 1.0);
    }
    assert!(partial_seen > 100);
    // The lane-wise answers are the one-point answer, out-of-range and NaN lanes included
    // (`hidden_lanes` only for the lanes picked).
    for _ in 0..2000 {
        let mut p = [[0f32; 8]; 3];
        for v in p.iter_mut().flatten() {
            *v = rnd(34) as f32 - 2.0;
        }
        p[1][3] = f32::NAN;
        // Points on cell faces, and on the grid's last faces.
        p[0][5] = p[0][5].round();
        p[2][6] = p[2][6].round();
        p[0][7] = 29.0;
        p[1][7] = 25.0;
        p[2][1] = 18.0;
        let mut keep = [true; 8];
        mask.visible_lanes(&p, &mut keep);
        let picked = (rnd(257) as u32) | 1 << 5;
        let hidden = mask.hidden_lanes(&p, picked);
        for l in 0..8 {
            let visible = mask.visible([p[0][l], p[1][l], p[2][l]]);
            assert_eq!(keep[l], visible, "lane {l}");
            let want = picked >> l & 1 == 1 && !visible;
            assert_eq!(hidden >> l & 1 == 1, want, "hidden lane {l} of {picked:#b}");
        }
    }
    // A removed block is removed at every point.
    let m = mask.blocks_per_axis();
    let removed = (0..m[0] * m[1] * m[2])
        .filter(|&b| mask.block_removed(b))
        .count();
    assert!(removed > 0, "some macrocell lies inside a ball");
    // Out-of-range and NaN points neither panic nor read outside.
    let _ = mask.visible([f32::NAN, -5.0, 1e9]);
}

#[test]
fn the_cut_gradient_is_the_interpolated_masks_gradient_on_the_exposed_surface_only() {
    let g = grid([30, 26, 19], false);
    let frame = VoxelFrame::of(&g);
    let mut mask = SculptMask::new(g.dims()).unwrap();
    let centre = [15.0, 13.0, 9.0];
    mask.remove(&Ball::new(g.index_to_world(DVec3::from(centre)), 14.0, frame).unwrap());
    let mut state = 777u64;
    let mut rnd = |hi: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * (hi - 1) as f64
    };
    let (mut on_surface, mut away) = (0, 0);
    for _ in 0..20000 {
        let p = [rnd(30) as f32, rnd(26) as f32, rnd(19) as f32];
        let c: [usize; 3] =
            std::array::from_fn(|a| (p[a].floor() as usize).min(mask.dims()[a] - 2));
        let corners: Vec<bool> = (0..8usize)
            .map(|k| mask.voxel(c[0] + (k & 1), c[1] + (k >> 1 & 1), c[2] + (k >> 2 & 1)))
            .collect();
        let mixed = corners.iter().any(|&k| k) && corners.iter().any(|&k| !k);
        match mask.cut_gradient(p) {
            None => away += usize::from(!mixed),
            Some(grad) => {
                assert!(
                    mixed,
                    "at {p:?}: a gradient in a cell the cut does not cross"
                );
                on_surface += 1;
                // Central differences of the interpolated mask inside the same cell.
                for a in 0..3 {
                    let h = 1e-3f32;
                    let (mut lo, mut hi) = (p, p);
                    lo[a] = (p[a] - h).max(c[a] as f32);
                    hi[a] = (p[a] + h).min(c[a] as f32 + 1.0);
                    let want = (trilinear_of_voxels(&mask, hi) - trilinear_of_voxels(&mask, lo))
                        / (hi[a] - lo[a]);
                    assert!(
                        (grad[a] - want).abs() < 2e-2,
                        "at {p:?}, axis {a}: {grad:?} vs {want}"
                    );
                }
                // Towards what is kept: away from the ball's centre.
                let out: f32 = (0..3).map(|a| grad[a] * (p[a] - centre[a] as f32)).sum();
                assert!(out > 0.0, "at {p:?}: {grad:?} points into the hole");
            }
        }
    }
    assert!(
        on_surface > 100 && away > 1000,
        "{on_surface} on the surface, {away} away"
    );
    assert_eq!(
        SculptMask::new([4, 4, 4]).unwrap().cut_gradient([1.5; 3]),
        None
    );
    let _ = mask.cut_gradient([f32::NAN, -3.0, 1e9]);
}

#[test]
fn the_mask_round_trips_through_bytes_and_bad_input_is_refused() {
    let g = grid([17, 9, 12], false);
    let frame = VoxelFrame::of(&g);
    let mut mask = SculptMask::new(g.dims()).unwrap();
    mask.remove(&Ball::new(g.index_to_world(DVec3::new(8.0, 4.0, 6.0)), 4.0, frame).unwrap());
    let bytes = mask.to_values();
    assert_eq!(bytes.len(), 17 * 9 * 12);
    let back = SculptMask::from_values(g.dims(), &bytes).unwrap();
    assert_eq!(kept(&back), kept(&mask));
    assert!(SculptMask::from_values(g.dims(), &bytes[1..]).is_err());
    assert!(SculptMask::new([0, 3, 3]).is_err());
    assert!(Ball::new(DVec3::ZERO, 0.0, frame).is_err());
    assert!(Ball::new(DVec3::NAN, 1.0, frame).is_err());
    let cam = camera(&g, "{}");
    assert!(ScreenStroke::new(&cam, (10, 10), &[], 3.0, frame).is_err());
    assert!(ScreenStroke::new(&cam, (10, 10), &[[1.0, f64::NAN]], 3.0, frame).is_err());
    assert!(ScreenStroke::new(&cam, (0, 10), &[[1.0, 1.0]], 3.0, frame).is_err());
    // A ball beyond the grid changes nothing.
    let far = Ball::new(DVec3::splat(1e6), 2.0, frame).unwrap();
    assert!(mask.remove(&far).is_empty());
}

#[test]
fn labels_are_the_nearest_seed_in_world_distance() {
    let g = grid([21, 17, 13], true);
    let frame = VoxelFrame::of(&g);
    let seeds = [
        LabelSeed {
            point: g.index_to_world(DVec3::new(3.0, 3.0, 3.0)),
            label: 1,
            rule: RegionRule::Nearest,
        },
        LabelSeed {
            point: g.index_to_world(DVec3::new(15.0, 4.0, 9.0)),
            label: 7,
            rule: RegionRule::Nearest,
        },
        LabelSeed {
            point: g.index_to_world(DVec3::new(9.0, 14.0, 2.0)),
            label: 3,
            rule: RegionRule::Nearest,
        },
    ];
    let visible = |i: usize, j: usize, _k: usize| !(i + j).is_multiple_of(5);
    let labels = label_regions(&frame, &seeds, visible).unwrap();
    let [nx, ny, nz] = g.dims();
    let mut used = [false; 8];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let got = labels[i + nx * (j + ny * k)];
                if !visible(i, j, k) {
                    assert_eq!(got, 0);
                    continue;
                }
                let w = g.index_to_world(DVec3::new(i as f64, j as f64, k as f64));
                let best = seeds
                    .iter()
                    .min_by(|a, b| (a.point - w).length().total_cmp(&(b.point - w).length()))
                    .unwrap();
                assert_eq!(got, best.label, "voxel {i},{j},{k}");
                used[got as usize] = true;
            }
        }
    }
    assert!(used[1] && used[7] && used[3]);
    assert!(label_regions(&frame, &[], visible).is_err());
    let zero = [LabelSeed {
        point: DVec3::ZERO,
        label: 0,
        rule: RegionRule::Connected,
    }];
    assert!(label_regions(&frame, &zero, visible).is_err());
}
