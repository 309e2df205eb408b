//! Python's keyword arguments as a scene request ([`volux_app::compose::SceneRequest`]):
//! Python's words of views, methods, integrators and colour rules, with the command line's
//! defaults, so that the same scene gives the same picture as `volux render`.
use std::sync::Arc;

use glam::DVec3;
use numpy::{PyReadonlyArray3, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use volux_app::compose::{Framing, MethodChoice, MethodRequest, SceneRequest, TfLayer, TfSource};
use volux_core::sculpt::SculptMask;
use volux_core::voi::ClipPlane;
use volux_core::{CameraSpec, NamedView};
use volux_render::integrate::{AdaptiveParams, Integrator, SegmentRule, StepControl};
use volux_render::isosurface::{parse_iso, Isosurfaces, Isovalue};
use volux_render::pt::SortMode;
use volux_render::sampling::Reconstruction;
use volux_render::scene::{GridRaycast, PtSettings, Volume as RVolume};
use volux_render::sculpt::LabelVolume;
use volux_render::shading::{BlinnPhong, Light};

use crate::errors::{option_error, IntoPy};
use crate::tf::TransferFunction;

/// A transfer function layer's source as Python gives it: a preset name or a file's path,
/// or a `TransferFunction`.
#[derive(FromPyObject)]
pub enum TfArg {
    /// A preset or a path.
    Name(String),
    /// A function.
    Given(TransferFunction),
}

/// Every keyword argument of a render, as given.
#[derive(Clone)]
pub struct SceneArgs {
    /// Transfer-function layers, each with its weight.
    pub tf: Vec<(TfSource, f64)>,
    /// A named view (`left`, `anterior`, `+x`, ...).
    pub view: Option<String>,
    /// Degrees about the up axis, added to the view's.
    pub azimuth: Option<f64>,
    /// Degrees above the horizon, added to the view's.
    pub elevation: Option<f64>,
    /// The screen's up, world.
    pub up: Option<[f64; 3]>,
    /// Zoom after fitting.
    pub zoom: f64,
    /// Orthographic projection.
    pub orthographic: bool,
    /// A camera in Volux's JSON form (`eye`, `target`, `up`, ...), instead of the orbit.
    pub camera_json: Option<String>,
    /// Width and height.
    pub size: (usize, usize),
    /// The method's word.
    pub method: String,
    /// The integrator's word.
    pub integrator: String,
    /// Fixed step (voxels).
    pub step: f64,
    /// Adaptive Simpson's tolerance and steps.
    pub adaptive: [f64; 4],
    /// The reconstruction filter's word.
    pub reconstruction: String,
    /// Jittered ray starts.
    pub jitter: bool,
    /// PT's fragment colour rule word.
    pub color: String,
    /// PT's visibility order word.
    pub sort: String,
    /// Samples along the longest axis when a mesh is resampled.
    pub resample: usize,
    /// Gradient shading.
    pub shade: bool,
    /// Blinn-Phong ambient, diffuse, specular, shininess.
    pub lighting: [f32; 4],
    /// A light direction (world) instead of the headlight.
    pub light: Option<[f32; 3]>,
    /// Isosurfaces as `VALUE:R,G,B,A` words.
    pub iso: Vec<String>,
    /// Maximum-intensity projection.
    pub mip: bool,
    /// Extinction multiplier.
    pub opacity_scale: f64,
    /// RGB volumes coloured by the TF.
    pub tf_colour: bool,
    /// Early ray termination.
    pub early_termination: bool,
    /// Clip planes `(a, b, c, d)`: kept where `a x + b y + c z + d >= 0`.
    pub clip_planes: Vec<[f64; 4]>,
    /// A mask: non-zero voxels kept.
    pub mask: Option<Arc<SculptMask>>,
    /// A label volume.
    pub labels: Option<Arc<LabelVolume>>,
    /// `all` or `visible`.
    pub frame: String,
}

fn word<T: Copy>(py: Python<'_>, option: &str, given: &str, table: &[(&str, T)]) -> PyResult<T> {
    let lower = given.trim().to_ascii_lowercase().replace('_', "-");
    table
        .iter()
        .find(|(w, _)| *w == lower)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let words: Vec<&str> = table.iter().map(|(w, _)| *w).collect();
            option_error(
                py,
                option,
                &format!("'{given}'"),
                &format!("one of {}", words.join(", ")),
            )
        })
}

