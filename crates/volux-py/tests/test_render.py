"""Pictures: the same scene gives the same PNG bytes as `volux render`; a numpy array is
read in place; warm renderers; transfer functions in every form Python has."""

import json
import warnings

import numpy as np
import pytest

import volux

from conftest import ball


def test_open_and_render_equal_the_command_line_byte_for_byte(tmp_path, cli, ball_array):
    src = tmp_path / "ball.nrrd"
    volux.Volume(ball_array, spacing=(0.8, 0.9, 1.5), origin=(-10, 5, 2)).save(str(src))
    args = ["--tf", "ct-bone", "--size", "96x64", "--view", "left", "--shade"]
    cli("render", src, "-o", tmp_path / "cli.png", *args)
    img = volux.render(volux.open(src), tf="ct-bone", size=(96, 64), view="left", shade=True)
    img.save(str(tmp_path / "py.png"))
    assert (tmp_path / "cli.png").read_bytes() == (tmp_path / "py.png").read_bytes()
    # The array itself, with the same geometry: the same picture.
    vol = volux.Volume(ball_array, spacing=(0.8, 0.9, 1.5), origin=(-10, 5, 2))
    again = volux.render(vol, tf="ct-bone", size=(96, 64), view="left", shade=True)
    assert again.to_png() == img.to_png()
    assert img.to_png() == (tmp_path / "cli.png").read_bytes()


@pytest.mark.parametrize(
    "args,kwargs",
    [
        (["--integrator", "adaptive-simpson", "--tol", "0.02"], dict(integrator="adaptive-simpson", tol=0.02)),
        (["--reconstruction", "catmull-rom", "--frame", "all"], dict(reconstruction="catmull-rom", frame="all")),
        (["--mip", "--tf", "viridis"], dict(mip=True, tf="viridis")),
        (["--iso", "500:1,0.8,0.6,1", "--tf", "ct-skin"], dict(iso="500:1,0.8,0.6,1", tf="ct-skin")),
        (["--clip-plane", "1,0,0,-14", "--frame", "visible", "--azimuth", "30"], dict(clip_planes=[(1, 0, 0, -14)], frame="visible", azimuth=30)),
        (["--tf", "ct-skin:0.3", "--tf", "ct-bone", "--orthographic", "--zoom", "1.4"], dict(tf=[("ct-skin", 0.3), "ct-bone"], orthographic=True, zoom=1.4)),
    ],
)
def test_scene_options_match_the_command_line(tmp_path, cli, ball_array, args, kwargs):
    src = tmp_path / "ball.nrrd"
    volux.Volume(ball_array).save(str(src))
    cli("render", src, "-o", tmp_path / "cli.png", "--size", "64x64", *args)
    img = volux.render(volux.open(src), size=(64, 64), **kwargs)
    assert img.to_png() == (tmp_path / "cli.png").read_bytes()


def test_mesh_renders_as_the_command_line(tmp_path, cli):
    from conftest import cube_tets

    points, tets, scalars = cube_tets(3)
    mesh = volux.Mesh(points, tets, scalars)
    assert mesh.kind == "mesh" and mesh.cells == len(tets)
    path = tmp_path / "cube.vtet"
    mesh.save(str(path))
    cli("render", path, "-o", tmp_path / "cli.png", "--size", "64x64", "--azimuth", "20", "--elevation", "25")
    img = volux.render(mesh, size=(64, 64), azimuth=20, elevation=25)
    assert img.to_png() == (tmp_path / "cli.png").read_bytes()
    assert img.stats["method"] == "pt"


def test_zero_copy_the_render_sees_an_in_place_change(ball_array):
    a = ball_array.copy()
    vol = volux.Volume(a)
    assert vol.shares_memory
    assert np.shares_memory(vol.to_numpy(), a)
    assert vol.to_numpy() is a
    r = volux.Renderer(vol)
    first = r.render(tf="ct-bone", size=(48, 48))
    a[:, :, :16] = 0  # cut the ball in place
    vol.modified()
    second = r.render(tf="ct-bone", size=(48, 48))
    assert first.to_png() != second.to_png()
    fresh = volux.render(volux.Volume(a.copy()), tf="ct-bone", size=(48, 48))
    assert second.to_png() == fresh.to_png()


