"""Files, DICOM folders and OME-Zarr stores opened as ``volux render FILE`` opens them."""

import os

from . import _volux
from .render_notes import say_notes

__all__ = ["open"]


def open(  # noqa: A001 (volux.open, as numpy.load or nibabel.load)
    path,
    *,
    series=None,
    array=None,
    channel=None,
    timepoint=None,
    component=None,
    level=None,
    q_variable=None,
    q_file=None,
    as_tets=False,
    memory_budget=None,
    lod=None,
):
    """Opens ``path`` (any format Volux reads: NRRD, NIfTI, MetaImage, MGH, Analyze, DICOM
    folders and files, TIFF stacks, VTK, PLOT3D, OFF, raw with a JSON sidecar, OME-Zarr) as
    a :class:`volux.Volume`.

    Reader options, each for the formats it applies to (given for another, it raises
    :class:`volux.OptionError`): ``series`` (DICOM series UID), ``array`` (VTK point array,
    OME-Zarr array), ``channel``, ``timepoint``, ``component``, ``level`` (an OME-Zarr level
    read whole), ``q_variable`` and ``q_file`` (PLOT3D). ``as_tets`` splits a grid into
    tetrahedra (for ``method="pt"``).

    An OME-Zarr store whose full level is larger than the memory budget (or opened with
    ``lod="auto"`` or a level number) is rendered out of core, brick by brick;
    ``memory_budget`` (bytes or ``"8G"``, ``"50%"``) bounds its caches.

    What the reader noted (values replaced, a store's statistics) is said as warnings and
    kept in ``volume.notes``.

    >>> ct = volux.open("series/", series="1.2.840...")
    >>> store = volux.open("cells.ome.zarr", memory_budget="2G")
    """
    volume = _volux.open(
        os.fspath(path),
        series=series,
        array=array,
        channel=channel,
        timepoint=timepoint,
        component=component,
        level=level,
        q_variable=q_variable,
        q_file=None if q_file is None else os.fspath(q_file),
        as_tets=as_tets,
        memory_budget=memory_budget,
        lod=lod,
    )
    say_notes(volume.notes)
    return volume
