//! What the sculpting tools do to the viewer's state (seed `004_*.txt` ch. 4-6): every change
//! is a [`SculptStep`] of the engine's [`Sculpt`] (undoable, saved in sessions), applied on
//! the UI thread (a plane, a stroke or a ball touches only the bricks it crosses); counting and
//! exporting labels, and writing NRRD files, run as background jobs.
//!
//! A mesh gets planes only (sec. 4.3): its [`Sculpt`] lives on a 2x2x2 stand-in grid over the
//! mesh's box, whose mask no tool touches.
use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::{Aabb, Buffer, Grid, Samples};
use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::{Sculpt, SculptStep};
use volux_render::session::Session;

use crate::app::ViewerApp;
use crate::jobs::{Job, Poll};

impl ViewerApp {
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
                self.error = Some(e);
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
                self.error = Some(e.to_string());
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
            .and_then(|_| sculpt.apply(step).map_err(|e| e.to_string()));
        match result {
            Ok(()) => {
                self.error = None;
                self.tools.label_counts = None;
                true
            }
            Err(e) => {
                self.error = Some(e);
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
                self.error = Some(e.to_string());
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
            Err(e) => self.error = Some(e.to_string()),
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
            Ok(None) => self.error = Some(missed(pixel)),
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// The visible surface under `pixel`, or the error shown.
    fn pick_at(&mut self, pixel: [f64; 2]) -> Option<DVec3> {
        let (grid, sculpt) = (self.sculpt_grid()?, self.sculpt.as_ref()?);
        match sculpt.pick(&grid, &self.pick_scene(), pixel) {
            Ok(Some(hit)) => Some(hit.world),
            Ok(None) => {
                self.error = Some(missed(pixel));
                None
            }
            Err(e) => {
                self.error = Some(e.to_string());
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

    /// A labelling seed at the surface point under `pixel` with the tools' label and colour.
    pub fn label_at(&mut self, pixel: [f64; 2]) {
        if let Some(point) = self.pick_at(pixel) {
            let (label, colour) = (self.tools.label, self.tools.colour);
            self.sculpt_step(SculptStep::Label {
                point,
                label,
                colour,
            });
        }
    }

    /// Counts the voxels of each label (sec. 6.2) in the background.
    pub fn compute_labels(&mut self) {
        let Some(work) = self.labels_work() else {
            return;
        };
        self.tools.label_counts = None;
        self.tools.labels_job = Some(Job::spawn("labelling", move || {
            work().map(|labels| label_counts(&labels))
        }));
    }

    /// The label volume's computation on the current state, to run on a job thread.
    fn labels_work(&mut self) -> Option<impl FnOnce() -> Result<Vec<u8>, String> + Send> {
        let (grid, sculpt) = (self.sculpt_grid(), self.sculpt.clone());
        let (Some(grid), Some(sculpt)) = (grid, sculpt) else {
            self.error = Some("labels apply to grids".into());
            return None;
        };
        if sculpt.label_seeds().is_empty() {
            self.error = Some("pick labelling seeds first (the Label tool)".into());
            return None;
        }
        let scene = self.scene.clone();
        Some(move || sculpt.labels(&grid, &scene).map_err(|e| e.to_string()))
    }

    /// Takes the label counts once counted.
    pub(crate) fn poll_sculpt_jobs(&mut self) {
        if let Some(job) = &mut self.tools.labels_job {
            if let Poll::Done(r) = job.poll() {
                self.tools.labels_job = None;
                match r {
                    Ok(counts) => self.tools.label_counts = Some(counts),
                    Err(e) => self.error = Some(e),
                }
            }
        }
    }

    /// Writes the mask (1 kept, 0 removed) to `path` as NRRD `u8` with the data's geometry,
    /// in the background.
    pub fn export_mask(&mut self, path: &Path) -> Result<(), String> {
        let (Some(grid), Some(sculpt)) = (self.sculpt_grid(), self.sculpt.as_ref()) else {
            return Err("a mask needs a grid dataset".into());
        };
        let mask = sculpt.mask().clone();
        let path = path.to_path_buf();
        self.export_job = Some(Job::spawn("exporting the mask", move || {
            write_u8(&grid, mask.to_values(), &path)
        }));
        Ok(())
    }

    /// Writes the label volume to `path` as NRRD `u8`, in the background.
    pub fn export_labels(&mut self, path: &Path) -> Result<(), String> {
        let grid = self.sculpt_grid().ok_or("labels apply to grids")?;
        let work = self.labels_work().ok_or("no labels to export")?;
        let path = path.to_path_buf();
        self.export_job = Some(Job::spawn("exporting the labels", move || {
            write_u8(&grid, work()?, &path)
        }));
        Ok(())
    }
}

/// A sculpt state for `volume`: a grid's own, or planes only on a mesh's box.
fn sculpt_on(volume: &Volume) -> Result<Sculpt, String> {
    let grid = match volume {
        Volume::Grid(g) => return Sculpt::new(g).map_err(|e| e.to_string()),
        other => stand_in(&other.bounds())?,
    };
    Sculpt::new(&grid).map_err(|e| e.to_string())
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

/// The voxel count of every label present (label 0, unlabelled, left out).
pub fn label_counts(labels: &[u8]) -> Vec<(u8, u64)> {
    let mut counts = [0u64; 256];
    for &l in labels {
        counts[l as usize] += 1;
    }
    (1..=255u8)
        .filter(|&l| counts[l as usize] > 0)
        .map(|l| (l, counts[l as usize]))
        .collect()
}

/// Writes `values` as an NRRD `u8` volume with `grid`'s geometry (3D Slicer opens it).
fn write_u8(grid: &Grid, values: Vec<u8>, path: &Path) -> Result<String, String> {
    let out = Grid::new(
        grid.dims(),
        grid.spacing().to_array(),
        grid.origin().to_array(),
        Samples::U8(Buffer::owned(values)),
    )
    .and_then(|g| g.with_direction(grid.direction()))
    .map_err(|e| e.to_string())?;
    volux_io::nrrd::write(&out, path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(format!("saved {}", path.display()))
}
