//! `Renderer`: a volume rendered frame after frame with one renderer kept warm (its caches of
//! data, classification and view), opened by the application layer's
//! [`volux_app::RendererFactory`] on the backend asked for; `Image`: a frame.
//!
//! A frame is drawn with the GIL released, on a worker thread, while the calling thread
//! watches for Ctrl-C (`Python::check_signals`, which cancels the frame through the
//! engine's [`Control`] and raises `KeyboardInterrupt`) and reports progress to a callback.
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use volux_app::{Backend, Device, RendererFactory};
use volux_core::image::PngOptions;
use volux_render::engine::Frame;
use volux_render::renderer::Renderer as EngineRenderer;
use volux_render::scene::{Method, Scene};
use volux_render::tiles::Control;
use volux_render::RenderError;

use crate::errors::{option_error, IntoPy};
use crate::scene::SceneArgs;
use crate::volume::Volume;

/// Whether this build has the GPU backend (the `gpu` feature).
#[pyfunction]
pub fn gpu_built() -> bool {
    cfg!(feature = "gpu")
}

/// The GPU device of a build with the `gpu` feature.
fn gpu_device() -> Option<Box<dyn volux_render::device::GpuDevice>> {
    #[cfg(feature = "gpu")]
    return Some(Box::new(volux_gpu::LazyGpu::new()));
    #[cfg(not(feature = "gpu"))]
    None
}

/// The renderer kept warm, and what it was opened for.
struct Warm {
    renderer: Box<dyn EngineRenderer>,
    method: Method,
    generation: u64,
    on_gpu: bool,
    device: Device,
}

/// A renderer's state: the factory and the renderer kept warm.
struct State {
    factory: RendererFactory,
    warm: Option<Warm>,
}

/// Renders one volume frame after frame, keeping its caches warm: a loop over cameras or
/// transfer functions costs what ``volux render --orbit`` costs per frame.
///
/// ``Renderer(volume, backend="auto")``; ``renderer.render(**scene)`` returns an
/// ``Image``. ``backend``: ``"auto"`` (the GPU when it draws the scene and is not a software
/// rasterizer, else the CPU engine), ``"cpu"`` or ``"gpu"``.
#[pyclass(frozen, module = "volux._volux", name = "Renderer")]
pub struct Renderer {
    volume: Py<Volume>,
    backend: Backend,
    state: Mutex<State>,
}

/// A frame drawn on a worker thread while this thread watches for Ctrl-C and reports
/// progress; `interrupted` holds the `KeyboardInterrupt` that cancelled it.
fn draw(
    py: Python<'_>,
    renderer: &mut dyn EngineRenderer,
    scene: &Scene,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Frame> {
    let cancel = Arc::new(AtomicBool::new(false));
    let done = Arc::new(AtomicUsize::new(0));
    let total = Arc::new(AtomicUsize::new(0));
    let (d, t) = (done.clone(), total.clone());
    let control = Control {
        cancel: Some(cancel.clone()),
        progress: Some(Arc::new(move |rows, of| {
            d.store(rows, Ordering::Relaxed);
            t.store(of, Ordering::Relaxed);
        })),
    };
    let progress = progress.map(|p| p.clone().unbind());
    let mut interrupted: Option<PyErr> = None;
    let mut callback_error: Option<PyErr> = None;
    let result: Result<Frame, RenderError> = py.detach(|| {
        std::thread::scope(|s| {
            let worker = s.spawn(|| renderer.render(scene, &control));
            let mut reported = 0;
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(20));
                Python::attach(|py| {
                    if interrupted.is_none() {
                        if let Err(e) = py.check_signals() {
                            interrupted = Some(e);
                            cancel.store(true, Ordering::Relaxed);
                        }
                    }
                    let (now, of) = (done.load(Ordering::Relaxed), total.load(Ordering::Relaxed));
                    if let (Some(p), true) =
                        (&progress, now != reported && callback_error.is_none())
                    {
                        reported = now;
                        if let Err(e) = p.bind(py).call1((now, of)) {
                            callback_error = Some(e);
                            cancel.store(true, Ordering::Relaxed);
                        }
                    }
                });
            }
            worker
                .join()
                .unwrap_or_else(|_| Err(RenderError::Internal("the render thread panicked".into())))
        })
    });
    if let Some(e) = interrupted.or(callback_error) {
        return Err(e);
    }
    if let (Some(p), Ok(_)) = (&progress, &result) {
        let of = total.load(Ordering::Relaxed);
        p.bind(py).call1((of, of))?;
    }
    result.py(py)
}

