//! Volux for Python: the extension module `volux._volux`, a third thin front end over the
//! application layer ([`volux_app`]), as f3d's Python bindings sit on libf3d.
//!
//! Python's arguments are turned into the application layer's plain values here (numpy
//! arrays into volumes, keyword arguments into a [`volux_app::compose::SceneRequest`]), and
//! its errors into Python exceptions that keep their fields ([`errors`]). The Python package
//! around it (`crates/volux-py/python/volux`) adds what is Python's own: the adapters of
//! nibabel, SimpleITK, meshio and pyvista objects, transfer functions from dicts and
//! matplotlib colormaps, progress bars and the Jupyter widget.
//!
//! - [`volume`]: `Volume` (a numpy array read in place, a mesh, a file or a store opened by
//!   [`volux_app::open`]);
//! - [`shared`]: the numpy buffer a volume reads in place (the crate's one `unsafe` block);
//! - [`scene`]: keyword arguments as a scene request (Python's words of views, methods and
//!   integrators);
//! - [`render`]: `Renderer` (one renderer kept warm across frames), cancellation by Ctrl-C,
//!   progress, `Image`;
//! - [`tf`]: the class `TransferFunction`;
//! - [`tools`]: measurement and the seeds' sculpting tools on arrays.
#![deny(missing_docs)]
#![deny(unsafe_code)]

use pyo3::prelude::*;

pub mod errors;
pub mod render;
pub mod scene;
pub mod shared;
pub mod tf;
pub mod tools;
pub mod volume;

/// Sets the process's memory budget (bytes, or a size such as ``"8G"`` or ``"50%"``), once,
/// before anything reads it: stores over it are rendered out of core, and no structure is
/// allocated past it.
#[pyfunction]
fn set_memory_budget(py: Python<'_>, budget: &Bound<'_, PyAny>) -> PyResult<u64> {
    use errors::IntoPy;
    let bytes = match budget.extract::<u64>() {
        Ok(b) => b,
        Err(_) => volux_app::words::memory_budget(&budget.str()?.to_string_lossy())
            .map_err(volux_app::AppError::from)
            .py(py)?,
    };
    volux_core::limits::set_memory_budget(bytes).py(py)?;
    Ok(bytes)
}

/// The process's memory budget in bytes.
#[pyfunction]
fn memory_budget() -> u64 {
    volux_core::limits::memory_budget()
}

/// The extension module `volux._volux`.
#[pymodule]
fn _volux(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<volume::Volume>()?;
    m.add_class::<tf::TransferFunction>()?;
    m.add_class::<render::Image>()?;
    m.add_class::<render::Renderer>()?;
    m.add_class::<scene::SceneSpec>()?;
    m.add_function(wrap_pyfunction!(volume::open, m)?)?;
    m.add_function(wrap_pyfunction!(volume::mesh, m)?)?;
    m.add_function(wrap_pyfunction!(tools::measure, m)?)?;
    m.add_function(wrap_pyfunction!(tools::regions, m)?)?;
    m.add_function(wrap_pyfunction!(tools::sculpt, m)?)?;
    m.add_function(wrap_pyfunction!(render::gpu_built, m)?)?;
    m.add_function(wrap_pyfunction!(set_memory_budget, m)?)?;
    m.add_function(wrap_pyfunction!(memory_budget, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("PRESETS", volux_core::transfer::PRESETS.to_vec())?;
    Ok(())
}