/// The named views' words.
pub const VIEWS: [(&str, NamedView); 18] = [
    ("left", NamedView::Left),
    ("right", NamedView::Right),
    ("anterior", NamedView::Anterior),
    ("posterior", NamedView::Posterior),
    ("superior", NamedView::Superior),
    ("inferior", NamedView::Inferior),
    ("l", NamedView::Left),
    ("r", NamedView::Right),
    ("a", NamedView::Anterior),
    ("p", NamedView::Posterior),
    ("s", NamedView::Superior),
    ("i", NamedView::Inferior),
    ("+x", NamedView::PlusX),
    ("-x", NamedView::MinusX),
    ("+y", NamedView::PlusY),
    ("-y", NamedView::MinusY),
    ("+z", NamedView::PlusZ),
    ("-z", NamedView::MinusZ),
];

impl SceneArgs {
    /// The camera: a camera's JSON as written, or the orbit of the view, azimuth,
    /// elevation and up (as `volux render --view --azimuth --elevation --up`).
    fn camera(&self, py: Python<'_>) -> PyResult<(CameraSpec, bool)> {
        if let Some(text) = &self.camera_json {
            return Ok((CameraSpec::from_json(text).py(py)?, true));
        }
        if let Some(up) = self.up {
            if !(up.iter().all(|c| c.is_finite()) && up.iter().any(|c| *c != 0.0)) {
                return Err(option_error(
                    py,
                    "up",
                    &format!("{up:?}"),
                    "x, y, z, not all zero",
                ));
            }
        }
        let (azimuth, elevation, up) = match &self.view {
            None => (None, None, self.up),
            Some(v) => {
                let named = word(py, "view", v, &VIEWS)?;
                let o = named.orbit(self.up.map(DVec3::from)).py(py)?;
                (Some(o.azimuth), Some(o.elevation), Some(o.up))
            }
        };
        let turn = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0.0) + b.unwrap_or(0.0)),
        };
        Ok((
            CameraSpec {
                projection: Some(
                    if self.orthographic {
                        "orthographic"
                    } else {
                        "perspective"
                    }
                    .into(),
                ),
                azimuth: turn(azimuth, self.azimuth),
                elevation: turn(elevation, self.elevation),
                up,
                zoom: Some(self.zoom),
                ..Default::default()
            },
            false,
        ))
    }

    /// The adaptive Simpson parameters.
    fn adaptive(&self) -> AdaptiveParams {
        let [tol, h0, hmin, hmax] = self.adaptive;
        AdaptiveParams {
            tol,
            h0,
            hmin,
            hmax,
            control: StepControl::Coupled,
            early_termination: None,
        }
    }

    /// The method request.
    fn method(&self, py: Python<'_>) -> PyResult<MethodRequest> {
        let choice = word(
            py,
            "method",
            &self.method,
            &[
                ("auto", MethodChoice::Auto),
                ("pt", MethodChoice::Pt),
                ("raycast", MethodChoice::Raycast),
                ("resample", MethodChoice::Resample),
                ("slicing", MethodChoice::Slicing),
            ],
        )?;
        #[derive(Clone, Copy)]
        enum I {
            Riemann,
            Trapezoid,
            Simpson,
            Adaptive,
            Preintegrated,
            Reference,
            Exact,
            Psi,
        }
        let integrator = word(
            py,
            "integrator",
            &self.integrator,
            &[
                ("riemann", I::Riemann),
                ("trapezoid", I::Trapezoid),
                ("simpson", I::Simpson),
                ("adaptive-simpson", I::Adaptive),
                ("preintegrated", I::Preintegrated),
                ("reference", I::Reference),
                ("exact", I::Exact),
                ("psi", I::Psi),
            ],
        )?;
        let color = word(
            py,
            "color",
            &self.color,
            &[
                ("average", SegmentRule::Average),
                ("psi", SegmentRule::Psi),
                ("exact", SegmentRule::Exact),
            ],
        )?;
        let sort = word(
            py,
            "sort",
            &self.sort,
            &[("centroid", SortMode::Centroid), ("exact", SortMode::Exact)],
        )?;
        let reconstruction = word(
            py,
            "reconstruction",
            &self.reconstruction,
            &[
                ("trilinear", Reconstruction::Trilinear),
                ("catmull-rom", Reconstruction::CatmullRom),
                ("b-spline", Reconstruction::BSpline),
            ],
        )?;
        let step = self.step;
        let grid_integrator = match integrator {
            I::Riemann => Ok(Integrator::Riemann { step }),
            I::Trapezoid => Ok(Integrator::Trapezoid { step }),
            I::Simpson => Ok(Integrator::Simpson { step }),
            I::Adaptive => Ok(Integrator::AdaptiveSimpson(self.adaptive())),
            I::Preintegrated => Ok(Integrator::Preintegrated { step }),
            I::Reference => Ok(Integrator::Reference),
            I::Exact => Err("exact".to_string()),
            I::Psi => Err("psi".to_string()),
        };
        if let Ok(i) = &grid_integrator {
            i.validate()
                .map_err(|e| volux_app::AppError::from(volux_render::RenderError::from(e)))
                .py(py)?;
        }
        let mesh_rule = match integrator {
            I::Exact => SegmentRule::Exact,
            I::Psi => SegmentRule::Psi,
            I::Adaptive => SegmentRule::AdaptiveSimpson(self.adaptive()),
            _ => color,
        };
        Ok(MethodRequest {
            choice,
            pt: PtSettings {
                sort,
                color,
                count_violations: false,
            },
            grid: grid_integrator.map(|integrator| GridRaycast {
                integrator,
                reconstruction,
                jitter: self.jitter,
            }),
            mesh_rule,
            resample: self.resample,
            slicing_step: step,
        })
    }

    /// The scene request.
    pub fn request(&self, py: Python<'_>) -> PyResult<SceneRequest> {
        let (camera, camera_is_explicit) = self.camera(py)?;
        let [ambient, diffuse, specular, shininess] = self.lighting;
        let lighting = BlinnPhong {
            ambient,
            diffuse,
            specular,
            shininess,
            light: match self.light {
                None => Light::Headlight,
                Some([x, y, z]) => Light::Direction(glam::Vec3::new(x, y, z)),
            },
            ..BlinnPhong::default()
        };
        lighting
            .validate()
            .map_err(|e| volux_app::AppError::from(volux_render::RenderError::from(e)))
            .py(py)?;
        let isos = self
            .iso
            .iter()
            .map(|s| parse_iso(s).map_err(|e| option_error(py, "iso", s, &e)))
            .collect::<PyResult<Vec<Isovalue>>>()?;
        let isosurfaces = Isosurfaces::new(isos)
            .map_err(|e| option_error(py, "iso", &format!("{:?}", self.iso), &e))?;
        let clip_planes = self
            .clip_planes
            .iter()
            .map(|[a, b, c, d]| {
                ClipPlane::new(*a, *b, *c, *d).map_err(|e| {
                    option_error(
                        py,
                        "clip_planes",
                        &format!("({a}, {b}, {c}, {d})"),
                        &e.to_string(),
                    )
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(SceneRequest {
            size: self.size,
            camera,
            camera_is_explicit,
            framing: word(
                py,
                "frame",
                &self.frame,
                &[("all", Framing::All), ("visible", Framing::Visible)],
            )?,
            zoom: self.zoom,
            tf: self
                .tf
                .iter()
                .map(|(source, weight)| TfLayer {
                    source: source.clone(),
                    weight: *weight,
                })
                .collect(),
            method: self.method(py)?,
            opacity_scale: self.opacity_scale,
            lighting,
            shade: self.shade,
            isosurfaces,
            mip: self.mip,
            tf_colour: self.tf_colour,
            early_termination: self.early_termination,
            clip_planes,
            mask: self.mask.clone(),
            labels: self.labels.clone(),
        })
    }
}

/// The grid of `volume`, or an error naming `option` (masks and labels apply to grids).
fn grid_dims(py: Python<'_>, option: &str, volume: &RVolume) -> PyResult<[usize; 3]> {
    match volume {
        RVolume::Grid(g) => Ok(g.dims()),
        other => Err(option_error(
            py,
            option,
            "an array",
            &format!(
                "no {option} on a {}: {option}s apply to grids read whole",
                other.kind()
            ),
        )),
    }
}

/// The values of a `[z, y, x]` array on the grid's voxels, as `u8`.
fn voxel_values(
    py: Python<'_>,
    option: &str,
    array: &Bound<'_, PyUntypedArray>,
    dims: [usize; 3],
) -> PyResult<Vec<u8>> {
    let [nx, ny, nz] = dims;
    if array.shape() != [nz, ny, nx] {
        return Err(option_error(
            py,
            option,
            &format!("an array of shape {:?}", array.shape()),
            &format!("the volume's shape ({nz}, {ny}, {nx}), indexed [z, y, x]"),
        ));
    }
    let np = py.import("numpy")?;
    let as_u8 = np.call_method1("ascontiguousarray", (array, "uint8"))?;
    let a: PyReadonlyArray3<'_, u8> = as_u8.extract()?;
    Ok(a.as_slice()?.to_vec())
}

/// A mask from a `[z, y, x]` array (non-zero: kept) on `volume`'s grid.
pub fn mask(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    volume: &RVolume,
) -> PyResult<Option<Arc<SculptMask>>> {
    let dims = grid_dims(py, "mask", volume)?;
    let np = py.import("numpy")?;
    let kept = np.call_method1("not_equal", (array, 0))?;
    let kept = kept.cast::<PyUntypedArray>()?;
    let values = voxel_values(py, "mask", kept, dims)?;
    let mask = SculptMask::from_values(dims, &values).py(py)?;
    // A mask that removes nothing changes no pixel (as `volux render --mask`).
    Ok((!mask.is_untouched()).then(|| Arc::new(mask)))
}

/// A label volume from a `[z, y, x]` array of integers 0 to 255 on `volume`'s grid, coloured
/// by the palette `volux render --labels` uses.
pub fn labels(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    volume: &RVolume,
) -> PyResult<Arc<LabelVolume>> {
    let dims = grid_dims(py, "labels", volume)?;
    let np = py.import("numpy")?;
    let (lo, hi): (f64, f64) = (
        np.call_method1("min", (array,))?.extract()?,
        np.call_method1("max", (array,))?.extract()?,
    );
    if lo < 0.0 || hi > 255.0 {
        return Err(option_error(
            py,
            "labels",
            &format!("an array of values {lo} to {hi}"),
            "integers 0 to 255",
        ));
    }
    let values = voxel_values(py, "labels", array, dims)?;
    let colours: Vec<(u8, [f32; 3])> = (1..=255u8)
        .filter_map(|l| volux_render::sculpt::labels::palette_colour(l).map(|c| (l, c)))
        .collect();
    let labels = LabelVolume::new(dims, values, &colours)
        .map_err(volux_app::AppError::from)
        .py(py)?;
    Ok(Arc::new(labels))
}

/// An isosurface word from Python's forms: `"V:R,G,B,A"`, a number (an off-white surface),
/// or `(value, (r, g, b, a))`.
pub fn iso_word(py: Python<'_>, item: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = item.extract::<String>() {
        return Ok(s);
    }
    if let Ok(v) = item.extract::<f64>() {
        return Ok(format!("{v}:0.9,0.88,0.82,1"));
    }
    if let Ok((v, [r, g, b, a])) = item.extract::<(f64, [f64; 4])>() {
        return Ok(format!("{v}:{r},{g},{b},{a}"));
    }
    Err(option_error(
        py,
        "iso",
        &item.repr()?.to_string(),
        "a value, (value, (r, g, b, a)) or 'VALUE:R,G,B,A'",
    ))
}

fn pairs(py: Python<'_>, option: &str, v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<[f64; 4]>> {
    let Some(v) = v else {
        return Ok(Vec::new());
    };
    v.extract::<Vec<[f64; 4]>>().map_err(|_| {
        option_error(
            py,
            option,
            &v.repr().map(|r| r.to_string()).unwrap_or_default(),
            "a list of (a, b, c, d): kept where a x + b y + c z + d >= 0",
        )
    })
}

/// A scene as Python gives it: every keyword argument of ``volux.render`` checked for its
/// form; the mask and labels arrays are put on the volume's grid when a frame is drawn.
#[pyclass(frozen, module = "volux._volux", name = "SceneSpec")]
pub struct SceneSpec {
    args: SceneArgs,
    mask: Option<Py<PyUntypedArray>>,
    labels: Option<Py<PyUntypedArray>>,
}

impl SceneSpec {
    /// The arguments with the mask and labels on `volume`'s grid.
    pub fn args(&self, py: Python<'_>, volume: &RVolume) -> PyResult<SceneArgs> {
        let mut args = self.args.clone();
        if let Some(m) = &self.mask {
            args.mask = mask(py, m.bind(py), volume)?;
        }
        if let Some(l) = &self.labels {
            args.labels = Some(labels(py, l.bind(py), volume)?);
        }
        Ok(args)
    }
}

#[pymethods]
impl SceneSpec {
    /// A scene; see ``help(volux.render)`` for each argument.
    #[new]
    #[pyo3(signature = (*, tf=None, view=None, azimuth=None, elevation=None, up=None, zoom=1.0,
        orthographic=false, camera=None, size=(512, 512), method="auto", integrator="riemann",
        step=0.5, tol=0.01, h0=0.5, hmin=0.001, hmax=0.5, reconstruction="trilinear",
        jitter=false, color="psi", sort="centroid", resample=256, shade=false, ambient=0.3,
        diffuse=0.7, specular=0.3, shininess=32.0, light=None, iso=None, mip=false,
        opacity_scale=1.0, tf_colour=false, early_termination=true, clip_planes=None,
        mask=None, labels=None, frame="visible"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        tf: Option<Vec<(TfArg, f64)>>,
        view: Option<String>,
        azimuth: Option<f64>,
        elevation: Option<f64>,
        up: Option<[f64; 3]>,
        zoom: f64,
        orthographic: bool,
        camera: Option<String>,
        size: (usize, usize),
        method: &str,
        integrator: &str,
        step: f64,
        tol: f64,
        h0: f64,
        hmin: f64,
        hmax: f64,
        reconstruction: &str,
        jitter: bool,
        color: &str,
        sort: &str,
        resample: usize,
        shade: bool,
        ambient: f32,
        diffuse: f32,
        specular: f32,
        shininess: f32,
        light: Option<[f32; 3]>,
        iso: Option<Vec<Bound<'_, PyAny>>>,
        mip: bool,
        opacity_scale: f64,
        tf_colour: bool,
        early_termination: bool,
        clip_planes: Option<&Bound<'_, PyAny>>,
        mask: Option<&Bound<'_, PyUntypedArray>>,
        labels: Option<&Bound<'_, PyUntypedArray>>,
        frame: &str,
    ) -> PyResult<Self> {
        let tf = tf
            .unwrap_or_default()
            .into_iter()
            .map(|(arg, weight)| {
                let source = match arg {
                    TfArg::Name(n) => TfSource::named(&n),
                    TfArg::Given(t) => TfSource::Given(t.tf),
                };
                (source, weight)
            })
            .collect();
        let args = SceneArgs {
            tf,
            view,
            azimuth,
            elevation,
            up,
            zoom,
            orthographic,
            camera_json: camera,
            size,
            method: method.to_string(),
            integrator: integrator.to_string(),
            step,
            adaptive: [tol, h0, hmin, hmax],
            reconstruction: reconstruction.to_string(),
            jitter,
            color: color.to_string(),
            sort: sort.to_string(),
            resample,
            shade,
            lighting: [ambient, diffuse, specular, shininess],
            light,
            iso: iso
                .unwrap_or_default()
                .iter()
                .map(|i| iso_word(py, i))
                .collect::<PyResult<_>>()?,
            mip,
            opacity_scale,
            tf_colour,
            early_termination,
            clip_planes: pairs(py, "clip_planes", clip_planes)?,
            mask: None,
            labels: None,
            frame: frame.to_string(),
        };
        let max = volux_app::words::MAX_IMAGE_SIDE;
        if !(1..=max).contains(&size.0) || !(1..=max).contains(&size.1) {
            return Err(option_error(
                py,
                "size",
                &format!("({}, {})", size.0, size.1),
                &format!("(width, height), each from 1 to {max}"),
            ));
        }
        // Every word checked now, not at the first frame.
        args.request(py)?;
        Ok(Self {
            args,
            mask: mask.map(|m| m.clone().unbind()),
            labels: labels.map(|l| l.clone().unbind()),
        })
    }
}
