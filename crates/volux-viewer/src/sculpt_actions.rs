//! What the sculpting tools do to the viewer's state (seed `004_*.txt` ch. 4-6): every change
//! is a [`SculptStep`] of the engine's [`Sculpt`] (undoable, saved in sessions), applied on
//! the UI thread (a plane, a stroke or a ball touches only the bricks it crosses: about 20 ms
//! for a stroke on a 256^3 grid). Labels and exports are in [`crate::sculpt_exports`].
//!
//! A mesh gets planes only (sec. 4.3): its [`Sculpt`] lives on a 2x2x2 stand-in grid over the
//! mesh's box, whose mask no tool touches.
use std::sync::Arc;

use glam::DVec3;
use volux_app::session::Session;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::{Aabb, Buffer, Grid, Samples};
use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::{Sculpt, SculptStep};

use crate::app::ViewerApp;
use crate::sculpt_state::Tool;

impl ViewerApp {
    /// Shows a tool's error (it stays until the next action or dismiss).
    pub(crate) fn show_error(&mut self, message: impl Into<String>) {
        self.error = Some(message.into());
        self.render_error = false;
    }

    /// The grid the mask and picks apply to (`None` for a mesh).
    pub fn sculpt_grid(&self) -> Option<Arc<Grid>> {
        match self.volume()? {
            Volume::Grid(g) => Some(g.clone()),
            _ => None,
        }
    }

    /// A new sculpt state on the loaded dataset holding `planes` (a session's clip planes).
    pub(crate) fn reset_sculpt(&mut self, planes: &[ClipPlane]) {
        self.tools.stroke.clear();
        self.tools.label_counts = None;
        self.tools.labels_job = None;
        if self.sculpt_grid().is_none() {
            self.tools.tool = Tool::Navigate;
        }
        let steps: Vec<_> = planes
            .iter()
            .map(|&plane| SculptStep::AddPlane { plane })
            .collect();
        let Some(volume) = self.volume().cloned() else {
            self.sculpt = None;
            return;
        };
        match sculpt_on(&volume).and_then(|s| replay(s, &steps)) {
            Ok(s) => self.sculpt = Some(s),
            Err(e) => {
                self.sculpt = None;
                self.show_error(e);
            }
        }
    }

    /// The sculpt state of an opened session: its steps replayed on a grid
    /// ([`Session::scene_on`]), else its planes. Steps on a mesh are refused with the engine's
    /// error (shown); the mesh then gets the session's planes.
    pub(crate) fn apply_session_sculpt(&mut self, session: &Session) {
        let Some(volume) = self.volume().cloned() else {
            return;
        };
        match session.scene_on(&volume) {
            Ok((_, Some(sculpt))) => self.sculpt = Some(sculpt),
            Ok((_, None)) => self.reset_sculpt(&session.clip_planes),
            Err(e) => {
                self.reset_sculpt(&session.clip_planes);
                self.show_error(e.to_string());
            }
        }
    }

    /// Applies `step`, showing why when it cannot apply; `true` when it did.
    pub fn sculpt_step(&mut self, step: SculptStep) -> bool {
        let Some(bounds) = self.volume().map(|v| v.bounds()) else {
            return false;
        };
        let Some(sculpt) = &mut self.sculpt else {
            return false;
        };
        let result = planes_after(sculpt.planes(), &step)
            .and_then(|planes| voi_of(&bounds, &planes).map(|_| ()))
            .and_then(|_| sculpt.apply(step).map_err(|e| crate::phrase::phrase(&e)));
        match result {
            Ok(()) => {
                self.error = None;
                self.tools.label_counts = None;
                true
            }
            Err(e) => {
                self.show_error(e);
                false
            }
        }
    }

    /// Undoes the last sculpt step (the next frame shows it).
    pub fn undo(&mut self) {
        if let Some(s) = &mut self.sculpt {
            s.undo();
            self.tools.label_counts = None;
        }
    }

    /// Redoes the last undone step.
    pub fn redo(&mut self) {
        if let Some(s) = &mut self.sculpt {
            if let Err(e) = s.redo() {
                self.show_error(e.to_string());
            }
            self.tools.label_counts = None;
        }
    }

    /// Adds a plane through the centre of the volume of interest facing the camera, keeping
    /// the far half (sec. 4.3).
    pub fn add_plane(&mut self) {
        let Some(centre) = self.voi().map(|v| v.centroid()) else {
            return;
        };
        let camera = self.scene.view.camera;
        let forward = (camera.target - camera.eye).normalize_or_zero();
        match ClipPlane::new(forward.x, forward.y, forward.z, -forward.dot(centre)) {
            Ok(plane) => {
                self.sculpt_step(SculptStep::AddPlane { plane });
            }
            Err(e) => self.show_error(e.to_string()),
        }
    }

    /// Moves plane `index` to `plane`. While `continuing` (the same slider drag) and the last
    /// step moved this plane, that step is replaced: one undo step per gesture.
    pub fn set_plane(&mut self, index: usize, plane: ClipPlane, continuing: bool) {
        let Some(sculpt) = &mut self.sculpt else {
            return;
        };
        let last = sculpt.steps().pop();
        let replace =
            continuing && matches!(last, Some(SculptStep::SetPlane { index: i, .. }) if i == index);
        if replace {
            sculpt.undo();
        }
        if !self.sculpt_step(SculptStep::SetPlane { index, plane }) && replace {
            // Put the drag's last good position back.
            if let (Some(s), Some(step)) = (&mut self.sculpt, last) {
                let _ = s.apply(step);
            }
        }
    }

    /// Removes plane `index`.
    pub fn remove_plane(&mut self, index: usize) {
        self.sculpt_step(SculptStep::RemovePlane { index });
    }

