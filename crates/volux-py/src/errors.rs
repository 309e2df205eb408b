//! The libraries' errors as Python exceptions that keep their fields: the classes are
//! defined in Python (`volux/errors.py`, so that they can also be a `ValueError`, an
//! `OSError` or a `MemoryError`), raised here with the message in Python's words (a setting
//! as its keyword argument, a remedy as the argument that applies it) and the error's data
//! as attributes.
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::BoundObject;
use volux_app::AppError;
use volux_render::{Remedy, RenderError, Setting, Vocabulary};

/// Python's vocabulary: settings as the keyword arguments of `volux.render`.
pub struct Keywords;

impl Vocabulary for Keywords {
    fn setting(&self, setting: Setting) -> String {
        let keyword = match setting {
            Setting::Step => "step",
            Setting::Tolerance => "tol",
            Setting::FirstStep => "h0",
            Setting::MinStep => "hmin",
            Setting::MaxStep => "hmax",
            Setting::OpacityScale => "opacity_scale",
            Setting::Ambient => "ambient",
            Setting::Diffuse => "diffuse",
            Setting::Specular => "specular",
            Setting::Shininess => "shininess",
            Setting::LightDirection => "light",
            Setting::ClipPlane => "clip_planes",
            other => return other.name().to_string(),
        };
        format!("{keyword}=")
    }

    fn remedy(&self, remedy: Remedy) -> String {
        match remedy {
            Remedy::GpuBackend => "use backend='gpu'".into(),
            Remedy::CpuBackend => "use backend='cpu'".into(),
            Remedy::SplitIntoTets => "open it with volux.open(..., as_tets=True)".into(),
            Remedy::Method("tet-raycast") => "use method='raycast'".into(),
            Remedy::Method(m) => format!("use method='{m}'"),
            Remedy::DropMip => "drop mip=True".into(),
            Remedy::WritePyramid => {
                "write a pyramid with `volux convert IN OUT.ome.zarr --levels auto`".into()
            }
            Remedy::LoadLevel => {
                "open a level that fits the memory budget (level=N, memory_budget=)".into()
            }
            Remedy::SmallerImage => "render a smaller image (size=)".into(),
            other => volux_render::EngineWords.remedy(other),
        }
    }
}

/// An instance of `volux.errors.<class>` with `message` and the attributes `fields`.
pub fn raise(py: Python<'_>, class: &str, message: String, fields: &[(&str, Py<PyAny>)]) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let module = py.import("volux.errors")?;
        let kwargs = PyDict::new(py);
        for (k, v) in fields {
            kwargs.set_item(k, v)?;
        }
        let value = module
            .getattr(class)?
            .call((message.clone(),), Some(&kwargs))?;
        Ok(PyErr::from_value(value))
    };
    build().unwrap_or_else(|e| {
        PyRuntimeError::new_err(format!("{message} (volux.errors.{class} unavailable: {e})"))
    })
}

