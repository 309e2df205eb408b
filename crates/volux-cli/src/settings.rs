//! Command-line arguments turned into library objects, in one place (ripgrep's `hiargs`):
//! sizes, colours, lighting, isosurfaces, integrators, the method for a volume, the transfer
//! function and the camera, and from them the [`Scene`] a command renders. No command parses
//! a string itself.
use std::path::Path;

use glam::DVec3;
use volux_app::compose::{
    self, Framing, MethodChoice, MethodRequest, SceneRequest, TfLayer, TfSource,
};
use volux_core::image::PngOptions;
use volux_core::{CameraSpec, NamedView, TransferFunction};
use volux_io::Dataset;
use volux_render::integrate::{AdaptiveParams, Integrator, SegmentRule, StepControl};
use volux_render::isosurface::{parse_iso, Isosurfaces};
use volux_render::pt::SortMode;
use volux_render::sampling::Reconstruction;
use volux_render::scene::{GridRaycast, PtSettings, Scene, Volume};
use volux_render::shading::{BlinnPhong, Light};

use crate::cli::{
    ColorArg, ControllerArg, FrameArg, IntegratorArg, MethodArg, ReconstructionArg, RenderArgs,
    SortArg,
};
use crate::commands::common::CmdError;
use volux_core::voi::ClipPlane;

/// Parses `--size WxH` ([`volux_app::words::image_size`]).
pub fn parse_size(s: &str) -> Result<(usize, usize), CmdError> {
    volux_app::words::image_size(s).map_err(|e| format!("--size {e}").into())
}

/// Parses `R,G,B` in 0..1 or `none`.
pub fn parse_background(s: &str) -> Result<Option<[f32; 3]>, CmdError> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--background '{s}': expected R,G,B in 0..1 or 'none'"))?;
    match v.as_slice() {
        [r, g, b] if v.iter().all(|c| (0.0..=1.0).contains(c)) => Ok(Some([*r, *g, *b])),
        _ => Err(format!("--background '{s}': expected three values in 0..1 or 'none'").into()),
    }
}

/// Parses a `--clip-plane A,B,C,D`.
pub fn parse_clip_plane(s: &str) -> Result<ClipPlane, CmdError> {
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--clip-plane '{s}': expected four numbers A,B,C,D"))?;
    match v.as_slice() {
        [a, b, c, d] => {
            ClipPlane::new(*a, *b, *c, *d).map_err(|e| format!("--clip-plane '{s}': {e}").into())
        }
        _ => Err(format!("--clip-plane '{s}': expected four numbers A,B,C,D").into()),
    }
}

/// A preset name or a file; presets are fitted to `volume` and scaled to its unit length.
pub fn transfer_function(spec: &str, volume: &Volume) -> Result<TransferFunction, CmdError> {
    layered_tf(&[spec.to_string()], volume)
}

/// Whether `--tf SPEC` names a file rather than a preset ([`TfSource::named`]).
pub fn is_tf_file(spec: &str) -> bool {
    matches!(TfSource::named(spec), TfSource::File(_))
}

/// A transfer-function file: Volux JSON, a ParaView preset or a Slicer `.vp`; what an
/// imported file sets that Volux does not apply is printed as warnings.
pub fn tf_file(spec: &str) -> Result<TransferFunction, CmdError> {
    let (tf, notes) = compose::read_tf_file(Path::new(spec))?;
    warn_notes(&notes);
    Ok(tf)
}

/// Notes printed as warnings.
fn warn_notes(notes: &[String]) {
    for note in notes {
        eprintln!("volux: warning: {}", crate::messages::sanitize(note));
    }
}

/// `NAME` or `NAME:WEIGHT` (a weight multiplies the layer's extinction).
fn layer_spec(spec: &str) -> Result<(&str, f64), CmdError> {
    match spec.rsplit_once(':') {
        Some((name, w)) if !name.is_empty() && w.trim().parse::<f64>().is_ok() => {
            let w: f64 = w.trim().parse().unwrap_or(1.0);
            if !(w.is_finite() && w >= 0.0) {
                return Err(format!("--tf '{spec}': the weight {w} must be >= 0").into());
            }
            Ok((name, w))
        }
        _ => Ok((spec, 1.0)),
    }
}

/// The `--tf` options as layers: one preset or file, or several layered (`NAME[:WEIGHT]`
/// each).
fn tf_layers(specs: &[String]) -> Result<Vec<TfLayer>, CmdError> {
    specs
        .iter()
        .map(|spec| {
            let (name, weight) = layer_spec(spec)?;
            Ok(TfLayer {
                source: TfSource::named(name),
                weight,
            })
        })
        .collect()
}

