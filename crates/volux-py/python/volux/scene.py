"""A scene as keyword arguments: what ``volux.render`` draws, kept as attributes a notebook
can change (``scene.view = "left"``, ``scene.tf = "ct-bone"``) between frames."""

import json
import os

from . import _volux
from .transfer import tf_layers

#: Every keyword of a scene and its default (the command line's defaults).
DEFAULTS = {
    "tf": None,
    "view": None,
    "azimuth": None,
    "elevation": None,
    "up": None,
    "zoom": 1.0,
    "orthographic": False,
    "camera": None,
    "size": (512, 512),
    "method": "auto",
    "integrator": "riemann",
    "step": 0.5,
    "tol": 0.01,
    "h0": 0.5,
    "hmin": 0.001,
    "hmax": 0.5,
    "reconstruction": "trilinear",
    "jitter": False,
    "color": "psi",
    "sort": "centroid",
    "resample": 256,
    "shade": False,
    "ambient": 0.3,
    "diffuse": 0.7,
    "specular": 0.3,
    "shininess": 32.0,
    "light": None,
    "iso": None,
    "mip": False,
    "opacity_scale": 1.0,
    "tf_colour": False,
    "early_termination": True,
    "clip_planes": None,
    "mask": None,
    "labels": None,
    "frame": "visible",
}


class Scene:
    """What to draw and how: every keyword of :func:`volux.render` as an attribute.

    >>> s = volux.Scene(tf="ct-bone", view="anterior", size=(256, 256))
    >>> s.view = "left"
    >>> img = renderer.render(s)
    """

    def __init__(self, **kwargs):
        unknown = set(kwargs) - set(DEFAULTS)
        if unknown:
            raise TypeError(
                f"Scene() got unknown arguments {sorted(unknown)}; "
                f"it takes {', '.join(sorted(DEFAULTS))}"
            )
        self.__dict__.update(DEFAULTS)
        self.__dict__.update(kwargs)

    def replace(self, **kwargs):
        """A copy with ``kwargs`` changed."""
        return Scene(**{**self.options(), **kwargs})

    def options(self):
        """The keyword arguments, as a dict."""
        return {k: self.__dict__[k] for k in DEFAULTS}

    def spec(self):
        """The scene checked by the engine (every word and value; a wrong one raises
        :class:`volux.OptionError` or :class:`volux.SettingError`)."""
        o = self.options()
        o["tf"] = tf_layers(o["tf"])
        o["camera"] = _camera_json(o["camera"])
        o["iso"] = _isos(o["iso"])
        if o["light"] is not None and isinstance(o["light"], str):
            if o["light"] != "headlight":
                raise _volux_option("light", o["light"], "(x, y, z) or 'headlight'")
            o["light"] = None
        if isinstance(o["size"], int):
            o["size"] = (o["size"], o["size"])
        o["size"] = tuple(o["size"])
        for key in ("up", "light"):
            if o[key] is not None:
                o[key] = tuple(o[key])
        if o["clip_planes"] is not None:
            o["clip_planes"] = [tuple(p) for p in o["clip_planes"]]
        return _volux.SceneSpec(**o)

    def __repr__(self):
        changed = {k: v for k, v in self.options().items() if v is not DEFAULTS[k] and v != DEFAULTS[k]}
        inner = ", ".join(f"{k}={v!r}" for k, v in changed.items() if k not in ("mask", "labels"))
        return f"volux.Scene({inner})"


def _volux_option(option, value, expected):
    from .errors import OptionError

    return OptionError(f"{option}={value!r}: expected {expected}", option=option, value=value, expected=expected)


def _camera_json(camera):
    """A camera's JSON text from a dict, a JSON text, a file's path or ``None``."""
    if camera is None:
        return None
    if isinstance(camera, dict):
        return json.dumps(camera)
    if isinstance(camera, (str, os.PathLike)):
        text = os.fspath(camera)
        if text.lstrip().startswith("{"):
            return text
        with open(text, encoding="utf-8") as f:
            return f.read()
    raise _volux_option("camera", camera, "a dict, a JSON text or a camera file's path")


def _isos(iso):
    """A list of isosurfaces from one value, one ``(value, rgba)`` or a list of them."""
    if iso is None:
        return None
    if isinstance(iso, (int, float, str)):
        return [iso]
    if isinstance(iso, tuple) and len(iso) == 2 and isinstance(iso[0], (int, float)) and not isinstance(iso[1], (int, float)):
        return [iso]
    return list(iso)


def scene_of(scene, kwargs):
    """The scene of ``render(scene, **kwargs)``: the scene with ``kwargs`` changed, or a
    scene of ``kwargs``."""
    if scene is None:
        return Scene(**kwargs)
    if isinstance(scene, dict):
        return Scene(**{**scene, **kwargs})
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a volux.Scene or a dict, got {type(scene).__name__}")
    return scene.replace(**kwargs) if kwargs else scene
