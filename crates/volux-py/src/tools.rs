//! The seed's tools with the command line's semantics (`volux measure`, `volux regions`,
//! `volux sculpt`; seed `004` sec. 4.4-4.5 and 6.2), on a grid seen in a scene, through the
//! application layer's [`Workbench`]: pixels are picked on the visible surface (opacity 0.5
//! along the ray, after the clip planes and the mask), lengths are in the grid's unit.
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use volux_app::tools::Workbench;
use volux_core::sculpt::RegionRule;
use volux_render::scene::Volume as RVolume;

use crate::errors::{option_error, IntoPy};
use crate::scene::SceneSpec;
use crate::volume::Volume;

/// The workbench of `volume` (a grid) in `scene`.
fn workbench(py: Python<'_>, volume: &Volume, scene: &SceneSpec) -> PyResult<Workbench> {
    let (v, _) = volume.current();
    let RVolume::Grid(grid) = &v else {
        return Err(option_error(
            py,
            "volume",
            v.kind(),
            "a grid read whole: sculpting, measuring and labelling apply to grids",
        ));
    };
    let request = scene.args(py, &v)?.request(py)?;
    let composed = volux_app::compose::compose_scene(&request, &v).py(py)?;
    Workbench::new(grid.clone(), composed.scene).py(py)
}

fn check_pixel(py: Python<'_>, bench: &Workbench, what: &str, p: [f64; 2]) -> PyResult<()> {
    if bench.in_image(p) {
        return Ok(());
    }
    let (w, h) = bench.size();
    Err(option_error(
        py,
        what,
        &format!("({}, {})", p[0], p[1]),
        &format!("a pixel in the {w}x{h} image"),
    ))
}

fn no_surface(py: Python<'_>, what: &str, p: [f64; 2]) -> PyErr {
    option_error(
        py,
        what,
        &format!("({}, {})", p[0], p[1]),
        "a pixel that shows a visible surface (its ray reaches opacity 0.5 under the transfer \
         function, clip planes and mask)",
    )
}

/// Measures the polyline through the visible surface under ``points`` (pixels ``(x, y)``)
/// in ``scene``: ``{"points": [(x, y, z), ...], "length": L, "unit": "mm"}`` in world units.
#[pyfunction]
pub fn measure<'py>(
    py: Python<'py>,
    volume: &Volume,
    scene: &SceneSpec,
    points: Vec<[f64; 2]>,
) -> PyResult<Bound<'py, PyDict>> {
    if points.len() < 2 {
        return Err(option_error(
            py,
            "points",
            &format!("{} point(s)", points.len()),
            "at least two pixels to measure between",
        ));
    }
    let bench = workbench(py, volume, scene)?;
    for p in &points {
        check_pixel(py, &bench, "points", *p)?;
    }
    let (world, length) = match bench.measure(&points).py(py)? {
        Ok(m) => m,
        Err(n) => return Err(no_surface(py, "points", points[n])),
    };
    let d = PyDict::new(py);
    let xyz: Vec<(f64, f64, f64)> = world.iter().map(|p| (p.x, p.y, p.z)).collect();
    d.set_item("points", xyz)?;
    d.set_item("length", length)?;
    d.set_item("unit", bench.grid.unit())?;
    Ok(d)
}

/// Labels the visible voxels from seeds ``(x, y, label)`` picked on the visible surface
/// (labels 1 to 255), by ``rule``: ``"connected"`` grows each seed's region through the
/// 6-connected visible voxels, ``"nearest"`` gives each visible voxel its nearest seed.
/// Returns a ``uint8`` array indexed ``[z, y, x]`` (0: unlabelled).
#[pyfunction]
#[pyo3(signature = (volume, scene, seeds, rule="connected"))]
pub fn regions<'py>(
    py: Python<'py>,
    volume: &Volume,
    scene: &SceneSpec,
    seeds: Vec<(f64, f64, u8)>,
    rule: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let rule = match rule {
        "connected" => RegionRule::Connected,
        "nearest" => RegionRule::Nearest,
        other => return Err(option_error(py, "rule", other, "'connected' or 'nearest'")),
    };
    if seeds.is_empty() {
        return Err(option_error(
            py,
            "seeds",
            "[]",
            "at least one (x, y, label)",
        ));
    }
    let mut bench = workbench(py, volume, scene)?;
    for (x, y, label) in &seeds {
        if *label == 0 {
            return Err(option_error(py, "seeds", "label 0", "labels 1 to 255"));
        }
        check_pixel(py, &bench, "seeds", [*x, *y])?;
        if !bench.seed_region([*x, *y], *label, rule).py(py)? {
            return Err(no_surface(py, "seeds", [*x, *y]));
        }
    }
    let labels = py.detach(|| bench.labels());
    let labels = labels.py(py)?;
    let [nx, ny, nz] = bench.grid.dims();
    Ok(PyArray1::from_vec(py, labels)
        .reshape([nz, ny, nx])?
        .into_any())
}

/// One tool of ``volux.sculpt``.
#[derive(FromPyObject)]
enum Tool {
    /// ``("erase", [(x, y), ...], radius)``: a disc swept through the pixels.
    Erase(String, Vec<[f64; 2]>, f64),
    /// ``("dig", (x, y), radius)``: a ball dug where the pixel meets the surface.
    Dig(String, [f64; 2], f64),
}

/// Applies the eraser and the digger in order (as ``volux sculpt``) to the grid seen in
/// ``scene``: ``tools`` are ``("erase", [(x, y), ...], radius_px)`` and ``("dig", (x, y),
/// radius_px)``. Returns ``(mask, removed)``: the mask as a ``uint8`` array indexed ``[z, y,
/// x]`` (1 kept, 0 removed; ``mask=`` of ``volux.render`` takes it) and the voxels each tool
/// removed.
#[pyfunction]
pub fn sculpt<'py>(
    py: Python<'py>,
    volume: &Volume,
    scene: &SceneSpec,
    tools: Vec<Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Vec<u64>)> {
    let form = "('erase', [(x, y), ...], radius) or ('dig', (x, y), radius), radius > 0";
    let mut parsed = Vec::with_capacity(tools.len());
    for t in &tools {
        let bad = || {
            option_error(
                py,
                "tools",
                &t.repr().map(|r| r.to_string()).unwrap_or_default(),
                form,
            )
        };
        let tool: Tool = t.extract().map_err(|_| bad())?;
        let ok = match &tool {
            Tool::Erase(kind, points, r) => kind == "erase" && !points.is_empty() && *r > 0.0,
            Tool::Dig(kind, _, r) => kind == "dig" && *r > 0.0,
        };
        if !ok {
            return Err(bad());
        }
        parsed.push(tool);
    }
    let mut bench = workbench(py, volume, scene)?;
    let mut removed = Vec::with_capacity(parsed.len());
    for tool in parsed {
        match tool {
            Tool::Erase(_, points, radius) => {
                for p in &points {
                    check_pixel(py, &bench, "tools", *p)?;
                }
                removed.push(bench.erase(points, radius).py(py)?);
            }
            Tool::Dig(_, pixel, radius) => {
                check_pixel(py, &bench, "tools", pixel)?;
                match bench.dig(pixel, radius).py(py)? {
                    Some(n) => removed.push(n),
                    None => return Err(no_surface(py, "tools", pixel)),
                }
            }
        }
    }
    let values = bench.sculpt.mask().to_values();
    let [nx, ny, nz] = bench.grid.dims();
    Ok((
        PyArray1::from_vec(py, values)
            .reshape([nz, ny, nx])?
            .into_any(),
        removed,
    ))
}