/// The `--tf` options' transfer function ([`compose::transfer_function`]); imported files'
/// notes are printed as warnings.
pub fn layered_tf(specs: &[String], volume: &Volume) -> Result<TransferFunction, CmdError> {
    let (tf, notes) = compose::transfer_function(&tf_layers(specs)?, volume)?;
    warn_notes(&notes);
    Ok(tf)
}

/// The lighting options (`--ambient`, `--diffuse`, `--specular`, `--shininess`, `--light`).
pub fn lighting(args: &RenderArgs) -> Result<BlinnPhong, CmdError> {
    let bad = || format!("--light '{}': expected X,Y,Z or 'headlight'", args.light);
    let light = if args.light == "headlight" {
        Light::Headlight
    } else {
        let v: Vec<f32> = args
            .light
            .split(',')
            .map(|c| c.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        match v.as_slice() {
            [x, y, z] => Light::Direction(glam::Vec3::new(*x, *y, *z)),
            _ => return Err(bad().into()),
        }
    };
    let s = BlinnPhong {
        ambient: args.ambient,
        diffuse: args.diffuse,
        specular: args.specular,
        shininess: args.shininess,
        light,
        ..BlinnPhong::default()
    };
    s.validate()?;
    Ok(s)
}

/// The `--iso` options.
pub fn isosurfaces(args: &RenderArgs) -> Result<Isosurfaces, CmdError> {
    let values = args
        .view_args
        .isos
        .iter()
        .map(|s| parse_iso(s).map_err(|e| format!("--iso '{s}': {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Isosurfaces::new(values)?)
}

/// The adaptive Simpson parameters of the command line (in the volume's unit length).
fn adaptive(args: &RenderArgs) -> AdaptiveParams {
    AdaptiveParams {
        tol: args.tol,
        h0: args.h0,
        hmin: args.hmin,
        hmax: args.hmax,
        control: match (args.decoupled, args.controller) {
            (true, _) => StepControl::Decoupled,
            (false, ControllerArg::Standard) => StepControl::CoupledStandard,
            (false, ControllerArg::Seed) => StepControl::Coupled,
        },
        early_termination: None,
    }
}

/// The grid integrator named on the command line (`None` for the mesh-only `exact` and
/// `psi`).
pub fn integrator(args: &RenderArgs) -> Option<Integrator> {
    let step = args.step;
    Some(match args.integrator {
        IntegratorArg::Riemann => Integrator::Riemann { step },
        IntegratorArg::Trapezoid => Integrator::Trapezoid { step },
        IntegratorArg::Simpson => Integrator::Simpson { step },
        IntegratorArg::AdaptiveSimpson => Integrator::AdaptiveSimpson(adaptive(args)),
        IntegratorArg::Preintegrated => Integrator::Preintegrated { step },
        IntegratorArg::Reference => Integrator::Reference,
        IntegratorArg::Exact | IntegratorArg::Psi => return None,
    })
}

impl From<SortArg> for SortMode {
    fn from(s: SortArg) -> Self {
        match s {
            SortArg::Centroid => SortMode::Centroid,
            SortArg::Exact => SortMode::Exact,
        }
    }
}

impl From<ColorArg> for SegmentRule {
    fn from(c: ColorArg) -> Self {
        match c {
            ColorArg::Average => SegmentRule::Average,
            ColorArg::Psi => SegmentRule::Psi,
            ColorArg::Exact => SegmentRule::Exact,
        }
    }
}

impl From<ReconstructionArg> for Reconstruction {
    fn from(r: ReconstructionArg) -> Self {
        match r {
            ReconstructionArg::Trilinear => Reconstruction::Trilinear,
            ReconstructionArg::CatmullRom => Reconstruction::CatmullRom,
            ReconstructionArg::BSpline => Reconstruction::BSpline,
        }
    }
}

/// The segment rule of mesh ray casting: `--integrator exact|psi|adaptive-simpson`, or the
/// colour of `--color` for the grid integrators.
pub fn tet_ray_rule(args: &RenderArgs) -> SegmentRule {
    match args.integrator {
        IntegratorArg::Exact => SegmentRule::Exact,
        IntegratorArg::Psi => SegmentRule::Psi,
        IntegratorArg::AdaptiveSimpson => SegmentRule::AdaptiveSimpson(adaptive(args)),
        _ => args.color.into(),
    }
}

/// Grid ray casting as the command line sets it, or the mesh-only integrator's name.
fn grid_raycast(args: &RenderArgs) -> Result<GridRaycast, String> {
    let integrator = integrator(args).ok_or_else(|| args.integrator.name())?;
    Ok(GridRaycast {
        integrator,
        reconstruction: args.reconstruction.into(),
        jitter: args.jitter,
    })
}

/// The loaded data as a volume.
pub fn plain_volume(data: Dataset) -> Result<Volume, CmdError> {
    match data {
        Dataset::Grid(g) => Ok(Volume::from(g)),
        Dataset::Mesh(m) => Ok(Volume::from(m)),
        _ => Err("unsupported dataset kind".into()),
    }
}

/// What can be refused from the file's header before it is loaded: a grid too large to be
/// split into tetrahedra (`--as-tets`), which would otherwise be read whole first.
pub fn check_before_load(file: &std::path::Path, args: &RenderArgs) -> Result<(), CmdError> {
    let pt = matches!(args.method, MethodArg::Auto | MethodArg::Pt);
    if args.as_tets && pt {
        if let Some(dims) = volux_io::peek_dims(file) {
            volux_core::limits::check_alloc(
                "the tetrahedral mesh of the grid",
                volux_core::tetrahedralize::grid_mesh_bytes(dims),
                1,
            )?;
        }
    }
    Ok(())
}

/// The loaded data as the volume to render: a grid split into tetrahedra for PT
/// (`--as-tets` with `--method auto|pt`).
pub fn volume(data: Dataset, args: &RenderArgs) -> Result<Volume, CmdError> {
    let volume = plain_volume(data)?;
    let pt = matches!(args.method, MethodArg::Auto | MethodArg::Pt);
    if args.as_tets && pt && matches!(volume, Volume::Grid(_)) {
        return Ok(volume.to_tets()?);
    }
    Ok(volume)
}

/// The method request of the command line.
fn method_request(args: &RenderArgs) -> MethodRequest {
    MethodRequest {
        choice: match args.method {
            MethodArg::Auto => MethodChoice::Auto,
            MethodArg::Pt => MethodChoice::Pt,
            MethodArg::Raycast => MethodChoice::Raycast,
            MethodArg::Resample => MethodChoice::Resample,
            MethodArg::Slicing => MethodChoice::Slicing,
        },
        pt: PtSettings {
            sort: args.sort.into(),
            color: args.color.into(),
            count_violations: args.stats && args.sort_violations,
        },
        grid: grid_raycast(args),
        mesh_rule: tet_ray_rule(args),
        resample: args.resample,
        slicing_step: args.step,
    }
}

/// The camera of the command line: `--camera FILE`, or the orbit options (`--view`,
/// `--azimuth`, `--elevation`, `--up`, `--zoom`, `--orthographic`).
pub fn camera_spec(args: &RenderArgs) -> Result<CameraSpec, CmdError> {
    if let Some(p) = &args.view_args.camera {
        let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
        return Ok(CameraSpec::from_json(&text).map_err(|e| format!("{}: {e}", p.display()))?);
    }
    let up = args.view_args.up.as_deref().map(parse_up).transpose()?;
    let (azimuth, elevation, up) = match args.view_args.view {
        None => (None, None, up),
        Some(v) => {
            let o = NamedView::from(v)
                .orbit(up.map(DVec3::from))
                .map_err(|e| format!("--view: {e}"))?;
            (Some(o.azimuth), Some(o.elevation), Some(o.up))
        }
    };
    let turn = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (None, None) => None,
        (a, b) => Some(a.unwrap_or(0.0) + b.unwrap_or(0.0)),
    };
    Ok(CameraSpec {
        projection: Some(
            if args.view_args.orthographic {
                "orthographic"
            } else {
                "perspective"
            }
            .into(),
        ),
        azimuth: turn(azimuth, args.view_args.azimuth),
        elevation: turn(elevation, args.view_args.elevation),
        up,
        zoom: Some(args.view_args.zoom),
        ..Default::default()
    })
}

/// Parses `--up X,Y,Z` (not zero).
fn parse_up(s: &str) -> Result<[f64; 3], CmdError> {
    let bad = || format!("--up '{s}': expected X,Y,Z, not all zero, e.g. 0,0,-1");
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) && v.iter().any(|c| *c != 0.0) => {
            Ok([*x, *y, *z])
        }
        _ => Err(bad().into()),
    }
}

/// Checks that `path` names a PNG file (`flag` for the message).
pub fn png_path(path: &Path, flag: &str) -> Result<(), CmdError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    match ext.as_deref() {
        Some("png") => Ok(()),
        Some(other) => Err(format!(
            "{flag} {}: Volux writes PNG images; name the file .png, not .{other}",
            path.display()
        )
        .into()),
        None => Err(format!(
            "{flag} {}: Volux writes PNG images; add the .png extension",
            path.display()
        )
        .into()),
    }
}

