//! `volux bench --suite voi`: the volume of interest of issue 18 (seed `004` ch. 4): a plane
//! cut of the 8-vertex data box and of a polyhedron of about 578 vertices (the seed's
//! figures: 0.15 ms and 1.3 ms; targets 10 and 200 us), one eraser disc on a 512x512x460
//! mask and one dig (targets 50 ms, [`sculpt`]), and a grid frame with five clip planes
//! and a mask against the same frame without (target: at most 10 % slower).
use std::hint::black_box;
use std::time::Instant;

use glam::DVec3;
use serde_json::json;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::Aabb;
use volux_render::engine::create_renderer;
use volux_render::scene::{Method, Scene};

use super::common::{frame, grid_of, grids, median};
use super::sculpt;
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
    let (ms_erase, erased) = sculpt::eraser_ms(frames.max(5))?;
    let f = clipped_frames(frames.max(3), n)?;
    if !as_json {
        outln!(
            "\nVolume of interest (issue 18); threads: {}",
            rayon::current_num_threads()
        )?;
        outln!(
            "plane cut, {} vertices: {us_small:.2} us (target 10)",
            small.vertices().len()
        )?;
        outln!(
            "plane cut, {} vertices: {us_big:.2} us (target 200)",
            big.vertices().len()
        )?;
        let [x, y, z] = sculpt::ERASER_DIMS;
        outln!(
            "eraser disc r={} px at 512x512 on a {x}x{y}x{z} mask: {ms_erase:.1} ms, {erased} \
             voxels (target 50)",
            sculpt::ERASER_RADIUS_PX
        )?;
        f.print()?;
    }
    Ok(vec![json!({
        "suite": "voi", "cut_us_8": us_small, "cut_us_many": us_big,
        "many_vertices": big.vertices().len(), "eraser_ms": ms_erase,
        "eraser_voxels": erased, "dataset": f.name, "dig_ms": f.dig_ms, "ms": f.plain,
        "ms_five_planes": f.planes, "ratio": f.planes / f.plain,
        "ms_planes_mask": f.masked, "ratio_planes_mask": f.masked / f.plain,
    })])
}

/// The frame figures: median ms without planes, with five planes, with the planes and a
/// mask, and of one dig.
struct Frames {
    name: String,
    plain: f64,
    planes: f64,
    masked: f64,
    dig_ms: Option<f64>,
}

impl Frames {
    fn print(&self) -> std::io::Result<()> {
        match self.dig_ms {
            Some(ms) => outln!(
                "{} dig r={} px at the image centre: {ms:.1} ms (target 50)",
                self.name,
                sculpt::DIG_RADIUS_PX
            )?,
            None => outln!("{}: the centre pixel shows no surface to dig", self.name)?,
        }
        outln!(
            "{} 512x512 riemann 0.5: {:.1} ms, with five clip planes {:.1} ms ({:.2}x), with \
             the planes and a mask {:.1} ms ({:.2}x, target <= 1.10x)",
            self.name,
            self.plain,
            self.planes,
            self.planes / self.plain,
            self.masked,
            self.masked / self.plain
        )?;
        Ok(())
    }
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

/// The median warm frame of the first grid (the CT head when present), without planes,
/// with five planes each cutting a thin slab or a corner, and with the planes and a mask
/// (the digs timed on it and two eraser discs), in turn.
fn clipped_frames(frames: usize, n: usize) -> Result<Frames, CmdError> {
    let mut all = grids(n)?;
    let pick = all.iter().position(|g| g.0 == "ct-head").unwrap_or(0);
    let (name, volume, tf) = all.swap_remove(pick);
    let grid = grid_of(&volume).ok_or("the VOI frames need a grid")?;
    let plain = Scene::new(sculpt::oblique(grid)?, 512, 512, tf);
    let (dig_ms, state) = sculpt::dig_ms(grid, &plain, 5)?;
    let planes = five_planes(&plain, &volume.bounds())?;
    let mut masked = planes.clone();
    masked.mask = Some(sculpt::frame_mask(state, &plain)?);
    let mut renderer = create_renderer(&volume, &Method::Auto)?;
    frame(renderer.as_mut(), &plain)?;
    let mut ms = [vec![], vec![], vec![]];
    for _ in 0..frames {
        for (times, scene) in ms.iter_mut().zip([&plain, &planes, &masked]) {
            times.push(frame(renderer.as_mut(), scene)?.stats.ms);
        }
    }
    let [a, b, c] = ms.map(|mut t| median(&mut t));
    Ok(Frames {
        name,
        plain: a,
        planes: b,
        masked: c,
        dig_ms,
    })
}

/// `scene` with five planes each cutting 5 % off a side or a corner of `b`.
fn five_planes(scene: &Scene, b: &Aabb) -> Result<Scene, CmdError> {
    let (c, size) = (b.center(), b.max - b.min);
    let mut out = scene.clone();
    for n in [
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Z,
        DVec3::ONE.normalize(),
    ] {
        let reach = 0.45 * n.abs().dot(size);
        out.clip_planes
            .push(ClipPlane::new(n.x, n.y, n.z, reach - n.dot(c))?);
    }
    Ok(out)
}
