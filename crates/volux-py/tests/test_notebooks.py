"""The example notebooks of docs/notebooks (one per user group) run to the end."""

import pathlib

import pytest

from conftest import REPO, shared

NOTEBOOKS = sorted((REPO / "docs" / "notebooks").glob("*.ipynb"))


def test_there_is_a_notebook_per_user_group():
    names = {p.stem for p in NOTEBOOKS}
    assert {"ct_dicom", "microscopy_omezarr", "cfd_tets"} <= names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path: pathlib.Path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    shared("")  # the notebooks read ../shared/data
    nb = nbformat.read(str(path), as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    images = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.outputs if "image/png" in o.get("data", {}))
    assert images >= 2, f"{path.name}: {images} pictures shown"