fn obj<T>(py: Python<'_>, value: T) -> Py<PyAny>
where
    T: for<'py> IntoPyObject<'py>,
{
    value
        .into_pyobject(py)
        .map(|b| b.into_bound().into_any().unbind())
        .unwrap_or_else(|_| py.None())
}

/// The engine's error as a Python exception.
pub fn render_error(py: Python<'_>, e: &RenderError) -> PyErr {
    let message = e.phrase(&Keywords);
    match e {
        RenderError::Cancelled => raise(py, "Cancelled", message, &[]),
        RenderError::Setting(s) => raise(
            py,
            "SettingError",
            message,
            &[
                (
                    "setting",
                    obj(py, Keywords.setting(s.setting).trim_end_matches('=')),
                ),
                ("value", obj(py, s.value.as_str())),
                ("expected", obj(py, s.expected.as_str())),
            ],
        ),
        RenderError::Refused(r) => raise(
            py,
            "Refused",
            message,
            &[
                ("by", obj(py, r.by.as_str())),
                ("refuses", obj(py, r.refuses.as_str())),
                ("remedy", obj(py, r.remedy.map(|m| Keywords.remedy(m)))),
            ],
        ),
        RenderError::Data(d) => core_error(py, d, message),
        RenderError::OverLimit {
            what, count, limit, ..
        } => raise(
            py,
            "OverBudget",
            message,
            &[
                ("what", obj(py, what.as_str())),
                ("bytes", obj(py, *count)),
                ("limit", obj(py, *limit)),
            ],
        ),
        RenderError::Backend { reason, remedy } => raise(
            py,
            "GpuError",
            message,
            &[
                ("reason", obj(py, reason.as_str())),
                ("remedy", obj(py, remedy.map(|m| Keywords.remedy(m)))),
            ],
        ),
        _ => raise(py, "VoluxError", message, &[]),
    }
}

/// The data model's error (`message` already phrased) as a Python exception: a memory budget
/// exceeded as `OverBudget`, the rest as `VoluxError`.
fn core_error(py: Python<'_>, e: &volux_core::Error, message: String) -> PyErr {
    match e {
        volux_core::Error::OverBudget {
            what,
            bytes,
            budget,
        } => raise(
            py,
            "OverBudget",
            format!("{message} (memory_budget=)"),
            &[
                ("what", obj(py, what.as_str())),
                ("bytes", obj(py, *bytes)),
                ("limit", obj(py, *budget)),
            ],
        ),
        _ => raise(py, "VoluxError", message, &[]),
    }
}

/// The application layer's error as a Python exception, in Python's words.
pub fn app_error(py: Python<'_>, e: &AppError) -> PyErr {
    match e {
        AppError::Render(r) => render_error(py, r),
        AppError::Read(r) => {
            let message = r.to_string();
            let over = match &r.kind {
                volux_io::ErrorKind::Data(d @ volux_core::Error::OverBudget { .. }) => Some(d),
                _ => None,
            };
            if let Some(d) = over {
                return core_error(py, d, message);
            }
            raise(
                py,
                "ReaderError",
                message,
                &[
                    ("path", obj(py, r.path.clone())),
                    ("reason", obj(py, r.kind.to_string())),
                ],
            )
        }
        AppError::Store { path, reason } => raise(
            py,
            "ReaderError",
            e.to_string(),
            &[
                ("path", obj(py, path.clone())),
                ("reason", obj(py, reason.as_str())),
            ],
        ),
        AppError::MisplacedOption { option, format } => raise(
            py,
            "OptionError",
            format!(
                "{}= applies to {} files; this one is {}",
                option.word().replace('-', "_"),
                option.owners(),
                format.name()
            ),
            &[
                ("option", obj(py, option.word().replace('-', "_"))),
                ("format", obj(py, format.name())),
            ],
        ),
        AppError::LodOnFile { lod, path, format } => {
            raise(
                py,
                "OptionError",
                format!(
                "lod={} applies to OME-Zarr stores, rendered out of core level by level; {} is \
                 {}, read whole",
                volux_app::words::level_word(*lod),
                path.display(),
                format.map_or("not a store".to_string(), |f| format!("a {} file", f.name()))
            ),
                &[("option", obj(py, "lod"))],
            )
        }
        AppError::NoSuchLevel { .. } => raise(
            py,
            "OptionError",
            format!("lod={e}"),
            &[("option", obj(py, "lod"))],
        ),
        AppError::MeshOnlyIntegrator { integrator } => raise(
            py,
            "OptionError",
            format!("integrator='{integrator}' applies to tetrahedral meshes (method='raycast')"),
            &[("option", obj(py, "integrator"))],
        ),
        AppError::NotRgb => raise(
            py,
            "OptionError",
            "tf_colour=True colours RGB volumes by the transfer function, and this volume has \
             one value per voxel"
                .into(),
            &[("option", obj(py, "tf_colour"))],
        ),
        AppError::LayerWeight { layer, weight } => raise(
            py,
            "OptionError",
            format!("tf: the weight {weight} of the layer {layer} must be >= 0"),
            &[("option", obj(py, "tf"))],
        ),
        AppError::TfFile { path, reason } => raise(
            py,
            "ReaderError",
            e.to_string(),
            &[
                ("path", obj(py, path.clone())),
                ("reason", obj(py, reason.as_str())),
            ],
        ),
        AppError::GpuNotBuilt => raise(
            py,
            "GpuError",
            "this build of volux has no GPU backend: build it with the `gpu` feature \
             (MATURIN_PEP517_ARGS='--features gpu' pip install ./crates/volux-py)"
                .into(),
            &[],
        ),
        AppError::Word(w) => raise(py, "OptionError", w.to_string(), &[]),
        other => raise(py, "VoluxError", other.to_string(), &[]),
    }
}

/// A keyword argument with a value it does not take.
pub fn option_error(py: Python<'_>, option: &str, value: &str, expected: &str) -> PyErr {
    raise(
        py,
        "OptionError",
        format!("{option}={value}: expected {expected}"),
        &[
            ("option", obj(py, option)),
            ("value", obj(py, value)),
            ("expected", obj(py, expected)),
        ],
    )
}

/// Converts the application layer's result into Python's.
pub trait IntoPy<T> {
    /// The value, or the error as a Python exception.
    fn py(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPy<T> for Result<T, AppError> {
    fn py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| app_error(py, &e))
    }
}

impl<T> IntoPy<T> for Result<T, RenderError> {
    fn py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| render_error(py, &e))
    }
}

impl<T> IntoPy<T> for Result<T, volux_core::Error> {
    fn py(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| {
            let message = e.to_string();
            core_error(py, &e, message)
        })
    }
}

/// Says the notes as Python warnings (`UserWarning`).
pub fn warn_notes(py: Python<'_>, notes: &[String]) -> PyResult<()> {
    if notes.is_empty() {
        return Ok(());
    }
    let warnings = py.import("warnings")?;
    for note in notes {
        warnings.call_method1("warn", (note.as_str(),))?;
    }
    Ok(())
}
