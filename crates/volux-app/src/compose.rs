//! A scene composed from a front end's choices, the same way in every front end: the
//! transfer function from presets, files or a given function (layered with weights), the
//! method for the volume at hand, the appearance, the cuts, and a camera framed on what is
//! there. The command line fills a [`SceneRequest`] from its flags, the Python bindings
//! from keyword arguments; the checks and defaults are these.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use volux_core::sculpt::SculptMask;
use volux_core::voi::ClipPlane;
use volux_core::{transfer_import, Camera, CameraSpec, TransferFunction};
use volux_render::framing::{fit_to_box, visible_bounds_of};
use volux_render::integrate::SegmentRule;
use volux_render::isosurface::Isosurfaces;
use volux_render::scene::{GridRaycast, Method, PtSettings, Scene, SlicingSettings, Volume};
use volux_render::sculpt::LabelVolume;
use volux_render::shading::BlinnPhong;

use crate::error::AppError;

/// Where a transfer function comes from.
#[derive(Clone, Debug)]
pub enum TfSource {
    /// A preset by name (`auto`, `ct-bone`, ...), fitted to the volume's range and scaled to
    /// its unit length.
    Preset(String),
    /// A file: Volux JSON, a ParaView preset or a Slicer `.vp`
    /// ([`transfer_import::import`] tells them apart).
    File(PathBuf),
    /// A function given as it is.
    Given(TransferFunction),
}

impl TfSource {
    /// A preset name or a file's path: a path ending in `.json` or `.vp`, or naming a file
    /// that exists, is a file.
    pub fn named(spec: &str) -> Self {
        let lower = spec.to_ascii_lowercase();
        if lower.ends_with(".json") || lower.ends_with(".vp") || Path::new(spec).is_file() {
            TfSource::File(PathBuf::from(spec))
        } else {
            TfSource::Preset(spec.to_string())
        }
    }

    /// The function for `volume`, and what an imported file sets that Volux does not apply
    /// (one sentence each, naming the file).
    pub fn resolve(&self, volume: &Volume) -> Result<(TransferFunction, Vec<String>), AppError> {
        match self {
            TfSource::Preset(name) => Ok((volume.preset_tf(name)?, Vec::new())),
            TfSource::File(path) => read_tf_file(path),
            TfSource::Given(tf) => Ok((tf.clone(), Vec::new())),
        }
    }

    /// The source's name, for messages.
    pub fn label(&self) -> String {
        match self {
            TfSource::Preset(name) => name.clone(),
            TfSource::File(path) => path.display().to_string(),
            TfSource::Given(_) => "given".to_string(),
        }
    }
}

