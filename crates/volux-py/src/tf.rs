//! `TransferFunction`: Volux's piecewise-linear colour and extinction, from our JSON (a
//! dict in Python), a preset fitted to a volume, or a ParaView or Slicer file.
use std::path::PathBuf;

use pyo3::prelude::*;
use volux_core::TransferFunction as Tf;

use crate::errors::IntoPy;
use crate::volume::Volume;

/// A transfer function: colour ``[value, r, g, b]`` points (linear RGB) and extinction
/// ``[value, tau]`` (or opacity ``[value, alpha]``) points, in data values or normalized
/// to the data's range (``space``).
#[pyclass(
    frozen,
    from_py_object,
    module = "volux._volux",
    name = "TransferFunction"
)]
#[derive(Clone)]
pub struct TransferFunction {
    /// The function.
    pub tf: Tf,
}

#[pymethods]
impl TransferFunction {
    /// Parses Volux's JSON form (``volux tf show`` prints it; the fields are those of the
    /// dict form).
    #[staticmethod]
    fn from_json(py: Python<'_>, text: &str) -> PyResult<Self> {
        Ok(Self {
            tf: Tf::from_json(text).py(py)?,
        })
    }

    /// Reads a Volux JSON file, a ParaView preset or a Slicer ``.vp``; what the file sets
    /// that Volux does not apply is returned as notes: ``(tf, notes)``.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<(Self, Vec<String>)> {
        let (tf, notes) = volux_app::compose::read_tf_file(&path).py(py)?;
        Ok((Self { tf }, notes))
    }

    /// The preset ``name`` fitted to ``volume`` as ``volux render --tf NAME`` fits it.
    #[staticmethod]
    fn preset(py: Python<'_>, name: &str, volume: &Volume) -> PyResult<Self> {
        let (v, _) = volume.current();
        Ok(Self {
            tf: v
                .preset_tf(name)
                .map_err(volux_app::AppError::from)
                .py(py)?,
        })
    }

    /// The JSON form.
    fn to_json(&self) -> String {
        self.tf.to_json()
    }

    fn __repr__(&self) -> String {
        format!(
            "<volux.TransferFunction {} colour points, {} extinction points>",
            self.tf.color.len(),
            self.tf.extinction.len() + self.tf.opacity.len()
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.tf == other.tf
    }
}
