"""The Jupyter widget's messages: a drag message in, a preview out while it moves, the
full frame when it stops; the scene as attributes."""

import json

import pytest

import volux
from volux.widget import VolumeWidget, CameraMoves

from conftest import ball

pytest.importorskip("anywidget")


def test_a_drag_message_in_a_new_frame_out():
    w = VolumeWidget(volux.Volume(ball(24)), volux.Scene(size=(64, 48), tf="ct-bone"))
    first = w.png
    assert first[:8] == b"\x89PNG\r\n\x1a\n"
    assert w.image.width == 64
    cam0 = w.camera
    w._handle_msg(w, {"type": "drag", "mode": "orbit", "dx": 40, "dy": 0, "phase": "move"})
    assert w.previews == 1
    assert w.png != first and "preview 32x24" in w.status
    w._handle_msg(w, {"type": "drag", "mode": "orbit", "dx": 0, "dy": 0, "phase": "end"})
    assert w.image.width == 64 and w.png != first
    assert w.camera["eye"] != cam0["eye"]
    # The distance to the target is kept by an orbit.
    d = lambda c: sum((a - b) ** 2 for a, b in zip(c["eye"], c["target"])) ** 0.5  # noqa: E731
    assert d(w.camera) == pytest.approx(d(cam0), rel=1e-9)
    before = w.camera
    w._handle_msg(w, {"type": "wheel", "delta": -200, "phase": "end"})
    assert d(w.camera) < d(before)
    w._handle_msg(w, {"type": "drag", "mode": "pan", "dx": 10, "dy": 0, "phase": "end"})
    assert w.camera["target"] != before["target"]


def test_the_scene_is_attributes():
    w = VolumeWidget(volux.Volume(ball(24)), volux.Scene(size=(48, 48), tf="ct-bone"))
    png = w.png
    w.tf = "ct-skin"
    assert w.tf == "ct-skin" and w.png != png
    cam = dict(w.camera)
    w.camera = cam
    assert json.loads(w.image.camera)["eye"] == pytest.approx(cam["eye"])
    # A wrong value is said in the status line; the widget stays usable.
    w.update(step=-1)
    assert "SettingError" in w.status
    w.update(step=0.5)
    assert w.status.startswith("frame")
    # A named view frames the volume afresh, whatever the mouse did.
    w._handle_msg(w, {"type": "drag", "mode": "orbit", "dx": 25, "dy": 5, "phase": "end"})
    w.update(view="left")
    fresh = VolumeWidget(volux.Volume(ball(24)), volux.Scene(size=(48, 48), tf="ct-skin", view="left"))
    assert w.png == fresh.png


def test_camera_moves_are_rotations():
    m = CameraMoves({"eye": [0, -10, 0], "target": [0, 0, 0], "up": [0, 0, 1], "projection": "perspective", "fov_y_deg": 30}, 100)
    m.orbit(180, 0)  # 90 degrees about up
    assert m.camera["eye"] == pytest.approx([10, 0, 0], abs=1e-9) or m.camera["eye"] == pytest.approx([-10, 0, 0], abs=1e-9)
