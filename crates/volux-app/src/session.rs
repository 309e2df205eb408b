//! A session: everything that decides a picture, saved as versioned JSON, so that a view
//! found by hand in the viewer (`volux-view`) is reproduced in batch
//! (`volux render --session S.json -o out.png`) to the same pixels.
//!
//! ```json
//! { "volux_session": 1,
//!   "dataset": { "path": "head.nrrd" },
//!   "width": 800, "height": 600,
//!   "camera": { "eye": [..], "target": [..], "up": [..], "projection": {..} },
//!   "appearance": { "tf": {..}, "opacity_scale": 1.0, "lighting": {..}, "shade_volume": false,
//!                   "isosurfaces": [], "mip": false },
//!   "method": { "name": "grid-raycast", "settings": {..} },
//!   "early_termination": 0.99, "background": [0.0, 0.0, 0.0],
//!   "slices": { "window": [lo, hi], "crosshair": [x, y, z] }, "backend": "auto" }
//! ```
//!
//! A relative dataset path is relative to the folder of the session file. Camera and
//! crosshair are in world coordinates (the dataset's millimetres). The transfer function is
//! the CLI's TF JSON ([`volux_core::TransferFunction`]), the method the engine's
//! [`Method`] with all its settings, so nothing is left to defaults that could change.
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use volux_core::image::{write_atomically, PngOptions};
use volux_core::Camera;

use volux_render::scene::{Appearance, Method, Scene, View, Volume};
use volux_render::sculpt::{Sculpt, SculptStep};

use crate::backend::Backend;
use crate::error::AppError;

/// The session format's version; files of another version are refused.
pub const SESSION_VERSION: u32 = 1;

/// Largest session file read (a TF of thousands of points fits many times over).
pub const MAX_SESSION_BYTES: u64 = 16 << 20;

/// The dataset a session shows, and the reader options it was loaded with.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetRef {
    /// The file or DICOM folder (relative paths: from the session file's folder).
    pub path: PathBuf,
    /// PLOT3D q variable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q_variable: Option<String>,
    /// PLOT3D q file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q_file: Option<PathBuf>,
    /// DICOM series.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series_uid: Option<String>,
    /// VTK point-data array.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub array: Option<String>,
    /// A grid split into tetrahedra (for the mesh methods).
    #[serde(default)]
    pub as_tets: bool,
    /// OME-Zarr, ImageJ hyperstack, OME-TIFF: the channel (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel: Option<usize>,
    /// Files holding several volumes (4-D NIfTI, NRRD, DICOM series with several stacks,
    /// OME-Zarr, ImageJ hyperstack, OME-TIFF): the timepoint (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timepoint: Option<usize>,
    /// Vector and colour volumes: the component read as the scalar (default: the first of a
    /// vector; a colour image keeps its colour).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub component: Option<usize>,
    /// OME-Zarr: a pyramid level read whole into memory (default: the store rendered out of
    /// core when it is over the memory budget, else its full level read whole).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub level: Option<usize>,
}

impl DatasetRef {
    /// The dataset at `path` with the readers' defaults.
    pub fn at(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            ..Self::default()
        }
    }

    /// The reader options this dataset is loaded with: the one translation of a dataset
    /// reference into [`volux_io::LoadOptions`], for every front end.
    pub fn load_options(&self) -> volux_io::LoadOptions {
        volux_io::LoadOptions {
            q_variable: self.q_variable.clone(),
            q_file: self.q_file.clone(),
            series_uid: self.series_uid.clone(),
            array: self.array.clone(),
            level: self.level,
            channel: self.channel.unwrap_or(0),
            timepoint: self.timepoint.unwrap_or(0),
            component: self.component,
        }
    }
}

/// The slice views' state: the window (values mapped to black and white) and the
/// crosshair point the three slices pass through (world coordinates).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceState {
    /// `[lowest, highest]` value shown, black to white.
    pub window: [f64; 2],
    /// The point the three slices pass through.
    pub crosshair: [f64; 3],
}

/// A saved view: dataset, camera, image size, appearance, method and slice state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    /// Always [`SESSION_VERSION`].
    pub volux_session: u32,
    /// What is shown.
    pub dataset: DatasetRef,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The camera, world coordinates.
    pub camera: Camera,
    /// Transfer function, lighting, isosurfaces, MIP.
    pub appearance: Appearance,
    /// The renderer and all its settings.
    pub method: Method,
    /// Early ray termination opacity (`null`: none).
    pub early_termination: Option<f32>,
    /// Clipping planes of the volume of interest ([`Scene::clip_planes`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip_planes: Vec<volux_core::voi::ClipPlane>,
    /// The sculpting steps (planes, eraser strokes, digs, picked points), replayed on the
    /// dataset to rebuild the mask ([`Sculpt::replay`]); when there are steps, the planes are
    /// those they make.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sculpt: Vec<SculptStep>,
    /// Colour under the transparent parts of the picture (`null`: a transparent PNG).
    pub background: Option<[f32; 3]>,
    /// The slice views, when the viewer saved them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slices: Option<SliceState>,
    /// Where the session is rendered (`volux render --session` follows it unless
    /// `--backend` is given; `null`: the CPU engine, the reference).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backend: Option<Backend>,
}

