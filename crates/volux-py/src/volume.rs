//! `Volume`: what Volux renders, from a numpy array read in place ([`crate::shared`]), a
//! tetrahedral mesh's arrays, or a file, folder or store opened by the application layer
//! ([`volux_app::open`]).
//!
//! Arrays are indexed `[z, y, x]` (C order, x fastest: numpy's, SimpleITK's and zarr's
//! order); geometry is given in world `x, y, z` order (spacing, origin, and a direction
//! matrix whose columns are the grid's axes), in LPS as every reader of Volux returns it.
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use glam::{DMat3, DVec3, Vec3};
use numpy::{
    PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use volux_app::open::{OpenRequest, OpenedVolume};
use volux_app::session::DatasetRef;
use volux_core::{Grid, Samples, TetMesh};
use volux_render::scene::Volume as RVolume;

use crate::errors::{option_error, IntoPy};
use crate::shared::NumpyBytes;

/// Where a volume's samples come from.
#[derive(Clone)]
enum Source {
    /// A numpy array read in place, and the geometry the grid is rebuilt with.
    Array {
        owner: Arc<NumpyBytes>,
        samples: Samples,
        geometry: Geometry,
    },
    /// A mesh, a file, a store: nothing to re-read.
    Fixed,
}

/// A grid's geometry as given.
#[derive(Clone, Copy)]
struct Geometry {
    dims: [usize; 3],
    spacing: [f64; 3],
    origin: [f64; 3],
    direction: DMat3,
}

impl Geometry {
    fn grid(&self, samples: Samples) -> Result<Grid, volux_core::Error> {
        Grid::new(self.dims, self.spacing, self.origin, samples)?.with_direction(self.direction)
    }
}

/// The volume and the count of its changes (renderers rebuild when it moves).
struct State {
    volume: RVolume,
    generation: u64,
    source: Source,
    notes: Vec<String>,
    /// The file, folder or store it was opened from.
    path: Option<PathBuf>,
}

/// A volume to render: a grid (from a numpy array or a file), a tetrahedral mesh, or an
/// OME-Zarr store rendered out of core.
///
/// ``volux.Volume(array, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None)`` reads a
/// numpy array indexed ``[z, y, x]`` in place when it is C-contiguous ``uint8``,
/// ``uint16``, ``int16`` or ``float32`` (the Python wrapper converts other arrays, with a
/// warning). After changing the array in place, call ``volume.modified()``.
#[pyclass(frozen, module = "volux._volux", name = "Volume")]
pub struct Volume {
    state: Mutex<State>,
}

impl Volume {
    fn wrap(volume: RVolume, source: Source, notes: Vec<String>) -> Self {
        Self {
            state: Mutex::new(State {
                volume,
                generation: 0,
                source,
                notes,
                path: None,
            }),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The engine's volume and its generation.
    pub fn current(&self) -> (RVolume, u64) {
        let s = self.lock();
        (s.volume.clone(), s.generation)
    }
}

fn triple(py: Python<'_>, name: &str, v: Option<Vec<f64>>, default: f64) -> PyResult<[f64; 3]> {
    match v {
        None => Ok([default; 3]),
        Some(v) => match v.as_slice() {
            [a, b, c] => Ok([*a, *b, *c]),
            _ => Err(option_error(
                py,
                name,
                &format!("{v:?}"),
                "three numbers in world x, y, z order",
            )),
        },
    }
}

fn direction(py: Python<'_>, d: Option<Vec<Vec<f64>>>) -> PyResult<DMat3> {
    let Some(rows) = d else {
        return Ok(DMat3::IDENTITY);
    };
    let bad = || {
        option_error(
            py,
            "direction",
            &format!("{rows:?}"),
            "a 3x3 matrix whose columns are the grid's x, y, z axes in world (LPS) coordinates",
        )
    };
    if rows.len() != 3 || rows.iter().any(|r| r.len() != 3) {
        return Err(bad());
    }
    // Rows as given; columns are the axes.
    Ok(DMat3::from_cols(
        DVec3::new(rows[0][0], rows[1][0], rows[2][0]),
        DVec3::new(rows[0][1], rows[1][1], rows[2][1]),
        DVec3::new(rows[0][2], rows[1][2], rows[2][2]),
    ))
}

#[pymethods]
impl Volume {
    /// A grid read in place from a numpy array indexed ``[z, y, x]`` (C-contiguous
    /// ``uint8``, ``uint16``, ``int16`` or ``float32`` in native byte order); any other
    /// array is converted once (``volux._arrays.volume_array`` says how, as a warning).
    #[new]
    #[pyo3(signature = (array, spacing=None, origin=None, direction=None, unit=None))]
    fn new(
        py: Python<'_>,
        array: &Bound<'_, PyAny>,
        spacing: Option<Vec<f64>>,
        origin: Option<Vec<f64>>,
        direction: Option<Vec<Vec<f64>>>,
        unit: Option<String>,
    ) -> PyResult<Self> {
        let (array, note): (Bound<'_, PyAny>, Option<String>) = py
            .import("volux._arrays")?
            .call_method1("volume_array", (array,))?
            .extract()?;
        if let Some(note) = note {
            crate::errors::warn_notes(py, &[note])?;
        }
        let array = array.cast::<PyUntypedArray>()?;
        let shape = array.shape().to_vec();
        let [nz, ny, nx] = shape[..] else {
            return Err(PyValueError::new_err(format!(
                "a volume is a 3-D array indexed [z, y, x]; this one has shape {shape:?}"
            )));
        };
        let Some((samples, owner)) = crate::shared::share(array)? else {
            return Err(PyTypeError::new_err(format!(
                "volux._arrays.volume_array returned a {} array it cannot read in place",
                array.dtype()
            )));
        };
        let geometry = Geometry {
            dims: [nx, ny, nz],
            spacing: triple(py, "spacing", spacing, 1.0)?,
            origin: triple(py, "origin", origin, 0.0)?,
            direction: self::direction(py, direction)?,
        };
        let mut grid = geometry.grid(samples.clone()).py(py)?;
        if let Some(u) = unit {
            grid = grid.with_unit(&u);
        }
        let notes = grid.notes().to_vec();
        Ok(Self::wrap(
            RVolume::from(grid),
            Source::Array {
                owner,
                samples,
                geometry,
            },
            notes,
        ))
    }

    /// A grid from a nibabel image (NIfTI, MGH, ...): the values as the image's
    /// ``dataobj`` holds them (scaled by ``scl_slope``/``scl_inter`` where set) and its
    /// affine turned from RAS to LPS, as ``volux.open`` reads the file.
    #[staticmethod]
    fn from_nibabel(py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        adapter(py, "volume_from_nibabel", image)
    }

    /// A grid from a SimpleITK image, its geometry as ITK holds it (LPS).
    #[staticmethod]
    fn from_sitk(py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        adapter(py, "volume_from_sitk", image)
    }

    /// A volume from a zarr array (read whole, indexed ``[z, y, x]`` or with leading
    /// axes of size 1) or an OME-Zarr path or store (opened as ``volux.open`` opens it: out of
    /// core over the memory budget).
    #[staticmethod]
    fn from_zarr(py: Python<'_>, source: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        adapter(py, "volume_from_zarr", source)
    }

    /// Re-reads the array after an in-place change (its value range, the renderers'
    /// caches): the next frame draws the new values. Do not change the array while a frame
    /// is being drawn.
    fn modified(&self, py: Python<'_>) -> PyResult<()> {
        let mut s = self.lock();
        if let Source::Array {
            samples, geometry, ..
        } = &s.source
        {
            let unit = match &s.volume {
                RVolume::Grid(g) => g.unit().to_string(),
                _ => "mm".to_string(),
            };
            let grid = geometry.grid(samples.clone()).py(py)?.with_unit(&unit);
            s.notes = grid.notes().to_vec();
            s.volume = RVolume::from(grid);
        }
        s.generation += 1;
        Ok(())
    }

    /// The file, folder or store the volume was opened from (``None`` for arrays).
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.lock().path.clone()
    }

    /// Writes the volume: a grid as NRRD (``.nrrd``, its geometry kept), a mesh as Volux's
    /// binary tet mesh (``.vtet``); what ``volux`` and ``volux-view`` open.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let volume = self.lock().volume.clone();
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        let written = match (&volume, ext.as_deref()) {
            (RVolume::Grid(g), Some("nrrd")) => py.detach(|| volux_io::nrrd::write(g, &path)),
            (RVolume::Mesh(m), Some("vtet")) => py.detach(|| volux_io::vtet::write(m, &path)),
            (other, _) => {
                return Err(option_error(
                    py,
                    "path",
                    &path.display().to_string(),
                    &format!(
                        "a .nrrd file for a grid, a .vtet file for a mesh (this volume is a {})",
                        other.kind()
                    ),
                ))
            }
        };
        written.map_err(|e| crate::errors::raise(py, "VoluxError", e.to_string(), &[]))
    }

    /// ``"grid"``, ``"mesh"`` or ``"bricked"`` (a store rendered out of core).
    #[getter]
    fn kind(&self) -> &'static str {
        match &self.lock().volume {
            RVolume::Grid(_) => "grid",
            RVolume::Mesh(_) => "mesh",
            RVolume::Bricked(..) => "bricked",
            other => other.kind(),
        }
    }

    /// Grid samples per axis in world order ``(nx, ny, nz)``; ``None`` for a mesh.
    #[getter]
    fn dims(&self) -> Option<(usize, usize, usize)> {
        match &self.lock().volume {
            RVolume::Grid(g) => {
                let [x, y, z] = g.dims();
                Some((x, y, z))
            }
            RVolume::Bricked(b, _) => b.cache(0).map(|c| {
                let [x, y, z] = c.layout().dims;
                (x, y, z)
            }),
            _ => None,
        }
    }

    /// The numpy shape of the grid, ``(nz, ny, nx)``; ``None`` for a mesh.
    #[getter]
    fn shape(&self) -> Option<(usize, usize, usize)> {
        self.dims().map(|(x, y, z)| (z, y, x))
    }

    /// Voxel spacing in world x, y, z order (grids).
    #[getter]
    fn spacing(&self) -> Option<(f64, f64, f64)> {
        match &self.lock().volume {
            RVolume::Grid(g) => Some(g.spacing().into()),
            _ => None,
        }
    }

    /// The world position of voxel (0, 0, 0) (grids).
    #[getter]
    fn origin(&self) -> Option<(f64, f64, f64)> {
        match &self.lock().volume {
            RVolume::Grid(g) => Some(g.origin().into()),
            _ => None,
        }
    }

    /// The grid's axes as the columns of a 3x3 matrix (rows listed), LPS.
    #[getter]
    fn direction(&self) -> Option<Vec<Vec<f64>>> {
        match &self.lock().volume {
            RVolume::Grid(g) => {
                let m = g.direction();
                Some(
                    (0..3)
                        .map(|r| (0..3).map(|c| m.col(c)[r]).collect())
                        .collect(),
                )
            }
            _ => None,
        }
    }

    /// The unit of lengths (``"mm"`` unless the file says otherwise).
    #[getter]
    fn unit(&self) -> String {
        match &self.lock().volume {
            RVolume::Grid(g) => g.unit().to_string(),
            _ => "mm".to_string(),
        }
    }

    /// The value range ``(min, max)``.
    #[getter]
    fn range(&self) -> (f64, f64) {
        let r = self.lock().volume.range();
        (r[0], r[1])
    }

    /// The grid's numpy dtype name (``"uint8"``, ...); ``"float32"`` for a mesh.
    #[getter]
    fn dtype(&self) -> &'static str {
        match &self.lock().volume {
            RVolume::Grid(g) => g.scalar_type().name(),
            _ => "float32",
        }
    }

    /// World bounds ``((xmin, ymin, zmin), (xmax, ymax, zmax))``.
    #[getter]
    fn bounds(&self) -> ((f64, f64, f64), (f64, f64, f64)) {
        let b = self.lock().volume.bounds();
        (b.min.into(), b.max.into())
    }

    /// Whether the samples are the numpy array's own memory (no copy).
    #[getter]
    fn shares_memory(&self) -> bool {
        match &self.lock().volume {
            RVolume::Grid(g) => match g.samples() {
                Samples::U8(b) => b.is_shared(),
                Samples::U16(b) => b.is_shared(),
                Samples::I16(b) => b.is_shared(),
                Samples::F32(b) => b.is_shared(),
            },
            _ => false,
        }
    }

    /// What the reader or the data model noted (non-finite values replaced, axes read, a
    /// store's statistics), one sentence each.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.lock().notes.clone()
    }

    /// The tetrahedra's count (meshes).
    #[getter]
    fn cells(&self) -> Option<usize> {
        match &self.lock().volume {
            RVolume::Mesh(m) => Some(m.tets().len()),
            _ => None,
        }
    }

    /// The store's pyramid levels (stores rendered out of core).
    #[getter]
    fn levels(&self) -> Option<usize> {
        match &self.lock().volume {
            RVolume::Bricked(b, _) => Some(b.levels()),
            _ => None,
        }
    }

    /// The histogram of the values: ``(counts, (min, max))`` over ``bins`` equal bins.
    #[pyo3(signature = (bins=256))]
    fn histogram(&self, bins: usize) -> PyResult<(Vec<u64>, (f64, f64))> {
        if bins == 0 || bins > 1 << 20 {
            return Err(PyValueError::new_err(format!(
                "bins={bins}: expected 1 to {}",
                1 << 20
            )));
        }
        let h = self.lock().volume.histogram(bins);
        Ok((h.counts, (h.min, h.max)))
    }

    /// The samples as a numpy array indexed ``[z, y, x]``: the array itself for a volume
    /// that reads one in place, a copy otherwise (grids read whole only).
    fn to_numpy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.lock();
        if let Source::Array { owner, .. } = &s.source {
            return Ok(owner.array(py).into_any());
        }
        let RVolume::Grid(g) = &s.volume else {
            return Err(PyTypeError::new_err(format!(
                "to_numpy() applies to grids read whole; this volume is a {}",
                s.volume.kind()
            )));
        };
        let [nx, ny, nz] = g.dims();
        let shape = [nz, ny, nx];
        Ok(match g.samples() {
            Samples::U8(b) => PyArray1::from_slice(py, b).reshape(shape)?.into_any(),
            Samples::U16(b) => PyArray1::from_slice(py, b).reshape(shape)?.into_any(),
            Samples::I16(b) => PyArray1::from_slice(py, b).reshape(shape)?.into_any(),
            Samples::F32(b) => PyArray1::from_slice(py, b).reshape(shape)?.into_any(),
        })
    }

    fn __repr__(&self) -> String {
        let s = self.lock();
        match &s.volume {
            RVolume::Grid(g) => {
                let [x, y, z] = g.dims();
                let sp = g.spacing();
                format!(
                    "<volux.Volume grid {x}x{y}x{z} {} spacing ({}, {}, {}) {} range [{}, {}]{}>",
                    g.scalar_type().name(),
                    sp.x,
                    sp.y,
                    sp.z,
                    g.unit(),
                    g.range()[0],
                    g.range()[1],
                    if matches!(s.source, Source::Array { .. }) {
                        " (numpy array, in place)"
                    } else {
                        ""
                    }
                )
            }
            RVolume::Mesh(m) => format!(
                "<volux.Volume mesh {} points {} tets range [{}, {}]>",
                m.positions().len(),
                m.tets().len(),
                m.range()[0],
                m.range()[1]
            ),
            other => format!("<volux.Volume {}>", other.kind()),
        }
    }
}

