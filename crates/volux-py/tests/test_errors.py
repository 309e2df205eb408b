"""Errors are Python exceptions with the library's fields, phrased in Python's words (a
setting as its keyword argument, a remedy as the argument that applies it)."""

import numpy as np
import pytest

import volux

from conftest import ball


def test_a_missing_file_is_a_reader_error_and_an_oserror(tmp_path):
    missing = tmp_path / "missing.nrrd"
    with pytest.raises(volux.ReaderError) as e:
        volux.open(missing)
    assert isinstance(e.value, OSError)
    assert str(e.value.path) == str(missing)
    assert "missing.nrrd" in str(e.value)


def test_a_setting_out_of_range_names_the_keyword():
    vol = volux.Volume(ball(16))
    with pytest.raises(volux.SettingError) as e:
        volux.render(vol, step=-1)
    assert isinstance(e.value, ValueError)
    assert e.value.setting == "step"
    assert str(e.value).startswith("step= -1 must be")
    with pytest.raises(volux.SettingError, match="opacity_scale="):
        volux.render(vol, opacity_scale=-2)


def test_a_refusal_says_the_argument_that_applies_the_way_out():
    vol = volux.Volume(ball(16))
    with pytest.raises(volux.Refused) as e:
        volux.render(vol, method="pt")
    assert "as_tets=True" in e.value.remedy
    assert "--" not in str(e.value)  # no command-line flag in Python's messages


def test_words_and_reader_options_are_option_errors(tmp_path):
    vol = volux.Volume(ball(16))
    with pytest.raises(volux.OptionError) as e:
        volux.render(vol, view="sideways")
    assert e.value.option == "view" and "anterior" in str(e.value)
    with pytest.raises(volux.OptionError, match="integrator='psi' applies to tetrahedral meshes"):
        volux.render(vol, integrator="psi")
    src = tmp_path / "b.nrrd"
    vol.save(str(src))
    with pytest.raises(volux.OptionError) as e:
        volux.open(src, series="1.2.3")
    assert e.value.option == "series" and "DICOM" in str(e.value)
    with pytest.raises(volux.OptionError, match="lod=auto applies to OME-Zarr stores"):
        volux.open(src, lod="auto")
    with pytest.raises(volux.OptionError):
        volux.Scene(size=(0, 10)).spec()
    with pytest.raises(TypeError, match="unknown arguments"):
        volux.render(vol, colour="psi")


def test_bad_arrays_are_refused_clearly():
    with pytest.raises(ValueError, match="3-D array"):
        volux.Volume(np.zeros((4, 4)))
    with pytest.raises(TypeError, match="holds numbers"):
        volux.Volume(np.zeros((2, 2, 2), dtype=complex))
    with pytest.raises(volux.OptionError, match="spacing"):
        volux.Volume(ball(8), spacing=(1, 1))
    with pytest.raises(volux.VoluxError, match="spacing"):
        volux.Volume(ball(8), spacing=(1, 0, 1))
    with pytest.raises(ValueError, match="names point"):
        volux.Mesh(np.zeros((4, 3)), [[0, 1, 2, 9]], np.zeros(4))
    with pytest.raises(volux.OptionError, match="shape"):
        volux.render(volux.Volume(ball(8)), mask=np.ones((4, 4, 4)))


def test_a_png_only_and_the_image_writes_whole(tmp_path):
    img = volux.render(volux.Volume(ball(8)), size=(16, 16))
    with pytest.raises(volux.OptionError, match=".png"):
        img.save(str(tmp_path / "x.jpg"))
    assert not (tmp_path / "x.jpg").exists()