impl Session {
    /// The session of `scene` on `dataset`.
    pub fn new(dataset: DatasetRef, scene: &Scene, background: Option<[f32; 3]>) -> Self {
        Self {
            volux_session: SESSION_VERSION,
            dataset,
            width: scene.view.width,
            height: scene.view.height,
            camera: scene.view.camera,
            appearance: scene.appearance.clone(),
            method: scene.method,
            early_termination: scene.early_termination,
            clip_planes: scene.clip_planes.clone(),
            sculpt: Vec::new(),
            background,
            slices: None,
            backend: None,
        }
    }

    /// This session with the steps of `sculpt`, its planes as the session's planes.
    pub fn with_sculpt(mut self, sculpt: &Sculpt) -> Self {
        self.sculpt = sculpt.steps();
        self.clip_planes = sculpt.planes().to_vec();
        self
    }

    /// The scene this session renders on `volume`: [`Session::scene`] with the sculpt steps
    /// replayed on a grid (their mask and planes); the sculpt state is returned too.
    pub fn scene_on(&self, volume: &Volume) -> Result<(Scene, Option<Sculpt>), AppError> {
        let mut scene = self.scene();
        if self.sculpt.is_empty() {
            return Ok((scene, None));
        }
        let Volume::Grid(grid) = volume else {
            return Err(AppError::SculptOnMesh);
        };
        let sculpt = Sculpt::replay(grid, &self.sculpt)?;
        sculpt.apply_to(&mut scene);
        Ok((scene, Some(sculpt)))
    }

    /// The scene this session renders, without the sculpt steps' mask (see
    /// [`Session::scene_on`]).
    pub fn scene(&self) -> Scene {
        Scene {
            view: View {
                camera: self.camera,
                width: self.width,
                height: self.height,
            },
            appearance: self.appearance.clone(),
            method: self.method,
            early_termination: self.early_termination,
            clip_planes: self.clip_planes.clone(),
            mask: None,
            labels: None,
        }
    }

    /// How the picture is written: over [`Session::background`], 8 bits.
    pub fn png_options(&self) -> PngOptions {
        PngOptions {
            background: self.background,
            sixteen_bit: false,
        }
    }

    /// Parses and checks a session (`origin` names it in errors): the version, the fields,
    /// and the scene it describes.
    pub fn from_json(text: &str, origin: &str) -> Result<Self, AppError> {
        let fail = |reason: String| AppError::Session {
            path: origin.to_string(),
            reason,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| fail(format!("not JSON: {e}")))?;
        match value.get("volux_session").and_then(|v| v.as_u64()) {
            Some(v) if v == SESSION_VERSION as u64 => {}
            Some(v) => {
                return Err(fail(format!(
                    "version {v}; this volux reads version {SESSION_VERSION}"
                )))
            }
            None => return Err(fail("no \"volux_session\" version: not a session".into())),
        }
        let session: Session = serde_json::from_value(value).map_err(|e| fail(e.to_string()))?;
        session
            .scene()
            .validate()
            .map_err(|e| fail(e.to_string()))?;
        session
            .method
            .check_appearance(&session.appearance)
            .map_err(|e| fail(e.to_string()))?;
        Ok(session)
    }

