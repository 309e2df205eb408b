"""Adapters of the objects Python users already have, keeping geometry right: nibabel
images (their RAS affine turned to Volux's LPS), SimpleITK images (LPS already), zarr
arrays and OME-Zarr stores, meshio meshes and pyvista unstructured grids.

Volux's world is LPS (+x the patient's left, +y posterior, +z superior), as DICOM, ITK and
Volux's own readers; a grid's direction matrix has the grid's axes as columns.
"""

import os
import warnings

import numpy as np

from . import _volux

__all__ = [
    "Mesh",
    "volume_from_nibabel",
    "volume_from_sitk",
    "volume_from_zarr",
    "mesh_from_meshio",
    "mesh_from_pyvista",
]

#: RAS to LPS: x and y change sign.
RAS_TO_LPS = np.diag([-1.0, -1.0, 1.0])


def geometry_of_affine(affine):
    """``(spacing, origin, direction)`` of a 4x4 voxel-to-world matrix (LPS): the columns'
    lengths, the translation, the columns normalized (the grid's axes)."""
    m = np.asarray(affine, dtype=float)
    if m.shape != (4, 4):
        raise ValueError(f"an affine is 4x4; this one is {m.shape}")
    linear = m[:3, :3]
    spacing = np.linalg.norm(linear, axis=0)
    if np.any(spacing <= 0) or not np.all(np.isfinite(spacing)):
        raise ValueError(f"the affine has a zero or non-finite axis: {linear.tolist()}")
    direction = linear / spacing
    return tuple(spacing.tolist()), tuple(m[:3, 3].tolist()), direction.tolist()


def volume_from_nibabel(image, timepoint=0):
    """A :class:`volux.Volume` from a nibabel image: values as ``image.dataobj`` scales them
    (``scl_slope``/``scl_inter``), the affine (``image.affine``: sform, else qform) from RAS
    to LPS. A 4-D image gives its ``timepoint``. The data is read in place when nibabel
    holds it in Fortran order in a type Volux holds (``.T`` is then a C-contiguous view)."""
    data = np.asanyarray(image.dataobj)
    if data.ndim == 4:
        if not 0 <= timepoint < data.shape[3]:
            raise IndexError(f"timepoint {timepoint}: the image has {data.shape[3]}")
        data = data[..., timepoint]
    elif data.ndim != 3:
        raise ValueError(f"a volume is 3-D (or 4-D with a timepoint); this image is {data.shape}")
    affine = np.eye(4)
    affine[:3] = RAS_TO_LPS @ np.asarray(image.affine, dtype=float)[:3]
    spacing, origin, direction = geometry_of_affine(affine)
    unit = _nibabel_unit(image)
    return _volux.Volume(data.T, spacing=spacing, origin=origin, direction=direction, unit=unit)


def _nibabel_unit(image):
    """The spatial unit a NIfTI header gives (``None``: millimetres)."""
    header = getattr(image, "header", None)
    get = getattr(header, "get_xyzt_units", None)
    if get is None:
        return None
    unit = get()[0]
    return {"meter": "m", "micron": "µm"}.get(unit)


def volume_from_sitk(image):
    """A :class:`volux.Volume` from a SimpleITK image (3-D, one component): its spacing,
    origin and direction as ITK holds them (LPS). The pixels are copied out of the image
    (SimpleITK's views do not keep the image alive)."""
    import SimpleITK as sitk

    if image.GetDimension() != 3:
        raise ValueError(f"a volume is 3-D; this image has {image.GetDimension()} dimensions")
    if image.GetNumberOfComponentsPerPixel() != 1:
        raise ValueError(
            f"the image has {image.GetNumberOfComponentsPerPixel()} components per pixel; "
            "pick one with sitk.VectorIndexSelectionCast(image, k)"
        )
    data = sitk.GetArrayFromImage(image)
    direction = np.asarray(image.GetDirection(), dtype=float).reshape(3, 3)
    return _volux.Volume(
        data,
        spacing=tuple(image.GetSpacing()),
        origin=tuple(image.GetOrigin()),
        direction=direction.tolist(),
    )


def volume_from_zarr(source, spacing=None, origin=None):
    """A :class:`volux.Volume` from zarr: a path or a local store of an OME-Zarr image is
    opened as ``volux.open`` opens it (out of core over the memory budget, its scale and
    translation read from the metadata); a ``zarr.Array`` is read whole, its axes of size 1
    before the last three dropped (``spacing``/``origin`` in x, y, z order)."""
    if isinstance(source, (str, os.PathLike)):
        from .files import open as open_file

        return open_file(source)
    path = _local_store_path(source)
    if path is not None and not hasattr(source, "shape"):
        from .files import open as open_file

        return open_file(path)
    if not hasattr(source, "shape"):
        raise TypeError(f"expected a zarr array, a zarr group or a path; got {type(source).__name__}")
    shape = tuple(source.shape)
    while len(shape) > 3 and shape[0] == 1:
        shape = shape[1:]
    if len(shape) != 3:
        raise ValueError(
            f"the array has shape {tuple(source.shape)}: select a channel and a timepoint "
            "(array[t, c]) to get three axes [z, y, x]"
        )
    data = np.asarray(source[...]).reshape(shape)
    return _volux.Volume(data, spacing=spacing, origin=origin)


