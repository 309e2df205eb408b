//! Region labelling by rule (issue 41): nearest seed versus connected growth.
use std::collections::VecDeque;

use glam::{DMat3, DVec3};

use super::*;
use crate::grid::{Buffer, Grid, Samples};

/// A `dims` grid of anisotropic spacing, turned, off the origin (only its geometry is used:
/// visibility is given as a function).
fn grid(dims: [usize; 3]) -> Grid {
    let n = dims.iter().product();
    Grid::new(
        dims,
        [0.7, 1.0, 1.6],
        [-5.0, 3.0, 10.0],
        Samples::F32(Buffer::owned(vec![0.0f32; n])),
    )
    .unwrap()
    .with_direction(DMat3::from_rotation_z(0.5))
    .unwrap()
}

fn seed(g: &Grid, ijk: [f64; 3], label: u8, rule: RegionRule) -> LabelSeed {
    LabelSeed {
        point: g.index_to_world(DVec3::from(ijk)),
        label,
        rule,
    }
}

/// Two balls of radius 3.5 voxels, apart: about (6, 6, 6) and (16, 8, 6).
fn blobs(i: usize, j: usize, k: usize) -> bool {
    let v = DVec3::new(i as f64, j as f64, k as f64);
    [DVec3::new(6.0, 6.0, 6.0), DVec3::new(16.0, 8.0, 6.0)]
        .iter()
        .any(|c| (v - *c).length() <= 3.5)
}

fn index(dims: [usize; 3], n: usize) -> (usize, usize, usize) {
    (n % dims[0], n / dims[0] % dims[1], n / (dims[0] * dims[1]))
}

#[test]
fn nearest_labels_both_blobs_connected_only_the_touched_one() {
    let g = grid([24, 15, 13]);
    let frame = VoxelFrame::of(&g);
    let dims = g.dims();
    // Between voxels, and its nearest voxel (7, 6, 6) is inside the first ball.
    let at = [6.6, 6.2, 5.9];
    let nearest = label_regions(&frame, &[seed(&g, at, 4, RegionRule::Nearest)], blobs).unwrap();
    let connected =
        label_regions(&frame, &[seed(&g, at, 4, RegionRule::Connected)], blobs).unwrap();
    let (mut first, mut second) = (0, 0);
    for n in 0..nearest.len() {
        let (i, j, k) = index(dims, n);
        let want_all = if blobs(i, j, k) { 4 } else { 0 };
        assert_eq!(nearest[n], want_all, "nearest, voxel {i},{j},{k}");
        let in_first = blobs(i, j, k) && i < 11;
        assert_eq!(
            connected[n],
            if in_first { 4 } else { 0 },
            "voxel {i},{j},{k}"
        );
        match (blobs(i, j, k), in_first) {
            (true, true) => first += 1,
            (true, false) => second += 1,
            _ => {}
        }
    }
    assert!(first > 100 && second > 100, "{first} {second}");
}

/// Per seed, the fewest 6-connected steps through `visible` voxels to each voxel (brute
/// force: one breadth-first search per seed from its voxel).
fn steps_from(
    dims: [usize; 3],
    from: [usize; 3],
    visible: &dyn Fn(usize, usize, usize) -> bool,
) -> Vec<u32> {
    let at = |[i, j, k]: [usize; 3]| i + dims[0] * (j + dims[1] * k);
    let mut d = vec![u32::MAX; dims.iter().product()];
    let mut q = VecDeque::from([from]);
    d[at(from)] = 0;
    while let Some(v) = q.pop_front() {
        for a in 0..3 {
            for s in [-1i64, 1] {
                let mut w = v;
                let x = w[a] as i64 + s;
                if x < 0 || x >= dims[a] as i64 {
                    continue;
                }
                w[a] = x as usize;
                if visible(w[0], w[1], w[2]) && d[at(w)] == u32::MAX {
                    d[at(w)] = d[at(v)] + 1;
                    q.push_back(w);
                }
            }
        }
    }
    d
}

/// A U: a slab whose middle wall (x = 10) is open only at y >= 12; a third part (z >= 8)
/// apart from it.
fn u_shape(i: usize, j: usize, k: usize) -> bool {
    k != 7 && (i != 10 || j >= 12 || k >= 8)
}

