//! The viewer's state and what acts on it: jobs polled, frames taken from the render
//! thread, the scene handed to the render thread whenever it changed, datasets opened
//! ([`crate::files`] reads and writes the rest). The window ([`crate::window`]) draws the
//! panels over it each frame. Nothing here waits for a render or a file.
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use eframe::egui;
use glam::DVec3;
use volux_app::session::{DatasetRef, Session, SliceState};
use volux_core::{Camera, TransferFunction};
use volux_io::progress::{with_progress, LoadProgress};
use volux_render::bricked::Lod;
use volux_render::framing::visible_bounds_of;
use volux_render::scene::{Method, Scene, Volume};
use volux_render::sculpt::Sculpt;

use crate::backend::{Backend, Device};
use crate::dataset::{self, Loaded};
use crate::file_dialog::FileDialog;
use crate::jobs::{Job, Poll};
use crate::navigation;
use crate::progressive::LevelShown;
use crate::render_service::{Event, FinishedFrame, RenderService};
use crate::sculpt_state::SculptTools;
use crate::tf_editor::{in_value_space, TfEditor};

/// How the viewer was started.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// A dataset or a session file to open.
    pub open: Option<PathBuf>,
    /// Write the first fully refined frame here and exit.
    pub screenshot: Option<PathBuf>,
    /// Render size for screenshots (default: the 3D view's size).
    pub size: Option<(usize, usize)>,
    /// With `screenshot`: also save the session here.
    pub save_session: Option<PathBuf>,
    /// The level an OME-Zarr store refines to (`--lod`): automatic, or a fixed level.
    pub lod: Lod,
    /// Where frames are rendered (`--backend`; the library's default is the CPU).
    pub backend: Backend,
    /// The channel and timepoint of the dataset opened at start (`--channel`,
    /// `--timepoint`: OME-Zarr, ImageJ hyperstacks, OME-TIFF).
    pub channel: Option<usize>,
    /// See [`Options::channel`]; also 4-D NIfTI, NRRD, DICOM series with several stacks.
    pub timepoint: Option<usize>,
    /// The component read as the scalar (`--component`: vector and colour volumes).
    pub component: Option<usize>,
}

/// The default background (dark blue-grey, as the CLI's demo).
pub const BACKGROUND: [f32; 3] = [0.02, 0.02, 0.03];

/// What the 3D view shows now.
pub struct Shown {
    /// The texture.
    pub texture: egui::TextureHandle,
    /// The frame's figures and kind.
    pub frame: FinishedFrame,
}

/// What was last handed to the render thread.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Submitted {
    volume: u64,
    pub(crate) scene: Scene,
    interacting: bool,
    background: [f32; 3],
}

/// The viewer.
pub struct ViewerApp {
    pub(crate) ctx: egui::Context,
    pub(crate) service: RenderService,
    /// The dataset on screen.
    pub data: Option<Loaded>,
    pub(crate) load_job: Option<Job<Loaded>>,
    /// Bytes read by the running load, and its cancel flag.
    pub(crate) load_progress: Option<Arc<LoadProgress>>,
    pub(crate) split_job: Option<(Job<Loaded>, Method)>,
    pub(crate) export_job: Option<Job<String>>,
    /// The error shown in the window (the viewer stays usable).
    pub error: Option<String>,
    /// The error came from rendering: the next frame of the newest request clears it.
    pub(crate) render_error: bool,
    /// A passing message (what was saved).
    pub status: Option<String>,
    /// Camera, appearance and method (the image size follows the 3D view).
    pub scene: Scene,
    /// Colour under the volume.
    pub background: [f32; 3],
    /// Slice window (values shown black to white).
    pub window: [f64; 2],
    /// The point the slices pass through (world).
    pub crosshair: DVec3,
    /// Outline the three slice planes in the 3D view.
    pub show_planes: bool,
    /// The TF editor (with a dataset).
    pub editor: Option<TfEditor>,
    /// The sculpt state (seed `004` ch. 4-6): planes, mask, picks, undo (with a dataset).
    pub sculpt: Option<Sculpt>,
    /// The sculpting tools' settings.
    pub tools: SculptTools,
    pub(crate) shown: Option<Shown>,
    pub(crate) slice_textures: Vec<Option<egui::TextureHandle>>,
    pub(crate) slices_key: Option<(u64, [f64; 2], [usize; 3])>,
    pub(crate) submitted: Option<Submitted>,
    pub(crate) interacting: bool,
    pub(crate) frame_times: VecDeque<Instant>,
    /// Size of the 3D view in pixels.
    pub view_size: (usize, usize),
    /// Where the 3D view was last drawn (points).
    pub view_rect: egui::Rect,
    pub(crate) options: Options,
    pub(crate) dialog: FileDialog,
    pub(crate) pending_session: Option<Session>,
    pub(crate) export_size: (usize, usize),
    /// Set once `--screenshot` wrote its file.
    pub finished: bool,
    /// A bricked volume refines to level 0 whatever the view ("Full resolution").
    pub full_resolution: bool,
    /// The levels of a bricked volume's frames shown, with their request, newest last
    /// (the last [`LEVEL_LOG`]).
    pub(crate) level_log: VecDeque<(u64, LevelShown)>,
}