/// What `volux render` checks before loading the file: image size, output options, camera
/// file, lighting, isosurfaces, the integrator's parameters.
pub struct RenderPlan {
    /// Image size.
    pub size: (usize, usize),
    /// PNG output options.
    pub png: PngOptions,
    /// The camera (resolved on the volume's bounds later).
    pub camera: CameraSpec,
    /// Lighting of isosurfaces and shaded volumes.
    pub lighting: BlinnPhong,
    /// Isosurfaces.
    pub isosurfaces: Isosurfaces,
}

impl RenderPlan {
    /// Parses and checks everything that does not need the data.
    pub fn new(args: &RenderArgs) -> Result<Self, CmdError> {
        crate::applicable::check_options(args)?;
        png_path(&args.output(), "--output")?;
        if let Some(p) = &args.error_map {
            png_path(p, "--error-map")?;
        }
        let size = parse_size(&args.view_args.size)?;
        let png = PngOptions {
            background: parse_background(&args.background)?,
            sixteen_bit: args.sixteen_bit,
        };
        let camera = camera_spec(args)?;
        if let Some(i) = integrator(args) {
            i.validate()?;
        }
        Ok(Self {
            size,
            png,
            camera,
            lighting: lighting(args)?,
            isosurfaces: isosurfaces(args)?,
        })
    }