/// Calls the Python adapter `name` of `volux.adapters`.
fn adapter(py: Python<'_>, name: &str, source: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    Ok(py
        .import("volux.adapters")?
        .call_method1(name, (source,))?
        .unbind())
}

/// A tetrahedral mesh from its arrays: ``points`` (N x 3, world x, y, z), ``tets`` (M x 4
/// point indices) and ``scalars`` (N values, one per point).
#[pyfunction]
pub fn mesh(
    py: Python<'_>,
    points: PyReadonlyArray2<'_, f64>,
    tets: PyReadonlyArray2<'_, i64>,
    scalars: PyReadonlyArray1<'_, f32>,
) -> PyResult<Volume> {
    let p = points.as_array();
    let t = tets.as_array();
    if p.ncols() != 3 || t.ncols() != 4 {
        return Err(PyValueError::new_err(format!(
            "points are N x 3 and tets M x 4; given {:?} and {:?}",
            p.shape(),
            t.shape()
        )));
    }
    let n = p.nrows();
    let positions: Vec<Vec3> = p
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32))
        .collect();
    let mut cells = Vec::with_capacity(t.nrows());
    for (i, r) in t.rows().into_iter().enumerate() {
        let mut c = [0u32; 4];
        for k in 0..4 {
            let v = r[k];
            if v < 0 || v as u64 >= n as u64 {
                return Err(PyValueError::new_err(format!(
                    "tets[{i}] names point {v}; the mesh has {n} points"
                )));
            }
            c[k] = v as u32;
        }
        cells.push(c);
    }
    let values = scalars.as_array().to_vec();
    if values.len() != n {
        return Err(PyValueError::new_err(format!(
            "scalars holds {} values; the mesh has {n} points",
            values.len()
        )));
    }
    let mesh = TetMesh::new(positions, values, cells).py(py)?;
    let notes = mesh.notes().to_vec();
    Ok(Volume::wrap(RVolume::from(mesh), Source::Fixed, notes))
}

