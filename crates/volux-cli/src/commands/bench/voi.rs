//! `volux bench --suite voi`: the volume of interest of issue 18 (seed `004` ch. 4): a plane
//! cut of the 8-vertex data box and of a polyhedron of about 578 vertices (the seed's
//! figures: 0.15 ms and 1.3 ms; targets 10 and 200 us), and a grid frame with five clip
//! planes against the same frame without (target: at most 10 % slower).
use std::hint::black_box;
use std::time::Instant;

use glam::DVec3;
use serde_json::json;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::{Aabb, CameraSpec};
use volux_render::engine::create_renderer;
use volux_render::scene::{Method, Scene};

use super::common::{frame, grids, median};
use crate::commands::common::CmdError;

/// Vertices of the larger polyhedron, as in the seed's benchmark.
const MANY_VERTICES: usize = 578;

/// Runs the VOI benchmark; returns the JSON rows.
pub fn run(frames: usize, n: usize, as_json: bool) -> Result<Vec<serde_json::Value>, CmdError> {
    let unit = Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let small = ConvexVoi::from_aabb(&unit)?;
    let big = rounded_box(MANY_VERTICES)?;
    let cut = ClipPlane::new(1.0, 0.3, 0.2, -0.55)?;
    let (us_small, us_big) = (cut_us(&small, &cut), cut_us(&big, &cut));
    let (name, ms_plain, ms_clipped) = clipped_frames(frames.max(3), n)?;
    if !as_json {
        println!(
            "\nVolume of interest (issue 18); threads: {}",
            rayon::current_num_threads()
        );
        println!(
            "plane cut, {} vertices: {us_small:.2} us (target 10)",
            small.vertices().len()
        );
        println!(
            "plane cut, {} vertices: {us_big:.2} us (target 200)",
            big.vertices().len()
        );
        println!(
            "{name} 512x512 riemann 0.5: {ms_plain:.1} ms, with five clip planes {ms_clipped:.1} ms ({:.2}x, target <= 1.10x)",
            ms_clipped / ms_plain
        );
    }
    Ok(vec![json!({
        "suite": "voi", "cut_us_8": us_small, "cut_us_many": us_big,
        "many_vertices": big.vertices().len(), "dataset": name, "ms": ms_plain,
        "ms_five_planes": ms_clipped, "ratio": ms_clipped / ms_plain,
    })])
}

/// The unit box cut by planes tangent to a sphere of radius 0.48 about its centre (normals
/// on a Fibonacci sphere) until it has at least `vertices` vertices.
fn rounded_box(vertices: usize) -> Result<ConvexVoi, CmdError> {
    let mut voi = ConvexVoi::from_aabb(&Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    })?;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..4 * vertices {
        if voi.vertices().len() >= vertices {
            break;
        }
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / (2 * vertices) as f64;
        let r = (1.0 - z * z).sqrt();
        let n = DVec3::new(
            r * (golden * i as f64).cos(),
            r * (golden * i as f64).sin(),
            z,
        );
        let plane = ClipPlane::new(-n.x, -n.y, -n.z, n.dot(DVec3::splat(0.5)) + 0.48)?;
        // A plane that would leave nothing cannot occur (the sphere stays inside); one that
        // removes nothing leaves the VOI as it is.
        voi.cut(&plane)?;
    }
    Ok(voi)
}

/// Microseconds per cut of `voi` by `plane` (a copy cut each time, the copy included):
/// the fastest of 5 rounds.
fn cut_us(voi: &ConvexVoi, plane: &ClipPlane) -> f64 {
    let reps = 2000;
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        for _ in 0..reps {
            let mut v = voi.clone();
            let _ = black_box(v.cut(black_box(plane)));
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e6 / reps as f64);
    }
    best
}

/// The median warm frame of the first grid (the CT head when present), without and with
/// five planes each cutting a thin slab or a corner, alternating.
fn clipped_frames(frames: usize, n: usize) -> Result<(String, f64, f64), CmdError> {
    let mut all = grids(n)?;
    let pick = all.iter().position(|g| g.0 == "ct-head").unwrap_or(0);
    let (name, volume, tf) = all.swap_remove(pick);
    let b = volume.bounds();
    let (c, size) = (b.center(), b.max - b.min);
    let mut renderer = create_renderer(&volume, &Method::Auto)?;
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let mut scene = Scene::new(spec.resolve(&b)?, 512, 512, tf);
    let plain = scene.clone();
    for n in [
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Z,
        DVec3::ONE.normalize(),
    ] {
        let reach = 0.45 * n.abs().dot(size);
        scene
            .clip_planes
            .push(ClipPlane::new(n.x, n.y, n.z, reach - n.dot(c))?);
    }
    frame(renderer.as_mut(), &plain)?;
    let (mut a, mut z) = (vec![], vec![]);
    for _ in 0..frames {
        a.push(frame(renderer.as_mut(), &plain)?.stats.ms);
        z.push(frame(renderer.as_mut(), &scene)?.stats.ms);
    }
    Ok((name, median(&mut a), median(&mut z)))
}