@pytest.mark.parametrize(
    "dtype,offset,held",
    [
        (np.float64, 0, "float32"),
        (np.int32, -500, "int16"),
        (np.uint32, 40000, "uint16"),
        (np.int64, 0, "uint8"),
        (np.bool_, 0, "uint8"),
        (np.int8, -3, "int16"),
        (np.int64, 1 << 20, "float32"),
    ],
)
def test_other_dtypes_are_converted_exactly_where_they_can_be_with_a_warning(dtype, offset, held):
    base = ball(16).astype(np.int64) // (200 if held == "uint8" else 1)
    a = (base + offset).astype(dtype) if dtype is not np.bool_ else base > 500
    with pytest.warns(UserWarning, match="converted"):
        vol = volux.Volume(a)
    assert vol.dtype == held
    # Read in place is the converted copy, not the caller's array.
    assert not np.shares_memory(vol.to_numpy(), a)
    assert np.array_equal(vol.to_numpy(), a.astype(held))


def test_non_contiguous_and_byte_swapped_arrays_are_copied_with_a_warning():
    a = ball(16)
    with pytest.warns(UserWarning, match="not C-contiguous"):
        v = volux.Volume(a[:, :, ::-1])
    assert np.array_equal(v.to_numpy(), a[:, :, ::-1])
    with pytest.warns(UserWarning, match="byte order"):
        v = volux.Volume(a.astype(">i2"))
    assert np.array_equal(v.to_numpy(), a)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        volux.Volume(a)  # read in place: no warning


def test_image_arrays_and_stats(ball_array):
    img = volux.render(volux.Volume(ball_array), tf="ct-bone", size=(40, 30))
    u8 = img.to_numpy()
    assert u8.shape == (30, 40, 4) and u8.dtype == np.uint8
    f = img.to_numpy("float32")
    assert f.shape == (30, 40, 4) and f.dtype == np.float32
    # Premultiplied: colour never exceeds alpha.
    assert np.all(f[..., :3] <= f[..., 3:] + 1e-6)
    assert img._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
    s = img.stats
    assert s["method"] == "raycast" and s["device"] == "CPU" and s["ms"] > 0
    cam = json.loads(img.camera)
    assert set(cam) >= {"eye", "target", "up", "projection"}
    # The camera given back draws the same picture.
    same = volux.render(volux.Volume(ball_array), tf="ct-bone", size=(40, 30), camera=cam)
    assert same.to_png() == img.to_png()


def test_a_warm_renderer_rebuilds_only_the_view(ball_array):
    r = volux.Renderer(volux.Volume(ball_array))
    first = r.render(tf="ct-bone", size=(48, 48))
    assert first.stats["rebuilt_data"]
    second = r.render(tf="ct-bone", size=(48, 48), azimuth=40)
    assert not second.stats["rebuilt_data"] and not second.stats["rebuilt_classification"]
    assert second.stats["rebuilt_view"]
    scene = volux.Scene(tf="ct-bone", size=(48, 48))
    scene.azimuth = 40
    assert r.render(scene).to_png() == second.to_png()


def test_transfer_functions_from_dicts_files_and_colormaps(tmp_path, ball_array):
    vol = volux.Volume(ball_array)
    d = {"space": "normalized", "color": [[0, 0, 0, 0], [1, 1, 0.9, 0.8]], "opacity": [[0.3, 0], [1, 0.7]]}
    a = volux.render(vol, tf=d, size=(32, 32))
    f = tmp_path / "tf.json"
    f.write_text(json.dumps(d))
    b = volux.render(vol, tf=str(f), size=(32, 32))
    assert a.to_png() == b.to_png()
    tf = volux.tf_from_dict(d)
    assert volux.TransferFunction.from_json(tf.to_json()) == tf
    matplotlib = pytest.importorskip("matplotlib")
    cm = volux.tf_from_colormap(matplotlib.colormaps["magma"], opacity=[(0.2, 0), (1, 0.6)])
    img = volux.render(vol, tf=cm, size=(32, 32))
    assert img.stats["coverage"] > 0
    direct = volux.render(vol, tf=matplotlib.colormaps["magma"], size=(32, 32))
    assert direct.stats["coverage"] > 0
    with pytest.raises(volux.VoluxError, match="color"):
        volux.tf_from_dict({"colour": []})


def test_accuracy_is_the_error_map(ball_array):
    e = volux.accuracy(volux.Volume(ball_array.astype(np.float32)), tol=0.01, size=(32, 24), tf="ct-bone")
    assert e.shape == (24, 32) and e.dtype == np.float32
    assert np.all(e >= 0)


def test_help_is_enough_to_start():
    doc = volux.render.__doc__
    for word in ("tf:", "view:", "method:", "integrator:", "clip_planes:", "backend:", "Ctrl-C"):
        assert word in doc, word
    assert "open" in volux.open.__doc__ and "memory_budget" in volux.open.__doc__