/// A transfer-function file (Volux JSON, a ParaView preset or a Slicer `.vp`), and what it
/// sets that Volux does not apply (one sentence each, naming the file).
pub fn read_tf_file(path: &Path) -> Result<(TransferFunction, Vec<String>), AppError> {
    let imported = transfer_import::import_file(path).map_err(|e| AppError::TfFile {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let notes = imported
        .notes
        .iter()
        .map(|n| format!("{}: {n}", path.display()))
        .collect();
    Ok((imported.tf, notes))
}

/// One layer of a transfer function: a source and the weight that multiplies its
/// extinction.
#[derive(Clone, Debug)]
pub struct TfLayer {
    /// Where the layer comes from.
    pub source: TfSource,
    /// The weight (finite, >= 0).
    pub weight: f64,
}

impl TfLayer {
    /// `source` at weight 1.
    pub fn plain(source: TfSource) -> Self {
        Self {
            source,
            weight: 1.0,
        }
    }
}

/// The transfer function of `layers` for `volume` (`auto` when there is none; one layer at
/// weight 1 is used as it is), and the imported files' notes.
pub fn transfer_function(
    layers: &[TfLayer],
    volume: &Volume,
) -> Result<(TransferFunction, Vec<String>), AppError> {
    for layer in layers {
        if !(layer.weight.is_finite() && layer.weight >= 0.0) {
            return Err(AppError::LayerWeight {
                layer: layer.source.label(),
                weight: layer.weight,
            });
        }
    }
    match layers {
        [] => TfSource::Preset("auto".into()).resolve(volume),
        [one] if one.weight == 1.0 => one.source.resolve(volume),
        _ => {
            let range = volume.range();
            let mut notes = Vec::new();
            let mut resolved = Vec::with_capacity(layers.len());
            for layer in layers {
                let (tf, n) = layer.source.resolve(volume)?;
                notes.extend(n);
                resolved.push((tf.resolved(range), layer.weight));
            }
            let tf =
                TransferFunction::layered(&resolved).map_err(volux_render::RenderError::from)?;
            Ok((tf, notes))
        }
    }
}

/// Which method a front end asks for; [`method_for`] picks the variant that draws the
/// volume at hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MethodChoice {
    /// Projected Tetrahedra for a mesh, grid ray casting for a grid.
    #[default]
    Auto,
    /// Projected Tetrahedra (seed `000`): meshes, and grids split into tetrahedra.
    Pt,
    /// Ray casting: the grid ray caster (seed `001`) or the mesh ray caster.
    Raycast,
    /// A mesh resampled to a grid, then ray cast.
    Resample,
    /// Texture slicing.
    Slicing,
}

/// A method request: the choice and the settings of each method it may become.
#[derive(Clone, Debug)]
pub struct MethodRequest {
    /// The method asked for.
    pub choice: MethodChoice,
    /// Projected Tetrahedra's settings.
    pub pt: PtSettings,
    /// The grid ray caster's settings, or the name of the mesh-only integrator asked for
    /// (`exact`, `psi`), which a grid cannot use.
    pub grid: Result<GridRaycast, String>,
    /// The mesh ray caster's segment rule.
    pub mesh_rule: SegmentRule,
    /// Samples along the longest axis when a mesh is resampled.
    pub resample: usize,
    /// The slice spacing of texture slicing (voxels).
    pub slicing_step: f64,
}

impl Default for MethodRequest {
    fn default() -> Self {
        Self {
            choice: MethodChoice::Auto,
            pt: PtSettings::default(),
            grid: Ok(GridRaycast::default()),
            mesh_rule: SegmentRule::default(),
            resample: 256,
            slicing_step: 0.5,
        }
    }
}

/// The method that draws `volume` as `request` asks: PT refused on a grid (the library says
/// why: split it into tetrahedra), the mesh-only integrators refused on a grid.
pub fn method_for(request: &MethodRequest, volume: &Volume) -> Result<Method, AppError> {
    let pt = || Method::ProjectedTetrahedra(request.pt);
    let grid = || {
        request
            .grid
            .clone()
            .map_err(|integrator| AppError::MeshOnlyIntegrator { integrator })
    };
    let mesh = matches!(volume, Volume::Mesh(_));
    Ok(match request.choice {
        MethodChoice::Auto | MethodChoice::Pt if mesh => pt(),
        MethodChoice::Pt => pt().resolve(volume).map(|_| pt())?,
        MethodChoice::Raycast if mesh => Method::TetRaycast(request.mesh_rule),
        MethodChoice::Resample if mesh => Method::Resample {
            samples: request.resample,
            raycast: grid()?,
        },
        MethodChoice::Slicing => Method::Slicing(SlicingSettings {
            step: request.slicing_step,
        }),
        _ => Method::GridRaycast(grid()?),
    })
}

/// What the camera frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Framing {
    /// The volume's bounds.
    #[default]
    All,
    /// What the clip planes and the mask leave visible (the bounds when nothing is).
    Visible,
}

/// Everything a front end chooses for a scene, as plain values.
#[derive(Clone, Debug)]
pub struct SceneRequest {
    /// Image width and height in pixels.
    pub size: (usize, usize),
    /// The camera: an orbit (azimuth, elevation, up, projection) fitted to the framed box, or
    /// a camera file's fields.
    pub camera: CameraSpec,
    /// Whether `camera` is a camera file's: its written fields are kept as they are and only
    /// the missing ones fit the framed box.
    pub camera_is_explicit: bool,
    /// What the camera frames.
    pub framing: Framing,
    /// Zoom after fitting (1: the framed box fills the image).
    pub zoom: f64,
    /// The transfer function's layers (none: `auto`).
    pub tf: Vec<TfLayer>,
    /// The method.
    pub method: MethodRequest,
    /// Extinction multiplier.
    pub opacity_scale: f64,
    /// Lighting of isosurfaces and shaded volumes.
    pub lighting: BlinnPhong,
    /// Shade the volume (gradient lighting).
    pub shade: bool,
    /// Isosurfaces.
    pub isosurfaces: Isosurfaces,
    /// Maximum-intensity projection.
    pub mip: bool,
    /// RGB volumes coloured by the transfer function instead of their own colour.
    pub tf_colour: bool,
    /// Stop rays at an opacity near 1 (the engine's default).
    pub early_termination: bool,
    /// Clip planes.
    pub clip_planes: Vec<ClipPlane>,
    /// A sculpt mask on the grid's voxels.
    pub mask: Option<Arc<SculptMask>>,
    /// A label volume on the grid's voxels.
    pub labels: Option<Arc<LabelVolume>>,
}

