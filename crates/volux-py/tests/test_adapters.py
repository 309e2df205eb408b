"""The adapters keep geometry and values: a file read by Volux and the same file read by
the reference library, then handed over, are the same volume (values, spacing, origin,
direction) and give the same picture."""

import numpy as np
import pytest

import volux

from conftest import ball, cube_tets

# An oblique, flipped affine (RAS): spacing (0.8, 1.1, 2.5), 20 degrees about z, x flipped.
ANGLE = np.radians(20.0)
ROT = np.array([[np.cos(ANGLE), -np.sin(ANGLE), 0], [np.sin(ANGLE), np.cos(ANGLE), 0], [0, 0, 1]])


def assert_same_volume(a, b):
    assert a.dims == b.dims
    np.testing.assert_allclose(a.spacing, b.spacing, rtol=1e-6)
    np.testing.assert_allclose(a.origin, b.origin, atol=1e-5)
    np.testing.assert_allclose(a.direction, b.direction, atol=1e-6)
    assert np.array_equal(a.to_numpy(), b.to_numpy())


def test_nibabel_image_and_file_are_the_same_volume(tmp_path):
    nib = pytest.importorskip("nibabel")
    data = np.asfortranarray(ball(24).transpose(2, 1, 0))  # nibabel's [i, j, k]
    affine = np.eye(4)
    affine[:3, :3] = ROT @ np.diag([-0.8, 1.1, 2.5])
    affine[:3, 3] = [12.0, -30.0, 7.5]
    img = nib.Nifti1Image(data, affine)
    path = tmp_path / "x.nii"
    nib.save(img, str(path))
    from_file = volux.open(path)
    handed = volux.Volume.from_nibabel(nib.load(str(path)))
    assert_same_volume(from_file, handed)
    # nibabel's data in Fortran order is read in place (a C-contiguous transposed view).
    assert handed.shares_memory
    # RAS -> LPS: the first voxel's world position.
    lps = np.diag([-1, -1, 1]) @ affine[:3, 3]
    np.testing.assert_allclose(handed.origin, lps)
    assert volux.render(from_file, size=(48, 48), view="anterior").to_png() == volux.render(handed, size=(48, 48), view="anterior").to_png()


def test_nibabel_scaling_is_applied():
    nib = pytest.importorskip("nibabel")
    data = (ball(16) // 10).astype(np.int16)
    img = nib.Nifti1Image(np.asfortranarray(data.transpose(2, 1, 0)), np.eye(4))
    img.header.set_slope_inter(2.0, -5.0)
    # Round trip through bytes so the proxy applies the scaling as on a file.
    img2 = nib.Nifti1Image.from_bytes(img.to_bytes())
    vol = volux.Volume.from_nibabel(img2)
    np.testing.assert_allclose(vol.to_numpy(), data * 2.0 - 5.0)


def test_sitk_image_and_file_are_the_same_volume(tmp_path):
    sitk = pytest.importorskip("SimpleITK")
    img = sitk.GetImageFromArray(ball(20))
    img.SetSpacing((0.7, 0.9, 1.6))
    img.SetOrigin((-40.0, 12.0, 3.0))
    img.SetDirection(tuple(ROT.T.ravel()))
    path = tmp_path / "x.mha"
    sitk.WriteImage(img, str(path))
    assert_same_volume(volux.open(path), volux.Volume.from_sitk(img))
    assert volux.Volume.from_sitk(img).spacing == pytest.approx((0.7, 0.9, 1.6))


def _meshio_mesh():
    meshio = pytest.importorskip("meshio")
    points, tets, scalars = cube_tets(3)
    return meshio.Mesh(points, [("tetra", tets)], point_data={"pressure": scalars})


def test_meshio_mesh_and_file_are_the_same_picture(tmp_path):
    meshio = pytest.importorskip("meshio")
    m = _meshio_mesh()
    path = tmp_path / "cube.vtu"
    meshio.write(str(path), m, binary=False)
    a = volux.render(volux.open(path), size=(48, 48), azimuth=25, elevation=20)
    b = volux.render(volux.Mesh.from_meshio(m), size=(48, 48), azimuth=25, elevation=20)
    assert a.to_png() == b.to_png()
    with pytest.raises(ValueError, match="hexahedron"):
        volux.Mesh.from_meshio(meshio.Mesh(m.points, [("tetra", m.cells[0].data), ("hexahedron", np.zeros((1, 8), int))], point_data=m.point_data))


def test_pyvista_grid_is_the_meshio_mesh():
    pv = pytest.importorskip("pyvista")
    points, tets, scalars = cube_tets(3)
    cells = np.hstack([np.full((len(tets), 1), 4), tets]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(tets), pv.CellType.TETRA), points)
    grid.point_data["pressure"] = scalars
    a = volux.render(volux.Mesh.from_pyvista(grid), size=(48, 48), azimuth=25, elevation=20)
    b = volux.render(volux.Mesh.from_meshio(_meshio_mesh()), size=(48, 48), azimuth=25, elevation=20)
    assert a.to_png() == b.to_png()
    # Other cells are split into tetrahedra, said in a warning.
    image = pv.ImageData(dimensions=(4, 4, 4))
    image.point_data["v"] = np.arange(64, dtype=np.float32)
    with pytest.warns(UserWarning, match="split into tetrahedra"):
        split = volux.Mesh.from_pyvista(image)
    assert split.kind == "mesh" and split.cells > 0


def test_zarr_array_and_ome_zarr_store(tmp_path, cli):
    zarr = pytest.importorskip("zarr")
    data = ball(24)
    arr = zarr.create_array(store=str(tmp_path / "plain.zarr"), shape=(1, 1) + data.shape, dtype=data.dtype, chunks=(1, 1, 8, 8, 8)) if hasattr(zarr, "create_array") else zarr.open(str(tmp_path / "plain.zarr"), mode="w", shape=(1, 1) + data.shape, dtype=data.dtype, chunks=(1, 1, 8, 8, 8))
    arr[...] = data[None, None]
    vol = volux.Volume.from_zarr(arr)
    assert np.array_equal(vol.to_numpy(), data)
    # An OME-Zarr store written by `volux convert`, opened out of core.
    src = tmp_path / "ball.nrrd"
    volux.Volume(data, spacing=(0.5, 0.5, 1.0)).save(str(src))
    store = tmp_path / "ball.ome.zarr"
    cli("convert", src, store, "--chunk", "8", "--levels", "2")
    out_of_core = volux.open(store, lod="auto")
    assert out_of_core.kind == "bricked" and out_of_core.levels == 2
    cli("render", store, "-o", tmp_path / "cli.png", "--lod", "auto", "--size", "48x48")
    assert volux.render(out_of_core, size=(48, 48)).to_png() == (tmp_path / "cli.png").read_bytes()
    assert volux.Volume.from_zarr(str(store)).kind in ("grid", "bricked")
