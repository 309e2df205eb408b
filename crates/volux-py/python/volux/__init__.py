"""Volux for Python: numpy in, pictures out, the viewer in Jupyter.

Volux renders 3D scalar data (CT, MRI and dose grids, microscopy stores larger than memory,
tetrahedral CFD meshes) with accurate, fast volume rendering: ray casting with adaptive
Simpson integration, Projected Tetrahedra with partial pre-integration, texture slicing,
isosurfaces, clipping and sculpting. This package is a thin front end over the same
application layer as the ``volux`` command line, so the same scene gives the same picture.

Start here:

>>> import volux
>>> head = volux.open("head.nrrd")                  # any format volux reads
>>> volux.render(head, tf="ct-bone", view="anterior").save("head.png")

>>> import numpy as np
>>> ct = np.zeros((64, 64, 64), np.int16)           # indexed [z, y, x]
>>> vol = volux.Volume(ct, spacing=(0.8, 0.8, 2.0))  # read in place, no copy
>>> img = volux.render(vol, size=(256, 256))
>>> img.to_numpy().shape
(256, 256, 4)

- Data in: :func:`open`, :class:`Volume` (numpy arrays), :class:`Mesh` (points, tets,
  scalars), ``Volume.from_nibabel``, ``Volume.from_sitk``, ``Volume.from_zarr``,
  ``Mesh.from_meshio``, ``Mesh.from_pyvista``.
- Pictures out: :func:`render`, :class:`Renderer` (warm frames), :class:`Scene`,
  :class:`Image` (``to_numpy``, ``save``, shown by notebooks).
- Transfer functions: presets (:data:`PRESETS`), files, dicts, :func:`tf_from_colormap`.
- Tools: :func:`measure`, :func:`regions`, :func:`sculpt`, :func:`accuracy`.
- Jupyter: :func:`show`.
"""

from . import errors
from ._volux import (
    PRESETS,
    Image,
    TransferFunction,
    Volume,
    __version__,
    gpu_built,
    memory_budget,
    set_memory_budget,
)
from .errors import (
    Cancelled,
    GpuError,
    OptionError,
    OverBudget,
    ReaderError,
    Refused,
    SettingError,
    VoluxError,
)
from .scene import Scene
from .rendering import Renderer, accuracy, render
from .transfer import tf_from_colormap, tf_from_dict
from .adapters import Mesh
from .tools import measure, regions, sculpt
from .files import open
from .widget import show

__all__ = [
    "PRESETS",
    "Cancelled",
    "GpuError",
    "Image",
    "Mesh",
    "OptionError",
    "OverBudget",
    "ReaderError",
    "Refused",
    "Renderer",
    "Scene",
    "SettingError",
    "TransferFunction",
    "Volume",
    "VoluxError",
    "__version__",
    "accuracy",
    "errors",
    "gpu_built",
    "measure",
    "memory_budget",
    "open",
    "regions",
    "render",
    "sculpt",
    "set_memory_budget",
    "show",
    "tf_from_colormap",
    "tf_from_dict",
]
