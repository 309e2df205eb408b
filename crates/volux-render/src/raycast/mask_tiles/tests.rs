//! The tiles out of the mask's reach against a brute-force march of every pixel's ray through
//! the macrocells the mask cuts, and their pixels against the render without the mask.
use glam::DVec3;
use volux_core::grid::{Buffer, Samples};
use volux_core::sculpt::{Ball, SculptMask, VoxelFrame};
use volux_core::{CameraSpec, Grid, TransferFunction};

use super::*;
use crate::integrate::Integrator;
use crate::raycast::render_grid;
use crate::tiles::TILE;

const N: usize = 40;

/// A smooth field, so that a pixel changes whenever its ray's samples do.
fn wavy_grid() -> Grid {
    let v = (0..N * N * N)
        .map(|n| {
            let (i, j, k) = (n % N, (n / N) % N, n / (N * N));
            (0.5 + 0.5 * (0.3 * i as f32).sin() * (0.2 * j as f32 + 0.1 * k as f32).cos()) * 0.8
        })
        .collect();
    Grid::new(
        [N; 3],
        [1.0, 0.8, 1.3],
        [2.0, -1.0, 0.5],
        Samples::F32(Buffer::owned(v)),
    )
    .unwrap()
}

/// Whether a world point lies in a macrocell the mask does not leave wholly visible.
fn in_cut_macrocell(mask: &SculptMask, g: &Grid, p: DVec3) -> bool {
    let ijk = (p - g.origin()) / g.spacing();
    let top = DVec3::splat((N - 1) as f64);
    if !(ijk.cmpge(DVec3::ZERO).all() && ijk.cmple(top).all()) {
        return false;
    }
    let [mx, my, mz] = mask.blocks_per_axis();
    // A point on a macrocell face is in both.
    let cells = |a: usize, n: usize| {
        let x = ijk[a] / SculptMask::BLOCK as f64;
        let c = (x.floor() as usize).min(n - 1);
        let below = (x.fract() == 0.0 && c > 0).then(|| c - 1);
        [Some(c), below]
    };
    let (xs, ys, zs) = (cells(0, mx), cells(1, my), cells(2, mz));
    xs.iter().flatten().any(|&i| {
        ys.iter().flatten().any(|&j| {
            zs.iter().flatten().any(|&k| {
                let m = i + mx * (j + my * k);
                mask.block_removed(m) || mask.block_partial(m)
            })
        })
    })
}

#[test]
fn tiles_out_of_the_masks_reach_are_those_no_ray_of_theirs_crosses_a_cut_macrocell_in() {
    let g = wavy_grid();
    let frame = VoxelFrame::of(&g);
    let mut mask = SculptMask::new(g.dims()).unwrap();
    let centre = g.index_to_world(DVec3::new(12.3, 25.1, 20.4));
    mask.remove(&Ball::new(centre, 4.5, frame).unwrap());
    let mask = std::sync::Arc::new(mask);
    let tf = TransferFunction::from_json(
        r#"{"color": [[0,1,0.5,0.25],[0.8,0.2,0.6,1]], "extinction": [[0,0.02],[0.8,0.15]]}"#,
    )
    .unwrap();
    for spec in [
        r#"{"azimuth": 30, "elevation": 20}"#,
        r#"{"azimuth": -70, "elevation": -35, "projection": "orthographic"}"#,
    ] {
        let cam = CameraSpec::from_json(spec)
            .unwrap()
            .resolve(&g.bounds())
            .unwrap();
        let mut o = RenderOptions::new(cam, tf.clone());
        (o.width, o.height) = (96, 80);
        o.integrator = Integrator::Riemann { step: 0.5 };
        o.mask = Some(mask.clone());
        let tiles = MaskTiles::new(&mask, &Placement::of(&g), &o, TileGrid::new(96, 80, TILE));
        let rays = cam.rays(96, 80);
        let (mut crossing, mut spared) = (0, 0);
        for y in 0..80 {
            for x in 0..96 {
                let ray = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
                let crosses = (0..40_000)
                    .map(|i| ray.origin + ray.dir * (i as f64 * 0.01))
                    .any(|p| in_cut_macrocell(&mask, &g, p));
                let touched = tiles.touched(x / TILE * TILE, y / TILE * TILE);
                assert!(
                    touched || !crosses,
                    "pixel {x},{y} crosses the cut ({spec})"
                );
                crossing += usize::from(crosses);
                spared += usize::from(!touched);
            }
        }
        assert!(
            crossing > 50 && spared > 1000,
            "{crossing} crossing, {spared} spared"
        );

        let cut = render_grid(&g, &o).unwrap().image;
        o.mask = None;
        let whole = render_grid(&g, &o).unwrap().image;
        let mut changed = 0;
        for y in 0..80 {
            for x in 0..96 {
                let same = cut.get(x, y) == whole.get(x, y);
                if !tiles.touched(x / TILE * TILE, y / TILE * TILE) {
                    assert!(
                        same,
                        "pixel {x},{y} out of the mask's reach changed ({spec})"
                    );
                }
                changed += usize::from(!same);
            }
        }
        assert!(
            changed > 20,
            "the ball changes only {changed} pixels ({spec})"
        );
    }
}