    /// The scene request of the command line (the camera as parsed, the rest from `args`).
    fn request(&self, args: &RenderArgs) -> Result<SceneRequest, CmdError> {
        Ok(SceneRequest {
            size: self.size,
            camera: self.camera.clone(),
            camera_is_explicit: args.view_args.camera.is_some(),
            framing: match args.view_args.frame {
                FrameArg::All => Framing::All,
                FrameArg::Visible => Framing::Visible,
            },
            zoom: args.view_args.zoom,
            tf: tf_layers(&args.view_args.tf)?,
            method: method_request(args),
            opacity_scale: args.view_args.opacity_scale,
            lighting: self.lighting,
            shade: args.shade,
            isosurfaces: self.isosurfaces.clone(),
            mip: args.mip,
            tf_colour: args.tf_colour,
            early_termination: !args.no_early_termination,
            clip_planes: args
                .view_args
                .clip_planes
                .iter()
                .map(|s| parse_clip_plane(s))
                .collect::<Result<_, _>>()?,
            mask: None,
            labels: None,
        })
    }

    /// The scene of `volume`: its transfer function, camera and method, every option
    /// checked against the method (`loaded_grid`: the file held a grid), composed by
    /// [`compose`] with the mask and labels files read in between.
    pub fn scene(
        &self,
        args: &RenderArgs,
        volume: &Volume,
        loaded_grid: bool,
    ) -> Result<Scene, CmdError> {
        let request = self.request(args)?;
        let begun = compose::begin_scene(&request, volume)?;
        warn_notes(&begun.notes);
        let mut scene = begun.scene;
        if let (Some(mask), Some(file)) = (&args.view_args.mask, &args.file) {
            // Before the camera: `--frame visible` frames what the mask leaves.
            crate::mask_file::add_mask(mask, volume, file, &mut scene)?;
        }
        if let (Some(labels), Some(file)) = (&args.labels, &args.file) {
            crate::label_file::add_labels(labels, volume, file, &mut scene)?;
        }
        crate::applicable::check_method(args, &scene.method.resolve(volume)?, loaded_grid)?;
        Ok(compose::frame_scene(&request, volume, scene)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn up_and_layer_specs_parse_or_say_what_they_expect() {
        assert_eq!(parse_up("0, 0,-1").unwrap(), [0.0, 0.0, -1.0]);
        for bad in ["0,0,0", "1,2", "a,b,c", "1,2,inf"] {
            let e = parse_up(bad).unwrap_err().to_string();
            assert!(e.contains("expected X,Y,Z"), "{bad}: {e}");
        }
        assert_eq!(layer_spec("ct-skin:0.2").unwrap(), ("ct-skin", 0.2));
        assert_eq!(layer_spec("my:tf.json").unwrap(), ("my:tf.json", 1.0));
        assert!(layer_spec("ct-bone:-1").is_err());
        assert!(png_path(Path::new("a.PNG"), "-o").is_ok());
        assert!(png_path(Path::new("a.jpg"), "-o").is_err());
        assert!(png_path(Path::new("a"), "-o").is_err());
    }
}