    /// The session as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a session always serializes")
    }

    /// Reads a session file; a relative dataset path becomes relative to the file's folder.
    pub fn load(path: &Path) -> Result<Self, AppError> {
        let origin = path.display().to_string();
        let fail = |reason: String| AppError::Session {
            path: origin.clone(),
            reason,
        };
        let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
        if !meta.is_file() {
            return Err(fail("not a regular file".into()));
        }
        if meta.len() > MAX_SESSION_BYTES {
            return Err(fail(format!(
                "{} bytes; a session is at most {MAX_SESSION_BYTES}",
                meta.len()
            )));
        }
        let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
        let mut session = Self::from_json(&text, &origin)?;
        if session.dataset.path.is_relative() {
            let folder = path.parent().unwrap_or(Path::new(""));
            session.dataset.path = folder.join(&session.dataset.path);
        }
        Ok(session)
    }

    /// Writes the session (to a temporary name, then renamed). The dataset path, relative
    /// to the working folder in memory, is written relative to the session's folder when
    /// the dataset lies inside it (the two move together), absolute otherwise.
    pub fn save(&self, path: &Path) -> Result<(), AppError> {
        let mut saved = self.clone();
        saved.dataset.path = path_for_session(&self.dataset.path, path);
        write_atomically(path, saved.to_json().as_bytes()).map_err(|e| AppError::Session {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
    }
}

/// `dataset` (relative to the working folder) as a session file at `session` names it.
fn path_for_session(dataset: &Path, session: &Path) -> PathBuf {
    let cwd = std::env::current_dir().unwrap_or_default();
    let absolute = |p: &Path| {
        let p = if p.is_relative() {
            cwd.join(p)
        } else {
            p.to_path_buf()
        };
        p.canonicalize().unwrap_or(p)
    };
    let data = absolute(dataset);
    let folder = absolute(session.parent().unwrap_or(Path::new("")));
    match data.strip_prefix(&folder) {
        Ok(inside) => inside.to_path_buf(),
        Err(_) => data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::{synth, CameraSpec};
    use volux_render::integrate::integrator::Integrator;
    use volux_render::isosurface::{Isosurfaces, Isovalue};
    use volux_render::scene::GridRaycast;

    fn scene() -> Scene {
        let grid = synth::marschner_lobb(8).unwrap();
        let camera = CameraSpec::default().resolve(&grid.bounds()).unwrap();
        let tf = volux_core::TransferFunction::from_json(
            r#"{"color": [[0, 0, 0, 1], [1, 1, 0.5, 0]], "extinction": [[0, 0], [1, 2]]}"#,
        )
        .unwrap();
        let mut s = Scene::new(camera, 40, 30, tf);
        s.method = Method::GridRaycast(GridRaycast {
            integrator: Integrator::AdaptiveSimpson(Integrator::REFERENCE),
            ..Default::default()
        });
        s.appearance.isosurfaces = Isosurfaces::new(vec![Isovalue {
            value: 0.5,
            rgba: [1.0, 0.0, 0.0, 0.5],
        }])
        .unwrap();
        s.clip_planes = vec![volux_core::voi::ClipPlane::new(1.0, -2.0, 0.5, 0.25).unwrap()];
        s
    }

    /// Saving and reading back gives the same scene, settings and all.
    #[test]
    fn round_trips_every_setting() {
        let dataset = DatasetRef {
            path: "data/head.nrrd".into(),
            q_variable: Some("energy".into()),
            channel: Some(1),
            timepoint: Some(2),
            ..Default::default()
        };
        let mut session = Session::new(dataset, &scene(), Some([0.1, 0.2, 0.3]));
        session.slices = Some(SliceState {
            window: [0.0, 1.0],
            crosshair: [0.5, 0.5, 0.5],
        });
        session.backend = Some(Backend::Gpu);
        let json = session.to_json();
        let raw: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(raw["backend"], "gpu");
        let back = Session::from_json(&json, "test").unwrap();
        assert_eq!(back, session);
        assert_eq!(back.scene(), scene());
    }

    /// A dataset beside the session is saved relative to it (they move together), one
    /// elsewhere absolute; loading resolves both.
    #[test]
    fn relative_paths_follow_the_session_file() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        std::fs::create_dir(root.join("s")).unwrap();
        for (data, written) in [
            (root.join("s/data/head.nrrd"), "data/head.nrrd".into()),
            (root.join("head.nrrd"), root.join("head.nrrd")),
        ] {
            let dataset = DatasetRef {
                path: data.clone(),
                ..Default::default()
            };
            let file = root.join("s/view.json");
            Session::new(dataset, &scene(), None).save(&file).unwrap();
            let text = std::fs::read_to_string(&file).unwrap();
            let raw: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert_eq!(raw["dataset"]["path"], written.display().to_string());
            assert_eq!(Session::load(&file).unwrap().dataset.path, data);
        }
    }

    /// Other versions, unknown fields, invalid scenes and non-sessions are named errors.
    #[test]
    fn refuses_what_it_cannot_reproduce() {
        let good = Session::new(DatasetRef::default(), &scene(), None).to_json();
        let cases = [
            (
                good.replace("\"volux_session\": 1", "\"volux_session\": 2"),
                "version 2",
            ),
            ("{\"color\": []}".to_string(), "not a session"),
            (good.replace("\"width\": 40", "\"width\": 0"), "image size"),
            (
                good.replace("\"mip\": false", "\"mip\": false, \"x\": 1"),
                "unknown field",
            ),
            ("{".to_string(), "not JSON"),
        ];
        for (text, expected) in cases {
            let err = Session::from_json(&text, "s.json").unwrap_err().to_string();
            assert!(err.contains(expected), "{err} (wanted {expected})");
            assert!(err.starts_with("session s.json: "), "{err}");
        }
    }

    /// A session saved before label steps had a rule reads them as nearest seeds, and saves
    /// a nearest step without the field.
    #[test]
    fn an_old_label_step_reads_as_nearest() {
        use volux_core::sculpt::RegionRule;
        let old = r#"{"tool": "label", "point": [1, 2, 3], "label": 4, "colour": [1, 0, 0]}"#;
        let step: SculptStep = serde_json::from_str(old).unwrap();
        let mut session = Session::new(DatasetRef::default(), &scene(), None);
        session.sculpt = vec![step.clone()];
        let json = session.to_json();
        assert!(!json.contains("\"rule\""), "{json}");
        let back = Session::from_json(&json, "old.json").unwrap();
        assert_eq!(back.sculpt, vec![step]);
        assert!(matches!(
            back.sculpt[0],
            SculptStep::Label {
                rule: RegionRule::Nearest,
                ..
            }
        ));
    }
}