impl Renderer {
    /// Renders `args` on the volume: the scene composed by the application layer, the
    /// renderer reopened only when the method, the volume or the device changed.
    fn frame(
        &self,
        py: Python<'_>,
        args: &SceneArgs,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Image> {
        let (volume, generation) = self.volume.get().current();
        let request = args.request(py)?;
        let composed = volux_app::compose::compose_scene(&request, &volume).py(py)?;
        let scene = composed.scene;
        crate::errors::warn_notes(py, &composed.notes)?;
        // Never wait for the lock with the GIL held: the frame drawn meanwhile needs the GIL
        // to report progress, and would wait for this thread.
        let mut state = match self.state.try_lock() {
            Ok(s) => s,
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "this Renderer is drawing a frame in another thread; use one Renderer per thread",
                ))
            }
        };
        let state = &mut *state;
        let placement = state.factory.place(&volume, &scene).py(py)?;
        let reuse = state.warm.as_ref().is_some_and(|w| {
            w.method == scene.method && w.generation == generation && w.on_gpu == placement.on_gpu
        });
        if !reuse {
            state.warm = None;
            let (renderer, device) = state
                .factory
                .make(&volume, &scene.method, placement.on_gpu)
                .py(py)?;
            state.warm = Some(Warm {
                renderer,
                method: scene.method,
                generation,
                on_gpu: placement.on_gpu,
                device,
            });
        }
        let warm = state.warm.as_mut().expect("opened above");
        let frame = draw(py, warm.renderer.as_mut(), &scene, progress)?;
        let camera = camera_dict(&scene.view.camera, &volume);
        Ok(Image {
            camera,
            frame: Arc::new(frame),
            device: warm.device.to_string(),
            cpu_because: placement.cpu_because,
            method: warm.renderer.name(),
        })
    }
}

#[pymethods]
impl Renderer {
    /// A renderer of ``volume`` on ``backend`` (``"auto"``, ``"cpu"`` or ``"gpu"``).
    #[new]
    #[pyo3(signature = (volume, backend="auto"))]
    fn new(py: Python<'_>, volume: Py<Volume>, backend: &str) -> PyResult<Self> {
        let backend = Backend::parse(backend)
            .map_err(volux_app::AppError::from)
            .py(py)?;
        Ok(Self {
            volume,
            backend,
            state: Mutex::new(State {
                factory: RendererFactory::new(backend, gpu_device()),
                warm: None,
            }),
        })
    }

    /// Renders the scene ``scene`` (a ``SceneSpec``) and calls ``progress(done, total)``
    /// while it draws.
    #[pyo3(signature = (scene, progress=None))]
    fn render(
        &self,
        py: Python<'_>,
        scene: &crate::scene::SceneSpec,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Image> {
        let (volume, _) = self.volume.get().current();
        let args = scene.args(py, &volume)?;
        self.frame(py, &args, progress)
    }

    /// The volume rendered.
    #[getter]
    fn volume(&self, py: Python<'_>) -> Py<Volume> {
        self.volume.clone_ref(py)
    }

    /// The backend asked for.
    #[getter]
    fn backend(&self) -> &'static str {
        self.backend.name()
    }

    /// The adapters the GPU backend can open, preferred first (a build with the GPU).
    fn adapters(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        RendererFactory::new(self.backend, gpu_device())
            .adapters()
            .py(py)
    }
}

/// A rendered frame: premultiplied linear RGBA, shown in a notebook as PNG.
#[pyclass(frozen, module = "volux._volux", name = "Image")]
pub struct Image {
    camera: String,
    frame: Arc<Frame>,
    device: String,
    cpu_because: Option<String>,
    method: &'static str,
}

fn png_options(
    py: Python<'_>,
    background: Option<[f32; 3]>,
    sixteen_bit: bool,
) -> PyResult<PngOptions> {
    if let Some(b) = background {
        if !b.iter().all(|c| (0.0..=1.0).contains(c)) {
            return Err(option_error(
                py,
                "background",
                &format!("{b:?}"),
                "(r, g, b) in 0..1",
            ));
        }
    }
    Ok(PngOptions {
        background,
        sixteen_bit,
    })
}

#[pymethods]
impl Image {
    /// Width in pixels.
    #[getter]
    fn width(&self) -> usize {
        self.frame.image.width()
    }

    /// Height in pixels.
    #[getter]
    fn height(&self) -> usize {
        self.frame.image.height()
    }

