"""``volux.show()``: the volume in Jupyter as an interactive widget (anywidget) that orbits,
pans and zooms with the mouse, draws quick previews while the mouse drags and the full frame
when it stops, and exposes its scene as Python attributes; outside Jupyter it opens
``volux-view`` when it is installed.

>>> w = volux.show(ct, tf="ct-bone")
>>> w.tf = "ct-skin"          # redraws
>>> w.camera                  # the camera now, as a dict (eye, target, up, ...)
>>> w.image.save("now.png")   # the last full frame
"""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

from .rendering import Renderer

__all__ = ["show", "VolumeWidget", "in_notebook"]

#: Degrees of orbit per pixel dragged.
ORBIT_DEG_PER_PX = 0.5
#: Zoom factor per 100 units of wheel.
WHEEL_FACTOR = 1.15
#: The scene's keywords that place the camera by orbit (a camera dict replaces them).
VIEW_KEYWORDS = {"view", "azimuth", "elevation", "up", "zoom", "orthographic", "frame"}


def in_notebook():
    """Whether this runs in a Jupyter kernel."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    shell = ipython.get_ipython()
    return shell is not None and hasattr(shell, "kernel")


def _vec(v):
    return [float(x) for x in v]


def _sub(a, b):
    return [x - y for x, y in zip(a, b)]


def _add(a, b):
    return [x + y for x, y in zip(a, b)]


def _scale(a, s):
    return [x * s for x in a]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _norm(a):
    n = math.sqrt(_dot(a, a))
    return _scale(a, 1.0 / n) if n > 0 else a


def _rotate(v, axis, deg):
    """``v`` rotated by ``deg`` degrees about the unit ``axis`` (Rodrigues)."""
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    k = axis
    return _add(_add(_scale(v, c), _scale(_cross(k, v), s)), _scale(k, _dot(k, v) * (1 - c)))


class CameraMoves:
    """Orbit, pan and zoom of an explicit camera (``eye``, ``target``, ``up``), in screen
    terms: pixels dragged, wheel units."""

    def __init__(self, camera, height):
        self.camera = dict(camera)
        self.height = height

    def orbit(self, dx, dy):
        c = self.camera
        eye, target, up = _vec(c["eye"]), _vec(c["target"]), _norm(_vec(c["up"]))
        offset = _sub(eye, target)
        offset = _rotate(offset, up, -dx * ORBIT_DEG_PER_PX)
        right = _norm(_cross(_sub(target, _add(target, offset)), up))
        offset2 = _rotate(offset, right, -dy * ORBIT_DEG_PER_PX)
        new_up = _norm(_rotate(up, right, -dy * ORBIT_DEG_PER_PX))
        c["eye"], c["up"] = _add(target, offset2), new_up

    def _pixel(self):
        c = self.camera
        dist = math.sqrt(_dot(_sub(c["eye"], c["target"]), _sub(c["eye"], c["target"])))
        if c.get("projection") == "orthographic":
            fov = 30.0
            dist = dist / max(c.get("zoom", 1.0), 1e-9)
        else:
            fov = c.get("fov_y_deg", 30.0)
        return 2.0 * dist * math.tan(math.radians(fov) / 2.0) / max(self.height, 1)

    def pan(self, dx, dy):
        c = self.camera
        eye, target, up = _vec(c["eye"]), _vec(c["target"]), _norm(_vec(c["up"]))
        forward = _norm(_sub(target, eye))
        right = _norm(_cross(forward, up))
        screen_up = _cross(right, forward)
        move = _add(_scale(right, -dx * self._pixel()), _scale(screen_up, dy * self._pixel()))
        c["eye"], c["target"] = _add(eye, move), _add(target, move)

    def zoom(self, delta):
        c = self.camera
        factor = WHEEL_FACTOR ** (delta / 100.0)
        if c.get("projection") == "orthographic":
            c["zoom"] = c.get("zoom", 1.0) / factor
        else:
            eye, target = _vec(c["eye"]), _vec(c["target"])
            c["eye"] = _add(target, _scale(_sub(eye, target), factor))


def _widget_class():
    import anywidget
    import traitlets

    class VolumeWidget(anywidget.AnyWidget):
        """The interactive view; ``scene``, ``tf``, ``camera`` are its scene, and
        ``image`` its last full frame."""

        _esm = os.path.join(os.path.dirname(__file__), "static", "widget.js")
        png = traitlets.Bytes(b"").tag(sync=True)
        width = traitlets.Int(512).tag(sync=True)
        height = traitlets.Int(512).tag(sync=True)
        status = traitlets.Unicode("").tag(sync=True)

        def __init__(self, volume, scene, backend="auto", preview_divisor=2):
            super().__init__()
            self._renderer = Renderer(volume, backend=backend)
            self._scene = scene
            self._divisor = max(1, int(preview_divisor))
            self.image = None
            self.previews = 0
            w, h = scene.size if not isinstance(scene.size, int) else (scene.size, scene.size)
            self.width, self.height = int(w), int(h)
            self.on_msg(self._handle_msg)
            self.redraw()

        # The scene as attributes.
        @property
        def scene(self):
            """The scene drawn (a copy: assign it, or use ``update``, to redraw)."""
            return self._scene.replace()

        @scene.setter
        def scene(self, scene):
            self._scene = scene
            self.redraw()

        @property
        def tf(self):
            """The transfer function (any form ``tf=`` takes)."""
            return self._scene.tf

        @tf.setter
        def tf(self, tf):
            self.update(tf=tf)

        @property
        def camera(self):
            """The camera now, as a dict (``eye``, ``target``, ``up``, projection)."""
            return json.loads(self.image.camera) if self.image is not None else None

        @camera.setter
        def camera(self, camera):
            self.update(camera=camera)

        def update(self, **kwargs):
            """Changes the scene's ``kwargs`` and redraws. A new view (``view``,
            ``azimuth``, ``elevation``, ``up``, ``zoom``, ``orthographic``, ``frame``) without
            a ``camera`` frames the volume afresh, leaving the camera the mouse moved."""
            if "camera" not in kwargs and set(kwargs) & VIEW_KEYWORDS:
                kwargs["camera"] = None
            self._scene = self._scene.replace(**kwargs)
            self.redraw()

        def redraw(self):
            """Draws the full frame."""
            self._draw(self._scene, preview=False)

        def _draw(self, scene, preview):
            try:
                if preview:
                    w, h = self.width, self.height
                    d = self._divisor
                    kwargs = {"size": (max(16, w // d), max(16, h // d))}
                    if scene.integrator == "adaptive-simpson":
                        kwargs.update(integrator="riemann", step=1.0)
                    img = self._renderer.render(scene.replace(**kwargs), progress=False)
                    self.previews += 1
                else:
                    img = self._renderer.render(scene, progress=False)
                    self.image = img
                    if scene.camera is None:
                        # Later moves start from the camera drawn.
                        self._scene = scene.replace(camera=json.loads(img.camera))
            except Exception as e:  # the widget says the error and stays usable
                self.status = f"{type(e).__name__}: {e}"
                return
            self.png = img.to_png()
            s = img.stats
            what = "preview" if preview else "frame"
            self.status = f"{what} {img.width}x{img.height}, {s['ms']:.0f} ms, {s['method']} on {s['device']}"

        def _handle_msg(self, _widget, content, _buffers=None):
            """A drag or wheel message from the front end: the camera moved, a preview
            drawn while it moves, the full frame when it stops."""
            kind = content.get("type")
            if kind not in ("drag", "wheel"):
                return
            if self.image is None:
                self.redraw()
                if self.image is None:
                    return
            moves = CameraMoves(json.loads(self.image.camera) if self._scene.camera is None else
                                json.loads(_camera_text(self._scene.camera)), self.height)
            if kind == "drag":
                dx, dy = float(content.get("dx", 0)), float(content.get("dy", 0))
                if content.get("mode") == "pan":
                    moves.pan(dx, dy)
                else:
                    moves.orbit(dx, dy)
            else:
                moves.zoom(float(content.get("delta", 0)))
            self._scene = self._scene.replace(camera=moves.camera, view=None, azimuth=None, elevation=None)
            if content.get("phase") == "end":
                self.redraw()
            else:
                self._draw(self._scene, preview=True)

    return VolumeWidget


def _camera_text(camera):
    return camera if isinstance(camera, str) else json.dumps(camera)


_CLASS = None


def VolumeWidget(volume, scene, backend="auto", preview_divisor=2):  # noqa: N802 (a class)
    """The widget class (built on first use: anywidget is imported only then)."""
    global _CLASS
    if _CLASS is None:
        _CLASS = _widget_class()
    return _CLASS(volume, scene, backend=backend, preview_divisor=preview_divisor)


def show(volume, scene=None, *, backend="auto", **kwargs):
    """Shows ``volume``: in Jupyter, an interactive widget (drag to orbit, right-drag or
    shift-drag to pan, the wheel to zoom; ``widget.tf``, ``widget.camera``,
    ``widget.update(**scene)``, ``widget.image``); elsewhere, ``volux-view`` on it when it
    is installed. Keywords: those of :func:`volux.render`."""
    from .scene import scene_of

    scene = scene_of(scene, kwargs)
    if in_notebook():
        try:
            return VolumeWidget(volume, scene, backend=backend)
        except ImportError as e:
            raise ImportError(
                "volux.show() in Jupyter needs anywidget: pip install 'volux[jupyter]'"
            ) from e
    viewer = shutil.which("volux-view")
    if viewer is None:
        raise RuntimeError(
            "volux.show() outside Jupyter opens volux-view, which is not installed "
            "(cargo install --path crates/volux-viewer); volux.render(...).save('x.png') "
            "writes a picture"
        )
    path = volume.path
    if path is None:
        suffix = ".vtet" if volume.kind == "mesh" else ".nrrd"
        fd, path = tempfile.mkstemp(prefix="volux-", suffix=suffix)
        os.close(fd)
        volume.save(path)
    return subprocess.Popen([viewer, os.fspath(path), "--backend", backend])


__all__ += ["CameraMoves"]