    /// The data's box cut by the planes (sec. 4.3), for the outline.
    pub fn voi(&self) -> Option<ConvexVoi> {
        let bounds = self.volume()?.bounds();
        let planes = self.sculpt.as_ref().map_or(&[][..], |s| s.planes());
        voi_of(&bounds, planes).ok()
    }

    /// The scene the tools pick in: what is rendered, without the sculpt (the sculpt's own
    /// picking adds it; holding no second reference to the mask keeps edits in place).
    pub fn pick_scene(&self) -> Scene {
        let mut scene = self.render_scene();
        scene.mask = None;
        scene.clip_planes.clear();
        scene
    }

    /// Erases the disc of the tools' radius swept along `points`, pixels of the rendered
    /// image (sec. 4.4): one step.
    pub fn erase_stroke(&mut self, points: Vec<[f64; 2]>) {
        if points.is_empty() || self.sculpt_grid().is_none() {
            return;
        }
        let scene = self.pick_scene();
        self.sculpt_step(SculptStep::Erase {
            camera: scene.view.camera,
            size: [scene.view.width, scene.view.height],
            points,
            radius_px: self.tools.radius_px,
        });
    }

    /// Digs at `pixel` of the rendered image (sec. 4.5).
    pub fn dig_at(&mut self, pixel: [f64; 2]) {
        let scene = self.pick_scene();
        let (Some(grid), Some(sculpt)) = (self.sculpt_grid(), self.sculpt.as_mut()) else {
            return;
        };
        match sculpt.dig(&grid, &scene, pixel, self.tools.radius_px) {
            Ok(Some(_)) => {
                self.error = None;
                self.tools.label_counts = None;
            }
            Ok(None) => self.show_error(missed(pixel)),
            Err(e) => self.show_error(e.to_string()),
        }
    }

    /// The visible surface under `pixel`, or the error shown.
    fn pick_at(&mut self, pixel: [f64; 2]) -> Option<DVec3> {
        let (grid, sculpt) = (self.sculpt_grid()?, self.sculpt.as_ref()?);
        match sculpt.pick(&grid, &self.pick_scene(), pixel) {
            Ok(Some(hit)) => Some(hit.world),
            Ok(None) => {
                self.show_error(missed(pixel));
                None
            }
            Err(e) => {
                self.show_error(e.to_string());
                None
            }
        }
    }

    /// Adds the surface point under `pixel` to the measurement (sec. 6.2); `new_line`
    /// starts a new polyline.
    pub fn measure_at(&mut self, pixel: [f64; 2], new_line: bool) {
        if let Some(point) = self.pick_at(pixel) {
            self.sculpt_step(SculptStep::Measure { point, new_line });
        }
    }

    /// A labelling seed at the surface point under `pixel` with the tools' label, colour and
    /// rule.
    pub fn label_at(&mut self, pixel: [f64; 2]) {
        if let Some(point) = self.pick_at(pixel) {
            let (label, colour, rule) = (self.tools.label, self.tools.colour, self.tools.rule);
            self.sculpt_step(SculptStep::Label {
                point,
                label,
                colour,
                rule,
            });
        }
    }
}

/// A sculpt state for `volume`: a grid's own, or planes only on a mesh's box.
fn sculpt_on(volume: &Volume) -> Result<Sculpt, String> {
    let grid = match volume {
        Volume::Grid(g) => return Sculpt::new(g).map_err(|e| crate::phrase::phrase(&e)),
        other => stand_in(&other.bounds())?,
    };
    Sculpt::new(&grid).map_err(|e| crate::phrase::phrase(&e))
}

/// A 2x2x2 grid spanning `bounds` (the frame of a mesh's plane-only sculpt).
fn stand_in(bounds: &Aabb) -> Result<Grid, String> {
    let size = (bounds.max - bounds.min).max(DVec3::splat(1e-9));
    Grid::new(
        [2, 2, 2],
        size.to_array(),
        bounds.min.to_array(),
        Samples::F32(Buffer::owned(vec![0.0; 8])),
    )
    .map_err(|e| e.to_string())
}

fn replay(mut sculpt: Sculpt, steps: &[SculptStep]) -> Result<Sculpt, String> {
    for step in steps {
        sculpt.apply(step.clone()).map_err(|e| e.to_string())?;
    }
    Ok(sculpt)
}

/// The planes once `step` applies (plane steps; others keep them).
fn planes_after(planes: &[ClipPlane], step: &SculptStep) -> Result<Vec<ClipPlane>, String> {
    let mut out = planes.to_vec();
    match step {
        SculptStep::AddPlane { plane } => out.push(*plane),
        SculptStep::SetPlane { index, plane } if *index < out.len() => out[*index] = *plane,
        SculptStep::RemovePlane { index } if *index < out.len() => {
            out.remove(*index);
        }
        SculptStep::SetPlane { index, .. } | SculptStep::RemovePlane { index } => {
            return Err(format!("there is no plane {index}"))
        }
        _ => {}
    }
    Ok(out)
}

/// The box `bounds` cut by `planes`; an error when they leave nothing.
pub fn voi_of(bounds: &Aabb, planes: &[ClipPlane]) -> Result<ConvexVoi, String> {
    let mut voi = ConvexVoi::from_aabb(bounds).map_err(|e| e.to_string())?;
    for p in planes {
        voi.cut(p).map_err(|e| e.to_string())?;
    }
    Ok(voi)
}

fn missed(pixel: [f64; 2]) -> String {
    format!(
        "nothing visible under pixel ({:.0}, {:.0}): pick on the data",
        pixel[0], pixel[1]
    )
}