impl Default for SceneRequest {
    fn default() -> Self {
        Self {
            size: (512, 512),
            camera: CameraSpec::default(),
            camera_is_explicit: false,
            framing: Framing::All,
            zoom: 1.0,
            tf: Vec::new(),
            method: MethodRequest::default(),
            opacity_scale: 1.0,
            lighting: BlinnPhong::default(),
            shade: false,
            isosurfaces: Isosurfaces::default(),
            mip: false,
            tf_colour: false,
            early_termination: true,
            clip_planes: Vec::new(),
            mask: None,
            labels: None,
        }
    }
}

/// A composed scene and what its user should read (imported files' notes).
#[derive(Clone, Debug)]
pub struct Composed {
    /// The scene, checked.
    pub scene: Scene,
    /// Notes, one sentence each.
    pub notes: Vec<String>,
}

/// The scene of `request` on `volume` before its camera is framed ([`frame_scene`] ends
/// it): a front end may add what it reads itself (a mask file) in between.
pub fn begin_scene(request: &SceneRequest, volume: &Volume) -> Result<Composed, AppError> {
    let rgb = matches!(volume, Volume::Grid(g) if g.color().is_some());
    if request.tf_colour && !rgb {
        return Err(AppError::NotRgb);
    }
    let (tf, notes) = transfer_function(&request.tf, volume)?;
    let method = method_for(&request.method, volume)?;
    let placeholder = request
        .camera
        .resolve(&volume.bounds())
        .map_err(volux_render::RenderError::from)?;
    let mut scene = Scene::new(placeholder, request.size.0, request.size.1, tf);
    scene.method = method;
    let a = &mut scene.appearance;
    a.opacity_scale = request.opacity_scale;
    a.lighting = request.lighting;
    a.shade_volume = request.shade;
    a.isosurfaces = request.isosurfaces.clone();
    a.mip = request.mip;
    a.data_colour = !request.tf_colour;
    if !request.early_termination {
        scene.early_termination = None;
    }
    scene.clip_planes = request.clip_planes.clone();
    scene.mask = request.mask.clone();
    scene.labels = request.labels.clone();
    Ok(Composed { scene, notes })
}

/// Ends a scene begun by [`begin_scene`]: the method resolved for the volume and checked
/// against the appearance, the camera framed, the whole checked.
pub fn frame_scene(
    request: &SceneRequest,
    volume: &Volume,
    mut scene: Scene,
) -> Result<Scene, AppError> {
    let resolved = scene.method.resolve(volume)?;
    resolved.check_appearance(&scene.appearance)?;
    scene.view.camera = frame_camera(request, volume, &scene)?;
    scene.validate()?;
    Ok(scene)
}

/// [`begin_scene`] then [`frame_scene`].
pub fn compose_scene(request: &SceneRequest, volume: &Volume) -> Result<Composed, AppError> {
    let begun = begin_scene(request, volume)?;
    Ok(Composed {
        scene: frame_scene(request, volume, begun.scene)?,
        notes: begun.notes,
    })
}

/// The camera of `request`: a camera file as written (missing fields fit the framed box);
/// an orbit fitted to the framed box's projection, then zoomed.
pub fn frame_camera(
    request: &SceneRequest,
    volume: &Volume,
    scene: &Scene,
) -> Result<Camera, AppError> {
    let bounds = match request.framing {
        Framing::All => volume.bounds(),
        Framing::Visible => visible_bounds_of(volume, scene).unwrap_or_else(|_| volume.bounds()),
    };
    let resolve = |spec: &CameraSpec| {
        spec.resolve(&bounds)
            .map_err(volux_render::RenderError::from)
    };
    if request.camera_is_explicit {
        return Ok(resolve(&request.camera)?);
    }
    let unzoomed = CameraSpec {
        zoom: None,
        ..request.camera.clone()
    };
    let camera = resolve(&unzoomed)?;
    let aspect = request.size.0 as f64 / request.size.1 as f64;
    Ok(fit_to_box(&camera, &bounds, aspect, request.zoom))
}
