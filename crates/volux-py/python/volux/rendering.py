"""Rendering: :func:`render` for one frame, :class:`Renderer` for many (its caches stay
warm), progress bars, and :func:`accuracy`."""

from . import _volux
from .scene import scene_of

__all__ = ["render", "Renderer", "accuracy"]


def _progress(progress):
    """A ``(done, total)`` callback and what closes it: tqdm's bar (shown after a second)
    for ``progress=True`` when tqdm is installed, the user's callable, or none."""
    if progress is False or progress is None:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, lambda: None
    bar = tqdm(total=None, unit="rows", delay=1.0, desc="volux", leave=False)

    def update(done, total):
        if total and bar.total != total:
            bar.total = total
        if done > bar.n:
            bar.update(done - bar.n)

    return update, bar.close


class Renderer:
    """Renders one volume frame after frame with its caches kept warm (data structures,
    classification, view), so a loop over cameras or transfer functions runs at the speed
    of ``volux render --orbit``.

    >>> r = volux.Renderer(vol, backend="auto")
    >>> frames = [r.render(tf="ct-bone", azimuth=a) for a in range(0, 360, 10)]

    ``backend``: ``"auto"`` (the GPU when this build has it, it draws the scene and it is
    not a software rasterizer; else the CPU engine), ``"cpu"`` or ``"gpu"``.
    """

    def __init__(self, volume, backend="auto"):
        self._renderer = _volux.Renderer(volume, backend)

    @property
    def volume(self):
        """The volume rendered."""
        return self._renderer.volume

    @property
    def backend(self):
        """The backend asked for."""
        return self._renderer.backend

    def render(self, scene=None, *, progress=True, **kwargs):
        """Renders ``scene`` (a :class:`volux.Scene` or dict) with ``kwargs`` changed, and
        returns an :class:`volux.Image`. Keywords: see :func:`volux.render`."""
        spec = scene_of(scene, kwargs).spec()
        callback, close = _progress(progress)
        try:
            return self._renderer.render(spec, callback)
        finally:
            close()


def render(volume, scene=None, *, backend="auto", progress=True, **kwargs):
    """Renders ``volume`` and returns an :class:`volux.Image` (``.save(path)``,
    ``.to_numpy()``, shown by notebooks). The same scene gives the same picture as
    ``volux render``, byte for byte.

    Transfer function and view:
      tf: a preset (``"auto"``, ``"ct-bone"``, ``"ct-skin"``, ... see ``volux.PRESETS``), a
        file (Volux JSON, ParaView preset, Slicer ``.vp``), a dict, a
        ``volux.TransferFunction``, a matplotlib colormap, or layers ``[(tf, weight), ...]``.
      view: ``"left"``, ``"right"``, ``"anterior"``, ``"posterior"``, ``"superior"``,
        ``"inferior"`` (the patient's sides, as in 3D Slicer) or ``"+x"`` ... ``"-z"``.
      azimuth, elevation: degrees added to the view's; up: (x, y, z); zoom: 1 frames the
        volume; orthographic; camera: a camera dict or JSON (``image.camera`` gives one back).
      size: (width, height); frame: ``"all"`` or ``"visible"`` (what the cuts leave).
    Method:
      method: ``"auto"`` (PT for meshes, ray casting for grids), ``"raycast"``, ``"pt"``,
        ``"slicing"``, ``"resample"``.
      integrator: ``"riemann"``, ``"trapezoid"``, ``"simpson"``, ``"adaptive-simpson"``
        (error-controlled: ``tol``, ``h0``, ``hmin``, ``hmax``), ``"preintegrated"``,
        ``"reference"``; for meshes ``"exact"``, ``"psi"``. step: in voxels.
      reconstruction: ``"trilinear"``, ``"catmull-rom"``, ``"b-spline"``; jitter.
      color (PT): ``"psi"``, ``"exact"``, ``"average"``; sort: ``"centroid"``, ``"exact"``.
    Appearance:
      shade (gradient lighting: ambient, diffuse, specular, shininess, light);
      iso: isovalues (a value, ``(value, (r, g, b, a))`` or ``"V:R,G,B,A"``, or a list);
      mip; opacity_scale; tf_colour (RGB volumes coloured by the TF).
    Cuts:
      clip_planes: ``[(a, b, c, d), ...]`` keeping ``a x + b y + c z + d >= 0``;
      mask: an array shaped like the volume (non-zero kept); labels: integers 0 to 255.
    Running:
      backend: ``"auto"``, ``"cpu"``, ``"gpu"``; progress: True (a tqdm bar when tqdm is
      installed and the frame takes over a second), False, or a ``callback(done, total)``.
      Ctrl-C stops the frame and raises ``KeyboardInterrupt``.

    >>> img = volux.render(volux.open("head.nrrd"), tf="ct-bone", view="left", shade=True)
    >>> img.save("left.png")
    """
    return Renderer(volume, backend=backend).render(scene, progress=progress, **kwargs)


def accuracy(volume, scene=None, *, tol=0.01, backend="cpu", **kwargs):
    """Adaptive Simpson's estimated absolute error per pixel (largest channel), as a
    ``(height, width)`` float32 array, for ``volume`` rendered at tolerance ``tol`` (the
    error map of ``volux render --integrator adaptive-simpson --error-map``)."""
    kwargs = {**kwargs, "integrator": "adaptive-simpson", "tol": tol}
    img = render(volume, scene, backend=backend, **kwargs)
    return img.error_map
