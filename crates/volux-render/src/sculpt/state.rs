//! The sculpt state of one grid: the clipping planes, the mask and the picked points, built by
//! a list of [`SculptStep`]s with undo and redo. Every step is stored resolved (a dig keeps
//! the ball it removed, an eraser stroke its camera and image size), so that replaying the
//! steps rebuilds the same mask bit for bit whatever the transfer function is then: a session
//! file saves the steps, not the mask.
use std::sync::Arc;

use glam::DVec3;
use volux_core::sculpt::{
    Ball, LabelSeed, MaskEdit, RegionRule, ScreenStroke, SculptMask, VoxelFrame,
};
use volux_core::voi::ClipPlane;
use volux_core::{Camera, Grid, Projection};

use super::labels::LabelVolume;
use super::pick::{pick, SurfacePoint, DEFAULT_PICK_OPACITY};
use crate::error::{RenderError, Setting, SettingError};
use crate::scene::Scene;

/// One step of sculpting, as saved in a session.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "tool", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SculptStep {
    /// A clipping plane added (seed `004` sec. 4.3).
    AddPlane {
        /// The plane.
        plane: ClipPlane,
    },
    /// Plane `index` moved or tilted.
    SetPlane {
        /// Which plane.
        index: usize,
        /// Its new position.
        plane: ClipPlane,
    },
    /// Plane `index` removed.
    RemovePlane {
        /// Which plane.
        index: usize,
    },
    /// An eraser stroke (sec. 4.4): a disc of `radius_px` pixels swept along `points`, pixel
    /// positions of `camera` in an image of `size` (width, height).
    Erase {
        /// The camera the stroke was drawn in.
        camera: Camera,
        /// The image size, pixels.
        size: [usize; 2],
        /// The stroke, pixels (x right, y down).
        points: Vec<[f64; 2]>,
        /// The disc radius, pixels.
        radius_px: f64,
    },
    /// A dig (sec. 4.5): the ball removed, picked at `pixel` with a radius of `radius_px`
    /// pixels converted to world units at the picked depth.
    Dig {
        /// Where the user dug, pixels.
        pixel: [f64; 2],
        /// The radius on the screen, pixels.
        radius_px: f64,
        /// The ball's centre, world.
        centre: DVec3,
        /// Its radius, world units.
        radius: f64,
    },
    /// A measurement point (sec. 6.2); `new_line` starts a new polyline.
    Measure {
        /// The picked world point.
        point: DVec3,
        /// Whether it starts a new polyline.
        new_line: bool,
    },
    /// A labelling seed (sec. 6.2): the visible voxels `rule` gives it (the nearest, or those
    /// connected to `point`) take `label`, drawn in `colour` (linear RGB).
    Label {
        /// The picked world point.
        point: DVec3,
        /// The label, 1 to 255.
        label: u8,
        /// Its colour.
        colour: [f32; 3],
        /// How the seed claims voxels. A session saved before the rule existed has none: its
        /// seeds are [`RegionRule::Nearest`], as they were; nearest is left out when saved
        /// (such a session still opens in a build without the field).
        #[serde(default, skip_serializing_if = "RegionRule::is_nearest")]
        rule: RegionRule,
    },
}

/// What undoing a step puts back.
#[derive(Clone, Debug)]
enum Undo {
    Mask(MaskEdit),
    Planes(Vec<ClipPlane>),
    Nothing,
}

/// The sculpt state of a grid: see the [module documentation](self).
#[derive(Clone, Debug)]
pub struct Sculpt {
    frame: VoxelFrame,
    mask: Arc<SculptMask>,
    planes: Vec<ClipPlane>,
    done: Vec<(SculptStep, Undo)>,
    undone: Vec<SculptStep>,
}

impl Sculpt {
    /// Nothing removed from `grid` yet.
    pub fn new(grid: &Grid) -> Result<Self, RenderError> {
        Ok(Self {
            frame: VoxelFrame::of(grid),
            mask: Arc::new(SculptMask::new(grid.dims())?),
            planes: Vec::new(),
            done: Vec::new(),
            undone: Vec::new(),
        })
    }

    /// The state `steps` build on `grid` (a saved session), undoable step by step.
    pub fn replay(grid: &Grid, steps: &[SculptStep]) -> Result<Self, RenderError> {
        let mut s = Self::new(grid)?;
        for (n, step) in steps.iter().enumerate() {
            s.apply(step.clone()).map_err(|e| RenderError::SculptStep {
                step: n + 1,
                steps: steps.len(),
                source: Box::new(e),
            })?;
        }
        Ok(s)
    }