/// How many shown levels [`ViewerApp::level_log`] keeps.
pub const LEVEL_LOG: usize = 64;

impl ViewerApp {
    /// A viewer on `ctx`, opening what `options` name.
    pub fn new(ctx: &egui::Context, options: Options) -> Self {
        let wake_ctx = ctx.clone();
        let service = RenderService::start_on(move || wake_ctx.request_repaint(), options.backend);
        let camera = Camera::fit(&volux_core::Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        });
        let placeholder_tf = TransferFunction::from_json(
            r#"{"color": [[0, 1, 1, 1], [1, 1, 1, 1]], "opacity": [[0, 0], [1, 1]]}"#,
        )
        .expect("a valid TF");
        let mut app = Self {
            ctx: ctx.clone(),
            service,
            data: None,
            load_job: None,
            load_progress: None,
            split_job: None,
            export_job: None,
            error: None,
            render_error: false,
            status: None,
            scene: Scene::new(camera, 640, 480, placeholder_tf),
            background: BACKGROUND,
            window: [0.0, 1.0],
            crosshair: DVec3::ZERO,
            show_planes: false,
            editor: None,
            sculpt: None,
            tools: SculptTools::default(),
            shown: None,
            slice_textures: vec![None, None, None],
            slices_key: None,
            submitted: None,
            interacting: false,
            frame_times: VecDeque::new(),
            view_size: options.size.unwrap_or((640, 480)),
            view_rect: egui::Rect::NOTHING,
            options: options.clone(),
            dialog: FileDialog::default(),
            pending_session: None,
            export_size: (1920, 1080),
            finished: false,
            full_resolution: false,
            level_log: VecDeque::new(),
        };
        if let Some(path) = &options.open {
            let source = DatasetRef {
                channel: options.channel,
                timepoint: options.timepoint,
                component: options.component,
                ..Default::default()
            };
            app.open_with(path, source);
        }
        app
    }

    /// Opens a dataset or (a `.json` with a session version) a session, in the background.
    pub fn open(&mut self, path: &Path) {
        self.open_with(path, DatasetRef::default());
    }

    /// [`ViewerApp::open`], the reader's choices (channel, timepoint, component) taken from
    /// `choice` (a session keeps its own).
    pub fn open_with(&mut self, path: &Path, choice: DatasetRef) {
        self.error = None;
        if is_session_file(path) {
            match Session::load(path) {
                Ok(s) => {
                    let source = s.dataset.clone();
                    self.pending_session = Some(s);
                    self.start_load(source);
                }
                Err(e) => self.error = Some(e.to_string()),
            }
            return;
        }
        self.pending_session = None;
        self.start_load(DatasetRef {
            path: path.to_path_buf(),
            ..choice
        });
    }

    fn start_load(&mut self, source: DatasetRef) {
        if !source.path.exists() {
            self.error = Some(format!("{}: no such file or folder", source.path.display()));
            self.pending_session = None;
            return;
        }
        let size = std::fs::metadata(&source.path)
            .ok()
            .filter(|m| m.is_file())
            .map(|m| format!(", {}", volux_core::units::format_bytes(m.len())))
            .unwrap_or_default();
        let label = format!("loading {}{size}", dataset::title_name(&source.path));
        let progress = LoadProgress::new();
        self.load_progress = Some(progress.clone());
        self.load_job = Some(Job::spawn(label, move || {
            with_progress(progress, || dataset::load(&source))
        }));
    }

    /// Reloads the dataset with another volume chosen along an axis beyond x, y, z
    /// (`option` "timepoint" or "component"; `None`: the colour of a colour image), keeping
    /// the view: the current state is applied to the new volume as a session would be.
    pub fn choose_volume(&mut self, option: &str, index: Option<usize>) {
        let Some(mut s) = self.session() else { return };
        match option {
            "timepoint" => s.dataset.timepoint = index,
            _ => s.dataset.component = index,
        }
        let source = s.dataset.clone();
        self.pending_session = Some(s);
        self.start_load(source);
    }

    /// Drops the running load: the window is free at once.
    pub fn cancel_load(&mut self) {
        if let Some(p) = self.load_progress.take() {
            p.cancel();
        }
        self.load_job = None;
        self.pending_session = None;
        self.status = Some("loading cancelled".into());
    }

    /// Whether background work (loading, splitting) is under way.
    pub fn busy(&self) -> bool {
        self.load_job.is_some() || self.split_job.is_some()
    }

    /// The window title: the file's name.
    pub fn title(&self) -> String {
        match &self.data {
            Some(d) => format!("{} — volux-view", dataset::title_name(&d.source.path)),
            None => "volux-view".into(),
        }
    }

    /// Takes the results of finished background jobs.
    pub(crate) fn poll_jobs(&mut self) {
        self.poll_sculpt_jobs();
        self.update_label_colours();
        if let Some(job) = &mut self.load_job {
            if let Poll::Done(r) = job.poll() {
                self.load_job = None;
                self.load_progress = None;
                match r {
                    Ok(loaded) => self.set_data(loaded),
                    Err(e) => {
                        self.error = Some(e);
                        self.pending_session = None;
                    }
                }
            }
        }
        if let Some((job, method)) = &mut self.split_job {
            let method = *method;
            if let Poll::Done(r) = job.poll() {
                self.split_job = None;
                match r {
                    Ok(loaded) => {
                        self.data = Some(loaded);
                        self.scene.method = method;
                    }
                    Err(e) => {
                        // Back to the volume's own method, or the next frame would split again.
                        if let Some(v) = self.volume().cloned() {
                            self.scene.method = Method::Auto.resolve(&v).unwrap_or(Method::Auto);
                        }
                        self.error = Some(format!("cannot split into tetrahedra: {e}"));
                    }
                }
            }
        }
        if let Some(job) = &mut self.export_job {
            if let Poll::Done(r) = job.poll() {
                self.export_job = None;
                match r {
                    Ok(m) => self.status = Some(m),
                    Err(e) => self.error = Some(e),
                }
            }
        }
    }

    /// Shows a newly loaded dataset: the session's view when one was opened, otherwise the
    /// home camera, the automatic TF, the crosshair at the centre.
    pub(crate) fn set_data(&mut self, mut loaded: Loaded) {
        if let Some(why) = crate::store::lod_refusal(&loaded.volume.volume, self.options.lod) {
            // Said, not clamped: the automatic level is shown instead.
            self.options.lod = volux_render::bricked::Lod::Auto;
            loaded.notes.push(why);
        }
        loaded.volume.volume = crate::store::with_lod(&loaded.volume.volume, self.lod());
        self.level_log.clear();
        let volume = loaded.volume.volume.clone();
        let range = volume.range();
        // The first picture: bone under faint skin for a CT, lit (volux_render's rule).
        let (tf, shade) = volume
            .first_look()
            .map(|(tf, shade)| (in_value_space(&tf, range), shade))
            .unwrap_or_else(|_| (self.scene.appearance.tf.clone(), false));
        self.scene = Scene::new(
            self.scene.view.camera,
            self.view_size.0,
            self.view_size.1,
            tf,
        );
        self.scene.appearance.shade_volume = shade;
        self.scene.view.camera = self.home_camera(&volume);
        self.scene.method = Method::Auto.resolve(&volume).unwrap_or(Method::Auto);
        self.window = [
            loaded.histogram.quantile(0.01),
            loaded
                .histogram
                .quantile(0.99)
                .max(loaded.histogram.quantile(0.01) + 1e-9),
        ];
        self.crosshair = loaded.slices.centre();
        self.editor = Some(TfEditor::new(
            loaded.histogram.clone(),
            &self.scene.appearance.tf,
        ));
        self.shown = None;
        self.slices_key = None;
        self.error = None;
        self.data = Some(loaded);
        self.reset_sculpt(&[]);
        if let Some(s) = self.pending_session.take() {
            self.apply_session(&s);
        }
        self.ctx
            .send_viewport_cmd(egui::ViewportCommand::Title(self.title()));
    }

    fn apply_session(&mut self, s: &Session) {
        self.scene = s.scene();
        self.scene.clip_planes.clear();
        self.apply_session_sculpt(s);
        self.scene.appearance.tf = in_value_space(&s.appearance.tf, self.range());
        self.background = s.background.unwrap_or(BACKGROUND);
        // A screenshot of a session is taken at its size (the batch render's); on screen the
        // view follows the window.
        if self.options.screenshot.is_some() && self.options.size.is_none() {
            self.options.size = Some((s.width, s.height));
        }
        if let Some(sl) = s.slices {
            self.window = sl.window;
            self.crosshair = DVec3::from_array(sl.crosshair);
        }
        if let Some(e) = &mut self.editor {
            e.fit_height(&self.scene.appearance.tf);
        }
    }

    /// Switches the method; a grid is split into tetrahedra first, on a job thread, for the
    /// mesh methods (the method applies once the split is done).
    pub fn set_method(&mut self, method: Method) {
        let Some(data) = &self.data else { return };
        let mesh_method = method.draws_tets();
        if data.volume_for(mesh_method).is_none() {
            if self.split_job.is_none() {
                let mut copy = data.clone();
                let job = Job::spawn("splitting into tetrahedra", move || {
                    copy.split_into_tets().map(|_| copy)
                });
                self.split_job = Some((job, method));
            }
            return;
        }
        self.scene.method = method;
    }

    /// The home view of `volume`: a three-quarter view fitted to what the transfer
    /// function and isosurfaces show and the clip planes and mask leave (the whole box when
    /// nothing is shown), as `volux render --frame visible` frames it.
    pub fn home_camera(&self, volume: &Volume) -> Camera {
        let scene = self.render_scene();
        let bounds = visible_bounds_of(volume, &scene).unwrap_or(volume.bounds());
        let aspect = self.view_size.0 as f64 / self.view_size.1.max(1) as f64;
        navigation::home(&bounds, aspect)
    }

    /// The data's value range.
    pub fn range(&self) -> [f64; 2] {
        self.data
            .as_ref()
            .map_or([0.0, 1.0], |d| d.volume.volume.range())
    }

    /// The session of what is on screen (the render size as the 3D view or `--size`), with
    /// the backend the viewer renders on (`--backend`; opening a session keeps the viewer's).
    pub fn session(&self) -> Option<Session> {
        let data = self.data.as_ref()?;
        let mut s = Session::new(
            data.source.clone(),
            &self.render_scene(),
            Some(self.background),
        );
        // A grid's sculpt is saved as its steps; a mesh's planes as the session's planes.
        if let (Some(sculpt), Some(_)) = (&self.sculpt, self.sculpt_grid()) {
            s = s.with_sculpt(sculpt);
        }
        s.slices = Some(SliceState {
            window: self.window,
            crosshair: self.crosshair.to_array(),
        });
        s.backend = Some(self.options.backend);
        Some(s)
    }

    /// The scene at the render size, with the sculpt's planes and mask.
    pub fn render_scene(&self) -> Scene {
        let (w, h) = self.options.size.unwrap_or(self.view_size);
        let mut scene = self.scene.clone();
        scene.view.width = w.max(1);
        scene.view.height = h.max(1);
        // The "shade" box stays ticked while a method or MIP that does not light the volume
        // is on (the frames and the saved session leave it out; it comes back with them).
        if scene.appearance.mip || scene.method.draws_tets() {
            scene.appearance.shade_volume = false;
        }
        if let Some(s) = &self.sculpt {
            s.apply_to(&mut scene);
        }
        scene.labels = self.scene_labels(&scene);
        scene
    }

    /// Asks for a new frame when the scene (or the interaction state) changed.
    pub(crate) fn submit_if_changed(&mut self) {
        let Some(data) = &self.data else { return };
        if self.split_job.is_some() {
            return;
        }
        let scene = self.render_scene();
        let mesh_method = scene.method.draws_tets();
        let Some(volume) = data.volume_for(mesh_method).cloned() else {
            // A mesh method on a grid not yet split (a session written by hand).
            self.set_method(scene.method);
            return;
        };
        let now = Submitted {
            volume: volume.id,
            scene: scene.clone(),
            interacting: self.interacting,
            background: self.background,
        };
        // Once the drag ends, the same scene is asked for again without `interacting`, and
        // the full frame follows the preview.
        if self.submitted.as_ref() == Some(&now) {
            return;
        }
        if let Err(e) = scene
            .validate()
            .and_then(|_| scene.method.resolve(&volume.volume))
            .and_then(|m| m.check_appearance(&scene.appearance))
        {
            self.error = Some(crate::phrase::phrase(&e));
            self.render_error = true;
            self.submitted = Some(now);
            return;
        }
        self.service.set_background(self.background);
        self.service.submit(&volume, &scene, self.interacting);
        self.submitted = Some(now);
    }

    /// Shows the frames the render thread finished.
    pub(crate) fn take_frames(&mut self, ctx: &egui::Context) {
        for event in self.service.poll() {
            match event {
                Event::Frame(f) => {
                    if f.generation != self.service.generation() && self.shown.is_some() {
                        continue;
                    }
                    let size = [f.image.width(), f.image.height()];
                    let color = egui::ColorImage::from_rgba_unmultiplied(size, &f.display);
                    let texture = ctx.load_texture("volux-3d", color, egui::TextureOptions::LINEAR);
                    self.frame_times.push_back(Instant::now());
                    while self.frame_times.len() > 30 {
                        self.frame_times.pop_front();
                    }
                    if f.generation == self.service.generation() && self.render_error {
                        self.error = None;
                        self.render_error = false;
                    }
                    if let Some(level) = f.level {
                        self.log_level(f.generation, level);
                    }
                    self.shown = Some(Shown { texture, frame: *f });
                }
                Event::Failed {
                    generation,
                    message,
                } => {
                    if generation == self.service.generation() {
                        self.error = Some(message);
                        self.render_error = true;
                    }
                }
            }
        }
    }

    /// Whether the frame on screen is the full-resolution frame of the newest request.
    pub fn shown_full(&self) -> bool {
        self.shown.as_ref().is_some_and(|s| {
            s.frame.full && s.frame.generation == self.service.generation() && !self.busy()
        })
    }

    /// The scene of the frame on screen.
    pub fn shown_scene(&self) -> Option<&Scene> {
        self.shown.as_ref().map(|s| &s.frame.scene)
    }

    /// The rendered image of the frame on screen (premultiplied linear RGBA).
    pub fn shown_image(&self) -> Option<&volux_core::Image> {
        self.shown.as_ref().map(|s| &s.frame.image)
    }

    /// What drew the frame on screen: the CPU engine or the GPU adapter named.
    pub fn shown_device(&self) -> Option<&Device> {
        self.shown.as_ref().map(|s| &s.frame.device)
    }

    /// Frames per second over the last frames shown.
    pub fn fps(&self) -> f64 {
        match (self.frame_times.front(), self.frame_times.back()) {
            (Some(a), Some(b)) if self.frame_times.len() > 1 => {
                (self.frame_times.len() - 1) as f64 / (*b - *a).as_secs_f64().max(1e-9)
            }
            _ => 0.0,
        }
    }

    /// Opens a file dropped on the window.
    pub(crate) fn take_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(path) = dropped.into_iter().find_map(|f| f.path) {
            self.open(&path);
        }
    }

    /// The volume on screen (as loaded).
    pub fn volume(&self) -> Option<&Volume> {
        self.data.as_ref().map(|d| &d.volume.volume)
    }
}

/// A `.json` file whose text names a session version.
fn is_session_file(path: &Path) -> bool {
    let json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    json && path.is_file()
        && std::fs::File::open(path)
            .and_then(|f| {
                use std::io::Read;
                let mut head = String::new();
                f.take(4096).read_to_string(&mut head).map(|_| head)
            })
            .is_ok_and(|h| h.contains("\"volux_session\""))
}