    /// The pixels as a numpy array of shape ``(height, width, 4)``: ``"uint8"`` (the
    /// default) is sRGB with straight alpha as the PNG holds it (over ``background`` when
    /// given, then opaque); ``"float32"`` is the renderer's premultiplied linear RGBA.
    #[pyo3(signature = (dtype="uint8", background=None))]
    fn to_numpy<'py>(
        &self,
        py: Python<'py>,
        dtype: &str,
        background: Option<[f32; 3]>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let img = &self.frame.image;
        let shape = [img.height(), img.width(), 4];
        match dtype {
            "uint8" => {
                let bytes = match background {
                    Some(b) => img.to_srgba8(b),
                    None => {
                        let png = img.encode_png(&png_options(py, None, false)?).py(py)?;
                        decode_png(&png).map_err(PyValueError::new_err)?
                    }
                };
                Ok(PyArray1::from_vec(py, bytes).reshape(shape)?.into_any())
            }
            "float32" => {
                let flat: Vec<f32> = img.pixels().iter().flatten().copied().collect();
                Ok(PyArray1::from_vec(py, flat).reshape(shape)?.into_any())
            }
            other => Err(option_error(py, "dtype", other, "'uint8' or 'float32'")),
        }
    }

    /// Writes the frame as PNG, the same bytes ``volux render -o`` writes for the same
    /// scene: over ``background`` ``(r, g, b)`` in 0..1 (black, as the command line's
    /// default), or transparent where nothing was drawn with ``background=None``;
    /// ``sixteen_bit`` for 16 bits per channel.
    #[pyo3(signature = (path, background=Some([0.0, 0.0, 0.0]), sixteen_bit=false))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        background: Option<[f32; 3]>,
        sixteen_bit: bool,
    ) -> PyResult<()> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        if ext.as_deref() != Some("png") {
            return Err(option_error(
                py,
                "path",
                &path.display().to_string(),
                "a .png file (Volux writes PNG images)",
            ));
        }
        let opts = png_options(py, background, sixteen_bit)?;
        let frame = self.frame.clone();
        let written: Result<(), volux_core::Error> =
            py.detach(|| frame.image.write_png(&path, &opts));
        written.py(py)
    }

    /// The PNG bytes over black (what a notebook shows).
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let png = self
            .frame
            .image
            .encode_png(&png_options(py, Some([0.0; 3]), false)?)
            .py(py)?;
        Ok(PyBytes::new(py, &png))
    }

    /// The PNG bytes ``save`` writes: over ``background`` (black by default; ``None``:
    /// transparent).
    #[pyo3(signature = (background=Some([0.0, 0.0, 0.0]), sixteen_bit=false))]
    fn to_png<'py>(
        &self,
        py: Python<'py>,
        background: Option<[f32; 3]>,
        sixteen_bit: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let png = self
            .frame
            .image
            .encode_png(&png_options(py, background, sixteen_bit)?)
            .py(py)?;
        Ok(PyBytes::new(py, &png))
    }

    /// Adaptive Simpson's estimated absolute error per pixel, shape ``(height, width)``;
    /// ``None`` for methods that do not estimate it.
    #[getter]
    fn error_map<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let img = &self.frame.image;
        self.frame
            .error_map
            .as_ref()
            .map(|e| {
                Ok(PyArray1::from_slice(py, e)
                    .reshape([img.height(), img.width()])?
                    .into_any())
            })
            .transpose()
    }

    /// The camera the frame was drawn with, in Volux's JSON form (``eye``, ``target``,
    /// ``up``, ``projection``, ``fov_y_deg`` or ``zoom``): ``camera=`` takes it back.
    #[getter]
    fn camera(&self) -> &str {
        &self.camera
    }

    /// The frame's figures: ``ms``, ``pixels``, ``method``, ``device`` (and why ``auto``
    /// chose the CPU), the caches it rebuilt.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.frame.stats;
        let d = PyDict::new(py);
        d.set_item("ms", s.ms)?;
        d.set_item("pixels", s.pixels)?;
        d.set_item("method", self.method)?;
        d.set_item("device", &self.device)?;
        d.set_item("cpu_because", &self.cpu_because)?;
        d.set_item("rebuilt_data", s.rebuilt.data)?;
        d.set_item("rebuilt_classification", s.rebuilt.classification)?;
        d.set_item("rebuilt_view", s.rebuilt.view)?;
        d.set_item("coverage", self.frame.image.coverage(0.0))?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "<volux.Image {}x{} {} on {}, {:.1} ms>",
            self.frame.image.width(),
            self.frame.image.height(),
            self.method,
            self.device,
            self.frame.stats.ms
        )
    }
}

/// The camera as the JSON a `camera=` argument takes back (an orthographic height as the
/// zoom of the volume's bounds, as `CameraSpec` writes it).
fn camera_dict(camera: &volux_core::Camera, volume: &volux_render::scene::Volume) -> String {
    let v = |d: glam::DVec3| format!("[{}, {}, {}]", d.x, d.y, d.z);
    let projection = match camera.projection {
        volux_core::Projection::Perspective { fov_y_deg } => {
            format!("\"projection\": \"perspective\", \"fov_y_deg\": {fov_y_deg}")
        }
        volux_core::Projection::Orthographic { height } => {
            let radius = (volume.bounds().diagonal() * 0.5).max(1e-9);
            format!(
                "\"projection\": \"orthographic\", \"zoom\": {}",
                2.0 * radius / height
            )
        }
    };
    format!(
        "{{\"eye\": {}, \"target\": {}, \"up\": {}, {projection}}}",
        v(camera.eye),
        v(camera.target),
        v(camera.up)
    )
}

/// The RGBA8 pixels of a PNG Volux encoded (straight alpha, sRGB): the exact bytes the
/// file holds.
fn decode_png(png: &[u8]) -> Result<Vec<u8>, String> {
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    if info.color_type != png::ColorType::Rgba || info.bit_depth != png::BitDepth::Eight {
        return Err(format!(
            "unexpected PNG {:?} {:?}",
            info.color_type, info.bit_depth
        ));
    }
    Ok(buf)
}