    /// The state with a saved mask as its starting point (`volux sculpt --mask`): the mask
    /// must be the grid's size.
    pub fn with_mask(mut self, mask: SculptMask) -> Result<Self, RenderError> {
        if mask.dims() != self.frame.dims {
            return Err(RenderError::LayerMismatch {
                layer: "sculpt mask",
                layer_dims: mask.dims(),
                grid_dims: self.frame.dims,
            });
        }
        self.mask = Arc::new(mask);
        Ok(self)
    }

    /// Applies `step` (the redo list is dropped). Errors, changing nothing, on a step that
    /// cannot apply (a plane index out of range, a radius of zero, a cut leaving nothing).
    pub fn apply(&mut self, step: SculptStep) -> Result<(), RenderError> {
        let undo = self.run(&step)?;
        self.done.push((step, undo));
        self.undone.clear();
        Ok(())
    }

    fn run(&mut self, step: &SculptStep) -> Result<Undo, RenderError> {
        let no_plane = |index: usize, action: &'static str, planes: usize| {
            Err(RenderError::NoSuchPlane {
                index,
                action,
                planes,
            })
        };
        let planes_before = self.planes.clone();
        match step {
            SculptStep::AddPlane { plane } => {
                plane.check()?;
                self.planes.push(*plane);
            }
            SculptStep::SetPlane { index, plane } => {
                plane.check()?;
                match self.planes.get_mut(*index) {
                    Some(p) => *p = *plane,
                    None => return no_plane(*index, "move", planes_before.len()),
                }
            }
            SculptStep::RemovePlane { index } => {
                if *index >= self.planes.len() {
                    return no_plane(*index, "remove", self.planes.len());
                }
                self.planes.remove(*index);
            }
            SculptStep::Erase {
                camera,
                size,
                points,
                radius_px,
            } => {
                let stroke =
                    ScreenStroke::new(camera, (size[0], size[1]), points, *radius_px, self.frame)?;
                return Ok(Undo::Mask(Arc::make_mut(&mut self.mask).remove(&stroke)));
            }
            SculptStep::Dig { centre, radius, .. } => {
                let ball = Ball::new(*centre, *radius, self.frame)?;
                return Ok(Undo::Mask(Arc::make_mut(&mut self.mask).remove(&ball)));
            }
            SculptStep::Measure { point, .. } | SculptStep::Label { point, .. } => {
                if !point.is_finite() {
                    return Err(SettingError::new(Setting::PickedPoint, point, "finite").into());
                }
                if matches!(step, SculptStep::Label { label: 0, .. }) {
                    return Err(SettingError::new(Setting::Label, 0, "from 1 to 255").into());
                }
                return Ok(Undo::Nothing);
            }
        }
        Ok(Undo::Planes(planes_before))
    }

    /// Undoes the last step; `false` when there is none.
    pub fn undo(&mut self) -> bool {
        let Some((step, undo)) = self.done.pop() else {
            return false;
        };
        match undo {
            Undo::Mask(edit) => Arc::make_mut(&mut self.mask).restore(&edit),
            Undo::Planes(p) => self.planes = p,
            Undo::Nothing => {}
        }
        self.undone.push(step);
        true
    }

    /// Redoes the last undone step; `false` when there is none.
    pub fn redo(&mut self) -> Result<bool, RenderError> {
        let Some(step) = self.undone.pop() else {
            return Ok(false);
        };
        let undo = self.run(&step)?;
        self.done.push((step, undo));
        Ok(true)
    }

    /// Whether there is a step to undo, and one to redo.
    pub fn can_undo_redo(&self) -> (bool, bool) {
        (!self.done.is_empty(), !self.undone.is_empty())
    }

    /// The steps applied, in order (what a session saves).
    pub fn steps(&self) -> Vec<SculptStep> {
        self.done.iter().map(|(s, _)| s.clone()).collect()
    }

    /// The mask.
    pub fn mask(&self) -> &Arc<SculptMask> {
        &self.mask
    }

    /// The clipping planes.
    pub fn planes(&self) -> &[ClipPlane] {
        &self.planes
    }

    /// The measurement polylines, in the order picked.
    pub fn measurements(&self) -> Vec<Vec<DVec3>> {
        let mut lines: Vec<Vec<DVec3>> = Vec::new();
        for (step, _) in &self.done {
            if let SculptStep::Measure { point, new_line } = step {
                match lines.last_mut() {
                    Some(line) if !new_line => line.push(*point),
                    _ => lines.push(vec![*point]),
                }
            }
        }
        lines
    }

    /// The labelling seeds with their colours.
    pub fn label_seeds(&self) -> Vec<(LabelSeed, [f32; 3])> {
        self.done
            .iter()
            .filter_map(|(step, _)| match step {
                SculptStep::Label {
                    point,
                    label,
                    colour,
                    rule,
                } => Some((
                    LabelSeed {
                        point: *point,
                        label: *label,
                        rule: *rule,
                    },
                    *colour,
                )),
                _ => None,
            })
            .collect()
    }

    /// The label volume (sec. 6.2): the visible voxels of the volume of interest (kept by
    /// the planes and the mask, with a non-zero extinction under `scene`'s transfer function)
    /// take the labels of the labelling seeds by each seed's rule
    /// ([`volux_core::sculpt::label_regions`]: connected seeds grow through the visible
    /// voxels, nearest seeds take the rest by world distance); 0 elsewhere. One byte per
    /// voxel, x fastest. Errors without seeds.
    pub fn labels(&self, grid: &Grid, scene: &Scene) -> Result<Vec<u8>, RenderError> {
        let seeds: Vec<_> = self.label_seeds().into_iter().map(|(s, _)| s).collect();
        let tf = scene.appearance.effective_tf().resolved(grid.range());
        let frame = self.frame;
        let visible = |i: usize, j: usize, k: usize| {
            let w = frame.world(DVec3::new(i as f64, j as f64, k as f64));
            self.mask.voxel(i, j, k)
                && self
                    .planes
                    .iter()
                    .all(|p| p.normal.dot(w) + p.offset >= 0.0)
                && tf.tau_per_world(f64::from(grid.value(i, j, k))) > 0.0
        };
        Ok(volux_core::sculpt::label_regions(&frame, &seeds, visible)?)
    }

    /// [`Sculpt::labels`] with the seeds' colours, ready to draw ([`Scene::labels`]).
    pub fn label_volume(&self, grid: &Grid, scene: &Scene) -> Result<LabelVolume, RenderError> {
        let colours: Vec<(u8, [f32; 3])> = self
            .label_seeds()
            .into_iter()
            .map(|(s, c)| (s.label, c))
            .collect();
        LabelVolume::new(grid.dims(), self.labels(grid, scene)?, &colours)
    }

    /// Puts the planes and the mask (when anything is removed) into `scene`.
    pub fn apply_to(&self, scene: &mut Scene) {
        scene.clip_planes = self.planes.clone();
        scene.mask = (!self.mask.is_untouched()).then(|| self.mask.clone());
    }

    /// The visible surface under `pixel` in `scene` with this state's planes and mask.
    pub fn pick(
        &self,
        grid: &Grid,
        scene: &Scene,
        pixel: [f64; 2],
    ) -> Result<Option<SurfacePoint>, RenderError> {
        let mut scene = scene.clone();
        self.apply_to(&mut scene);
        pick(grid, &scene, (pixel[0], pixel[1]), DEFAULT_PICK_OPACITY)
    }

    /// Digs at `pixel` of `scene` (sec. 4.5): picks the visible surface there and removes the
    /// ball whose radius is `radius_px` pixels at that depth. Returns the point dug at, or
    /// `None` (nothing changed) when the pixel shows no surface.
    pub fn dig(
        &mut self,
        grid: &Grid,
        scene: &Scene,
        pixel: [f64; 2],
        radius_px: f64,
    ) -> Result<Option<SurfacePoint>, RenderError> {
        let Some(hit) = self.pick(grid, scene, pixel)? else {
            return Ok(None);
        };
        let radius = radius_px * pixel_size_at(&scene.view.camera, scene.view.height, hit.depth);
        self.apply(SculptStep::Dig {
            pixel,
            radius_px,
            centre: hit.world,
            radius,
        })?;
        Ok(Some(hit))
    }
}

/// The world size of one pixel at view depth `depth` for `camera` in an image `height` pixels
/// high.
pub fn pixel_size_at(camera: &Camera, height: usize, depth: f64) -> f64 {
    let h = height.max(1) as f64;
    match camera.projection {
        Projection::Perspective { fov_y_deg } => {
            2.0 * depth.max(0.0) * (fov_y_deg.to_radians() * 0.5).tan() / h
        }
        Projection::Orthographic { height } => height / h,
    }
}

/// The length of a polyline (world units: millimetres for medical data).
pub fn polyline_length(points: &[DVec3]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).length()).sum()
}
