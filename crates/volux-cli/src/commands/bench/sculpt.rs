//! The sculpting figures of `volux bench --suite voi` (issue 18, seed `004` sec. 4.4-4.5):
//! one eraser disc on a full-resolution mask of a 512x512x460 grid (the seed: 0.096 s on a
//! 64³ mask), one dig on the CT head, and the mask a frame is drawn with.
use std::sync::Arc;
use std::time::Instant;

use volux_core::sculpt::{ScreenStroke, SculptMask, VoxelFrame};
use volux_core::{Buffer, Camera, CameraSpec, Grid, Samples};
use volux_render::framing::fit_to_box;
use volux_render::scene::Scene;
use volux_render::sculpt::{Sculpt, SculptStep};

use super::common::median;
use crate::commands::common::CmdError;

/// The eraser's grid: the size of a 512x512x460 CT, its spacing in millimetres.
pub const ERASER_DIMS: [usize; 3] = [512, 512, 460];
/// The eraser disc's radius at 512x512, pixels.
pub const ERASER_RADIUS_PX: f64 = 40.0;
/// The dig's radius at 512x512, pixels.
pub const DIG_RADIUS_PX: f64 = 20.0;

/// Median milliseconds of one eraser disc (radius [`ERASER_RADIUS_PX`] at the image centre)
/// on a fresh full-resolution mask of an [`ERASER_DIMS`] grid, seen from an oblique orbit
/// camera framing it, macrocell states included; and the voxels one disc removes.
pub fn eraser_ms(rounds: usize) -> Result<(f64, u64), CmdError> {
    let [x, y, z] = ERASER_DIMS;
    let zeros = Samples::U8(Buffer::owned(vec![0u8; x * y * z]));
    let grid = Grid::new(ERASER_DIMS, [0.45, 0.45, 0.6], [0.0; 3], zeros)?;
    let camera = oblique(&grid)?;
    let stroke = ScreenStroke::new(
        &camera,
        (512, 512),
        &[[256.0, 256.0]],
        ERASER_RADIUS_PX,
        VoxelFrame::of(&grid),
    )?;
    let fresh = SculptMask::new(ERASER_DIMS)?;
    let (mut ms, mut removed) = (Vec::new(), 0);
    for _ in 0..rounds {
        let mut mask = fresh.clone();
        let t = Instant::now();
        let edit = mask.remove(&stroke);
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        removed = edit.removed_voxels();
    }
    Ok((median(&mut ms), removed))
}

/// An orbit camera at azimuth 30, elevation 20 fitted to `grid` in a square image.
pub fn oblique(grid: &Grid) -> Result<Camera, CmdError> {
    let spec = CameraSpec {
        azimuth: Some(30.0),
        elevation: Some(20.0),
        ..Default::default()
    };
    let b = grid.bounds();
    Ok(fit_to_box(&spec.resolve(&b)?, &b, 1.0, 1.0))
}

/// Median milliseconds of a dig (pick and ball of [`DIG_RADIUS_PX`]) at the centre of
/// `scene`, `rounds` digs in a row at that pixel (each goes deeper, as a user digs); the
/// sculpt state after them. `None` when the centre shows no surface.
pub fn dig_ms(
    grid: &Grid,
    scene: &Scene,
    rounds: usize,
) -> Result<(Option<f64>, Sculpt), CmdError> {
    let mut sculpt = Sculpt::new(grid)?;
    let mut ms = Vec::new();
    let centre = [
        scene.view.width as f64 / 2.0,
        scene.view.height as f64 / 2.0,
    ];
    for _ in 0..rounds {
        let t = Instant::now();
        let hit = sculpt.dig(grid, scene, centre, DIG_RADIUS_PX)?;
        if hit.is_none() {
            break;
        }
        ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let ms = (!ms.is_empty()).then(|| median(&mut ms));
    Ok((ms, sculpt))
}

/// The mask of the masked frame: the digs of `sculpt` and two eraser discs off the centre
/// of `scene`'s image.
pub fn frame_mask(mut sculpt: Sculpt, scene: &Scene) -> Result<Arc<SculptMask>, CmdError> {
    let (w, h) = (scene.view.width as f64, scene.view.height as f64);
    for (x, y) in [(0.3, 0.35), (0.7, 0.6)] {
        sculpt.apply(SculptStep::Erase {
            camera: scene.view.camera,
            size: [scene.view.width, scene.view.height],
            points: vec![[x * w, y * h]],
            radius_px: ERASER_RADIUS_PX,
        })?;
    }
    Ok(sculpt.mask().clone())
}