def _local_store_path(obj):
    """The folder of a zarr group or array on a local file system, or ``None``."""
    store = getattr(obj, "store", None)
    for attr in ("root", "path", "dir_path"):
        p = getattr(store, attr, None)
        if isinstance(p, (str, os.PathLike)) and os.path.isdir(os.fspath(p)):
            sub = getattr(obj, "path", "") or ""
            return os.path.join(os.fspath(p), sub) if sub else os.fspath(p)
    return None


def _point_scalars(point_data, name, where):
    if name is not None:
        if name not in point_data:
            raise KeyError(f"{where} has no point array {name!r}; it has {sorted(point_data)}")
        values = np.asarray(point_data[name])
    else:
        one = [k for k, v in point_data.items() if np.asarray(v).ndim == 1]
        if not one:
            raise ValueError(f"{where} has no scalar point array; it has {sorted(point_data)}")
        name, values = one[0], np.asarray(point_data[one[0]])
        if len(one) > 1:
            warnings.warn(f"{where}: rendering the point array {name!r} of {one} (name= picks another)")
    if values.ndim != 1:
        raise ValueError(f"{where}: the point array {name!r} has shape {values.shape}, not one value per point")
    return values.astype(np.float32, copy=False)


def mesh_from_meshio(mesh, scalars=None):
    """A tetrahedral :class:`volux.Volume` from a ``meshio.Mesh``: its points, its
    ``tetra`` cells and the point array ``scalars`` (default: the first scalar one). Other
    volume cells (hexahedra, wedges, pyramids) are refused by name rather than dropped."""
    tets = [c.data for c in mesh.cells if c.type == "tetra"]
    others = sorted({c.type for c in mesh.cells if c.type in ("hexahedron", "wedge", "pyramid", "tetra10", "hexahedron20")})
    if others:
        raise ValueError(
            f"the mesh holds {others} cells besides tetrahedra; Volux renders tetrahedral meshes "
            "(split them first, e.g. pyvista's UnstructuredGrid.triangulate())"
        )
    if not tets:
        raise ValueError("the mesh has no tetra cells")
    values = _point_scalars(mesh.point_data, scalars, "the meshio mesh")
    return _volux.mesh(
        np.asarray(mesh.points, dtype=np.float64)[:, :3],
        np.concatenate(tets).astype(np.int64),
        values,
    )


def mesh_from_pyvista(grid, scalars=None):
    """A tetrahedral :class:`volux.Volume` from a pyvista ``UnstructuredGrid`` (or any
    dataset pyvista can cast to one): its points, its tetrahedra and the point array
    ``scalars`` (default: the active scalars). A grid with other cells is split into
    tetrahedra (``triangulate()``), said in a warning."""
    import pyvista as pv

    if not isinstance(grid, pv.UnstructuredGrid):
        grid = grid.cast_to_unstructured_grid()
    cells = grid.cells_dict
    if set(cells) - {pv.CellType.TETRA}:
        kinds = sorted(pv.CellType(k).name for k in cells if k != pv.CellType.TETRA)
        warnings.warn(f"the grid's {kinds} cells were split into tetrahedra (triangulate())")
        grid = grid.triangulate()
        cells = grid.cells_dict
    if pv.CellType.TETRA not in cells:
        raise ValueError("the grid has no tetrahedra")
    name = scalars if scalars is not None else grid.point_data.active_scalars_name
    values = _point_scalars(grid.point_data, name, "the pyvista grid")
    return _volux.mesh(
        np.asarray(grid.points, dtype=np.float64),
        np.asarray(cells[pv.CellType.TETRA], dtype=np.int64),
        values,
    )


class Mesh:
    """A tetrahedral mesh: ``volux.Mesh(points, tets, scalars)`` returns a
    :class:`volux.Volume` of kind ``"mesh"``.

    points: ``(N, 3)`` world x, y, z; tets: ``(M, 4)`` point indices; scalars: ``(N,)``
    values, one per point.
    """

    def __new__(cls, points, tets, scalars):
        return _volux.mesh(
            np.ascontiguousarray(points, dtype=np.float64),
            np.ascontiguousarray(tets, dtype=np.int64),
            np.ascontiguousarray(scalars, dtype=np.float32),
        )

    from_meshio = staticmethod(mesh_from_meshio)
    from_pyvista = staticmethod(mesh_from_pyvista)
