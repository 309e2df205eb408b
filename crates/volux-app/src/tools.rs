//! The seed's interactive tools on a grid in a view (seed `004` sec. 4.4-4.5 and 6.2): the
//! eraser, the digger, measurement and region labelling, for the front ends that apply them
//! without a window (`volux sculpt|measure|regions`, the Python bindings). A [`Workbench`]
//! holds the grid, the scene it is seen in and the sculpt state the scene's clip planes and
//! mask start.
use std::sync::Arc;

use glam::DVec3;
use volux_core::sculpt::RegionRule;
use volux_core::Grid;
use volux_render::scene::Scene;
use volux_render::sculpt::{polyline_length, Sculpt, SculptStep, SurfacePoint};

use crate::error::AppError;

/// A grid, the scene it is seen in, and its sculpt state.
pub struct Workbench {
    /// The grid.
    pub grid: Arc<Grid>,
    /// The scene (its clip planes and mask moved into [`Workbench::sculpt`]).
    pub scene: Scene,
    /// The sculpt state: the scene's clip planes and mask, then the tools applied.
    pub sculpt: Sculpt,
}

impl Workbench {
    /// The workbench of `grid` seen in `scene`: the scene's clip planes and mask start the
    /// sculpt state (so that picks and tools see what the picture shows).
    pub fn new(grid: Arc<Grid>, mut scene: Scene) -> Result<Self, AppError> {
        let mut sculpt = Sculpt::new(&grid)?;
        for plane in std::mem::take(&mut scene.clip_planes) {
            sculpt.apply(SculptStep::AddPlane { plane })?;
        }
        if let Some(mask) = scene.mask.take() {
            sculpt = sculpt.with_mask(Arc::unwrap_or_clone(mask))?;
        }
        Ok(Self {
            grid,
            scene,
            sculpt,
        })
    }

    /// The image size of the view, in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.scene.view.width, self.scene.view.height)
    }

    /// Whether `pixel` lies in the image.
    pub fn in_image(&self, [x, y]: [f64; 2]) -> bool {
        let (w, h) = self.size();
        (0.0..=w as f64).contains(&x) && (0.0..=h as f64).contains(&y)
    }

    /// The visible surface under `pixel` (opacity 0.5 along its ray, after the clip planes
    /// and the mask); `None` where the ray meets none.
    pub fn pick(&self, pixel: [f64; 2]) -> Result<Option<SurfacePoint>, AppError> {
        Ok(self.sculpt.pick(&self.grid, &self.scene, pixel)?)
    }

    /// The world points under `pixels` and the length of the polyline through them (world
    /// units: the grid's [`Grid::unit`]); `Err(index)` names the first pixel that shows no
    /// surface.
    pub fn measure(
        &self,
        pixels: &[[f64; 2]],
    ) -> Result<Result<(Vec<DVec3>, f64), usize>, AppError> {
        let mut points = Vec::with_capacity(pixels.len());
        for (n, pixel) in pixels.iter().enumerate() {
            match self.pick(*pixel)? {
                Some(hit) => points.push(hit.world),
                None => return Ok(Err(n)),
            }
        }
        let length = polyline_length(&points);
        Ok(Ok((points, length)))
    }

    /// The eraser: a disc of `radius` pixels swept through `points` removes what it covers,
    /// through the whole depth (seed `004` sec. 4.4). Returns the voxels removed.
    pub fn erase(&mut self, points: Vec<[f64; 2]>, radius: f64) -> Result<u64, AppError> {
        let before = self.sculpt.mask().removed_count();
        let (w, h) = self.size();
        self.sculpt.apply(SculptStep::Erase {
            camera: self.scene.view.camera,
            size: [w, h],
            points,
            radius_px: radius,
        })?;
        Ok(self.sculpt.mask().removed_count() - before)
    }

    /// The digger: a ball of `radius` pixels' width removed where `pixel` meets the visible
    /// surface (seed `004` sec. 4.5). Returns the voxels removed, `None` where the pixel
    /// shows no surface.
    pub fn dig(&mut self, pixel: [f64; 2], radius: f64) -> Result<Option<u64>, AppError> {
        let before = self.sculpt.mask().removed_count();
        let (grid, scene) = (self.grid.clone(), self.scene.clone());
        Ok(self
            .sculpt
            .dig(&grid, &scene, pixel, radius)?
            .map(|_| self.sculpt.mask().removed_count() - before))
    }

    /// A region seed at the visible surface under `pixel` with `label` (1 to 255) claiming
    /// voxels by `rule`; `false` where the pixel shows no surface.
    pub fn seed_region(
        &mut self,
        pixel: [f64; 2],
        label: u8,
        rule: RegionRule,
    ) -> Result<bool, AppError> {
        let Some(hit) = self.pick(pixel)? else {
            return Ok(false);
        };
        // The colour `render --labels` gives the label too.
        let palette = volux_render::sculpt::labels::LABEL_PALETTE;
        let colour = palette[usize::from(label.max(1) - 1) % palette.len()];
        self.sculpt.apply(SculptStep::Label {
            point: hit.world,
            label,
            colour,
            rule,
        })?;
        Ok(true)
    }

    /// The labels the seeds give the visible voxels (one per voxel, x fastest; 0: none).
    pub fn labels(&self) -> Result<Vec<u8>, AppError> {
        Ok(self.sculpt.labels(&self.grid, &self.scene)?)
    }
}
