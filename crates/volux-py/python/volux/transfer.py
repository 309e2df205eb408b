"""Transfer functions from what Python users have: a preset's name or a file's path
(Volux JSON, a ParaView preset, a Slicer ``.vp``), a dict of Volux's JSON form, a
``TransferFunction``, a matplotlib colormap with an opacity curve, or layers of them with
weights.

A dict has Volux's JSON fields: ``color`` (``[value, r, g, b]`` points, linear RGB),
``extinction`` (``[value, tau]``) or ``opacity`` (``[value, alpha]`` per ``opacity_step``),
``space`` (``"value"`` or ``"normalized"`` over the data's range), ``opacity_scale``,
``unit_length``.

>>> volux.render(vol, tf="ct-bone")
>>> volux.render(vol, tf=[("ct-skin", 0.2), "ct-bone"])        # layers with weights
>>> volux.render(vol, tf={"space": "normalized",
...                       "color": [[0, 0, 0, 0], [1, 1, 1, 1]],
...                       "opacity": [[0.3, 0], [1, 0.8]]})
>>> import matplotlib
>>> volux.render(vol, tf=volux.tf_from_colormap(matplotlib.colormaps["magma"],
...                                              opacity=[(0.2, 0), (1, 0.6)]))
"""

import json
import numbers
import os

from ._volux import TransferFunction

__all__ = ["tf_from_dict", "tf_from_colormap", "tf_layers"]


def tf_from_dict(d):
    """A :class:`TransferFunction` from a dict of Volux's JSON form (checked: a wrong field
    raises :class:`volux.VoluxError` naming it)."""
    return TransferFunction.from_json(json.dumps(d))


def _srgb_to_linear(c):
    c = float(c)
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def tf_from_colormap(cmap, opacity=((0.0, 0.0), (1.0, 0.5)), samples=32, value_range=None):
    """A :class:`TransferFunction` from a matplotlib colormap (or any callable taking values
    in 0..1 and returning sRGB(A) rows) and an opacity curve ``[(position, alpha), ...]``.

    Positions are fractions of the data's range unless ``value_range=(lo, hi)`` maps them
    to data values. The colormap is sampled at ``samples`` positions and converted from sRGB
    to linear RGB (Volux composites in linear light); alpha is opacity per voxel step.
    """
    if samples < 2:
        raise ValueError("samples must be at least 2")
    import numpy as np

    xs = np.linspace(0.0, 1.0, samples)
    rows = np.asarray(cmap(xs), dtype=float)
    if rows.ndim != 2 or rows.shape[1] < 3:
        raise ValueError("the colormap must return rows of (r, g, b[, a]) for an array of positions")
    lo, hi = (0.0, 1.0) if value_range is None else map(float, value_range)
    at = lambda x: lo + (hi - lo) * float(x)  # noqa: E731
    color = [[at(x), *(_srgb_to_linear(c) for c in row[:3])] for x, row in zip(xs, rows)]
    alpha = [[at(p), float(a)] for p, a in opacity]
    d = {
        "space": "normalized" if value_range is None else "value",
        "color": color,
        "opacity": alpha,
    }
    return tf_from_dict(d)


def _source(tf):
    """One layer's source: a name or path (str), or a TransferFunction."""
    if isinstance(tf, TransferFunction):
        return tf
    if isinstance(tf, os.PathLike):
        return os.fspath(tf)
    if isinstance(tf, str):
        return tf
    if isinstance(tf, dict):
        return tf_from_dict(tf)
    if callable(tf) and hasattr(tf, "N"):
        return tf_from_colormap(tf)
    raise TypeError(
        "tf: expected a preset name, a file's path, a dict, a volux.TransferFunction, a "
        f"matplotlib colormap, or a list of them with weights; got {type(tf).__name__}"
    )


def tf_layers(tf):
    """The layers ``[(source, weight), ...]`` of any form ``tf=`` takes (``None``: the
    ``auto`` preset)."""
    if tf is None:
        return None
    if isinstance(tf, (list, tuple)):
        if len(tf) == 2 and isinstance(tf[1], numbers.Real) and not isinstance(tf[0], numbers.Real):
            return [(_source(tf[0]), float(tf[1]))]
        layers = []
        for item in tf:
            if isinstance(item, (list, tuple)) and len(item) == 2 and isinstance(item[1], numbers.Real):
                layers.append((_source(item[0]), float(item[1])))
            else:
                layers.append((_source(item), 1.0))
        return layers
    return [(_source(tf), 1.0)]