/// Opens a file, a DICOM folder or an OME-Zarr store as Volux's readers read it (the same
/// as ``volux render FILE``): a store larger than ``memory_budget`` (or opened with
/// ``lod=``) is rendered out of core.
#[pyfunction]
#[pyo3(signature = (path, *, series=None, array=None, channel=None, timepoint=None, component=None, level=None, q_variable=None, q_file=None, as_tets=false, memory_budget=None, lod=None))]
#[allow(clippy::too_many_arguments)]
pub fn open(
    py: Python<'_>,
    path: PathBuf,
    series: Option<String>,
    array: Option<String>,
    channel: Option<usize>,
    timepoint: Option<usize>,
    component: Option<usize>,
    level: Option<usize>,
    q_variable: Option<String>,
    q_file: Option<PathBuf>,
    as_tets: bool,
    memory_budget: Option<&Bound<'_, PyAny>>,
    lod: Option<&Bound<'_, PyAny>>,
) -> PyResult<Volume> {
    let dataset = DatasetRef {
        path,
        q_variable,
        q_file,
        series_uid: series,
        array,
        as_tets,
        channel,
        timepoint,
        component,
        level,
    };
    let budget = match memory_budget {
        None => volux_core::limits::memory_budget(),
        Some(b) => match b.extract::<u64>() {
            Ok(bytes) => bytes,
            Err(_) => volux_app::words::memory_budget(&b.str()?.to_string_lossy())
                .map_err(volux_app::AppError::from)
                .py(py)?,
        },
    };
    let lod = match lod {
        None => None,
        Some(l) => Some(match l.extract::<usize>() {
            Ok(n) => volux_render::bricked::Lod::Level(n),
            Err(_) => volux_app::words::level(&l.str()?.to_string_lossy())
                .map_err(volux_app::AppError::from)
                .py(py)?,
        }),
    };
    let request = OpenRequest { lod, budget };
    let opened: Result<OpenedVolume, volux_app::AppError> =
        py.detach(|| volux_app::open::open_volume(&dataset, &request));
    let opened = opened.py(py)?;
    let volume = Volume::wrap(opened.volume, Source::Fixed, opened.notes);
    volume.lock().path = Some(dataset.path);
    Ok(volume)
}
