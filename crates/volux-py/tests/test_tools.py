"""The seed's tools, as the command line applies them: the same pixels, the same points
and lengths, the same labels and masks."""

import json

import numpy as np

import volux

from conftest import ball


def test_measure_equals_volux_measure(tmp_path, cli):
    a = ball(32)
    src = tmp_path / "b.nrrd"
    volux.Volume(a, spacing=(0.5, 0.5, 0.8)).save(str(src))
    out = cli("measure", src, "--point", "20,30", "--point", "44,34", "--size", "64x64", "--tf", "ct-bone", "--json").stdout
    expected = json.loads(out)
    got = volux.measure(volux.open(src), [(20, 30), (44, 34)], size=(64, 64), tf="ct-bone")
    assert got["unit"] == expected["unit"] == "mm"
    assert got["length"] == expected["length"]
    np.testing.assert_array_equal(got["points"], expected["points"])


def test_regions_and_sculpt_give_arrays_render_takes(tmp_path, cli):
    a = ball(32)
    vol = volux.Volume(a)
    labels = volux.regions(vol, [(30, 30, 3)], size=(64, 64), tf="ct-bone")
    assert labels.shape == a.shape and labels.dtype == np.uint8
    assert set(np.unique(labels)) <= {0, 3} and (labels == 3).sum() > 0
    # The same as `volux regions`.
    src = tmp_path / "b.nrrd"
    vol.save(str(src))
    cli("regions", src, "--seed", "30,30,3", "--size", "64x64", "--tf", "ct-bone", "-o", tmp_path / "l.nrrd")
    from_cli = volux.open(tmp_path / "l.nrrd").to_numpy()
    assert np.array_equal(from_cli, labels)
    img = volux.render(vol, labels=labels, size=(64, 64), tf="ct-bone")
    assert img.stats["coverage"] > 0
    mask, removed = volux.sculpt(vol, [("erase", [(32, 32)], 6), ("dig", (24, 30), 4)], size=(64, 64), tf="ct-bone")
    assert mask.shape == a.shape and removed[0] > 0
    assert (mask == 0).sum() == sum(removed)
    cli("sculpt", src, "--erase", "32,32,6", "--dig", "24,30,4", "--size", "64x64", "--tf", "ct-bone", "-o", tmp_path / "m.nrrd")
    assert np.array_equal(volux.open(tmp_path / "m.nrrd").to_numpy(), mask)
    cut = volux.render(vol, mask=mask, size=(64, 64), tf="ct-bone")
    assert cut.to_png() != volux.render(vol, size=(64, 64), tf="ct-bone").to_png()