#[test]
fn seeds_sharing_a_component_split_it_by_steps_ties_to_the_first() {
    let g = grid([21, 15, 11]);
    let frame = VoxelFrame::of(&g);
    let dims = g.dims();
    // Two seeds either side of the wall near its closed end (straight-line near each other,
    // far around the wall), a third at the tie-breaking middle of the open end, and a
    // duplicate of the first (it finds its voxel taken: it labels nothing).
    let seeds = [
        seed(&g, [8.0, 2.0, 3.0], 1, RegionRule::Connected),
        seed(&g, [12.0, 2.0, 3.0], 2, RegionRule::Connected),
        seed(&g, [10.0, 14.0, 3.0], 3, RegionRule::Connected),
        seed(&g, [8.0, 2.0, 3.0], 9, RegionRule::Connected),
    ];
    let labels = label_regions(&frame, &seeds, u_shape).unwrap();
    assert_eq!(labels, label_regions(&frame, &seeds, u_shape).unwrap());
    let steps: Vec<Vec<u32>> = [[8, 2, 3], [12, 2, 3], [10, 14, 3], [8, 2, 3]]
        .iter()
        .map(|&s| steps_from(dims, s, &u_shape))
        .collect();
    let mut seen = [0usize; 10];
    for n in 0..labels.len() {
        let (i, j, k) = index(dims, n);
        // The fewest steps, the first seed of equals.
        let best = (0..seeds.len())
            .filter(|&s| steps[s][n] != u32::MAX)
            .min_by_key(|&s| (steps[s][n], s));
        let want = best.map_or(0, |s| seeds[s].label);
        assert_eq!(labels[n], want, "voxel {i},{j},{k}");
        seen[usize::from(labels[n])] += 1;
    }
    let at = |i: usize, j: usize, k: usize| labels[i + dims[0] * (j + dims[1] * k)];
    assert_eq!((at(8, 2, 3), at(12, 2, 3), at(10, 14, 3)), (1, 2, 3));
    // The part above z = 7 touches no seed; the duplicate seed took nothing.
    assert!((0..labels.len()).all(|n| index(dims, n).2 < 7 || labels[n] == 0));
    assert_eq!(seen[9], 0);
    assert!(seen[1] > 100 && seen[2] > 100 && seen[3] > 100, "{seen:?}");
    // The nearest rule labels the part no seed touches, and splits across the wall.
    let nearest: Vec<LabelSeed> = seeds
        .iter()
        .map(|s| LabelSeed {
            rule: RegionRule::Nearest,
            ..*s
        })
        .collect();
    let by_nearest = label_regions(&frame, &nearest, u_shape).unwrap();
    assert_ne!(by_nearest, labels);
    assert!(by_nearest[..]
        .iter()
        .zip(&labels)
        .any(|(a, b)| *a != 0 && *b == 0));
}

#[test]
fn nearest_seeds_take_what_connected_regions_leave() {
    let g = grid([24, 15, 13]);
    let frame = VoxelFrame::of(&g);
    let dims = g.dims();
    // A nearest seed right beside the first ball, a connected seed in it: the ball is the
    // connected seed's, the second ball the nearest seed's.
    let seeds = [
        seed(&g, [3.0, 6.0, 6.0], 5, RegionRule::Nearest),
        seed(&g, [8.0, 6.0, 6.0], 2, RegionRule::Connected),
    ];
    let labels = label_regions(&frame, &seeds, blobs).unwrap();
    for (n, &l) in labels.iter().enumerate() {
        let (i, j, k) = index(dims, n);
        let want = match (blobs(i, j, k), i < 11) {
            (false, _) => 0,
            (true, true) => 2,
            (true, false) => 5,
        };
        assert_eq!(l, want, "voxel {i},{j},{k}");
    }
}

#[test]
fn a_connected_seed_off_every_visible_voxel_labels_nothing() {
    let g = grid([24, 15, 13]);
    let frame = VoxelFrame::of(&g);
    for at in [[0.0, 0.0, 0.0], [1e9, -1e9, 3.0], [-30.0, 6.0, 6.0]] {
        let labels =
            label_regions(&frame, &[seed(&g, at, 1, RegionRule::Connected)], blobs).unwrap();
        assert!(labels.iter().all(|&l| l == 0), "{at:?}");
    }
    // Its nearest voxel empty, a neighbour visible: it starts there.
    let one = |i: usize, j: usize, k: usize| (i, j, k) == (6, 5, 5);
    let start = [seed(&g, [5.4, 5.0, 5.0], 3, RegionRule::Connected)];
    let labels = label_regions(&frame, &start, one).unwrap();
    assert_eq!(labels.iter().filter(|&&l| l == 3).count(), 1);
}

#[test]
fn a_seed_saved_without_a_rule_is_nearest() {
    let old: LabelSeed = serde_json::from_str(r#"{"point": [1, 2, 3], "label": 4}"#).unwrap();
    assert_eq!(old.rule, RegionRule::Nearest);
    let new: LabelSeed =
        serde_json::from_str(r#"{"point": [1, 2, 3], "label": 4, "rule": "connected"}"#).unwrap();
    assert_eq!(new.rule, RegionRule::Connected);
    assert_eq!(RegionRule::default(), RegionRule::Nearest);
    for rule in RegionRule::ALL {
        let json = serde_json::to_string(&rule).unwrap();
        assert_eq!(json, format!("\"{}\"", rule.name()));
    }
}
