"""The seed's tools with the command line's semantics (``volux measure``, ``volux
regions``, ``volux sculpt``): pixels of the rendered view are picked where the opacity
along their ray reaches 0.5 under the transfer function, the clip planes and the mask;
lengths are in the grid's unit (millimetres unless the file says otherwise)."""

from . import _volux
from .scene import scene_of

__all__ = ["measure", "regions", "sculpt"]


def measure(volume, points, scene=None, **kwargs):
    """The polyline through the visible surface under ``points`` (pixels ``(x, y)`` of the
    view of ``scene``/``kwargs``): ``{"points": [(x, y, z), ...], "length": L, "unit": u}``.

    >>> volux.measure(ct, [(200, 240), (310, 250)], tf="ct-bone", view="anterior")
    """
    return _volux.measure(volume, scene_of(scene, kwargs).spec(), [tuple(p) for p in points])


def regions(volume, seeds, rule="connected", scene=None, **kwargs):
    """Labels the visible voxels from ``seeds`` ``[(x, y, label), ...]`` picked in the view:
    ``"connected"`` grows each seed through 6-connected visible voxels, ``"nearest"`` gives
    each visible voxel its nearest seed (world distance). Returns ``uint8`` labels indexed
    ``[z, y, x]`` (0: unlabelled); ``labels=`` of :func:`volux.render` draws them."""
    return _volux.regions(volume, scene_of(scene, kwargs).spec(), [tuple(s) for s in seeds], rule)


def sculpt(volume, tools, scene=None, **kwargs):
    """Applies the eraser and the digger in order to the grid seen in the view:
    ``("erase", [(x, y), ...], radius_px)`` removes what a disc swept through the pixels
    covers, through the whole depth; ``("dig", (x, y), radius_px)`` removes a ball where the
    pixel meets the visible surface. Returns ``(mask, removed)``: the mask (``uint8``
    ``[z, y, x]``, 1 kept; ``mask=`` of :func:`volux.render` takes it) and the voxels each
    tool removed."""
    return _volux.sculpt(volume, scene_of(scene, kwargs).spec(), list(tools))
