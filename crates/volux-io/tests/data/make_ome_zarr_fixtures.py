"""Writes the OME-Zarr test fixtures (tiny_v04, tiny_v05, and tczyx_v05 described at the end) with ome-zarr-py (run once; the stores are committed).

    pip install zarr ome-zarr numpy   # made with zarr 3.1.6, ome-zarr 0.18.0
    python make_ome_zarr_fixtures.py

Both stores hold a 9 x 7 x 5 (x, y, z) u16 image, axes (z, y, x) in micrometres, chunks
(2, 3, 4) (z, y, x), two levels:
  level 0: value(x, y, z) = x + 10 y + 100 z, scale (z, y, x) = (2.5, 0.5, 0.25),
           translation (z, y, x) = (10, 20, 30)
  level 1: level 0 subsampled by 2 (value(x, y, z) = 2x + 20y + 200z, 5 x 4 x 3),
           scale doubled, same translation.
tiny_v04.ome.zarr: NGFF 0.4 on Zarr v2 (blosc lz4); tiny_v05.ome.zarr: NGFF 0.5 on Zarr v3 (zstd).
"""
import shutil

import numpy as np
import numcodecs
import zarr
from ome_zarr.format import FormatV04, FormatV05
from ome_zarr.writer import write_multiscale

z, y, x = np.meshgrid(np.arange(5), np.arange(7), np.arange(9), indexing="ij")
level0 = (x + 10 * y + 100 * z).astype(np.uint16)
level1 = level0[::2, ::2, ::2].copy()
axes = [
    {"name": "z", "type": "space", "unit": "micrometer"},
    {"name": "y", "type": "space", "unit": "micrometer"},
    {"name": "x", "type": "space", "unit": "micrometer"},
]
transforms = [
    [{"type": "scale", "scale": [2.5, 0.5, 0.25]}, {"type": "translation", "translation": [10.0, 20.0, 30.0]}],
    [{"type": "scale", "scale": [5.0, 1.0, 0.5]}, {"type": "translation", "translation": [10.0, 20.0, 30.0]}],
]
stores = [
    ("tiny_v04.ome.zarr", FormatV04(), 2, {"compressor": numcodecs.Blosc(cname="lz4", shuffle=1)}),
    ("tiny_v05.ome.zarr", FormatV05(), 3, {}),
]
for name, fmt, zarr_format, compression in stores:
    shutil.rmtree(name, ignore_errors=True)
    group = zarr.open_group(name, mode="w", zarr_format=zarr_format)
    write_multiscale(
        [level0, level1],
        group,
        fmt=fmt,
        axes=axes,
        coordinate_transformations=transforms,
        storage_options={"chunks": (2, 3, 4), **compression},
        name="tiny",
    )
    print(name, dict(group.attrs))

# tczyx_v05.ome.zarr: a 5-D (t, c, z, y, x) = (2, 2, 3, 4, 5) int32 image, one level, NGFF 0.5,
# value = x + 5 y + 20 z + 60 c + 120 t, scale (t, c, z, y, x) = (1, 1, 3, 2, 1) micrometres.
t, c, z, y, x = np.meshgrid(*[np.arange(n) for n in (2, 2, 3, 4, 5)], indexing="ij")
tczyx = (x + 5 * y + 20 * z + 60 * c + 120 * t).astype(np.int32)
shutil.rmtree("tczyx_v05.ome.zarr", ignore_errors=True)
group = zarr.open_group("tczyx_v05.ome.zarr", mode="w", zarr_format=3)
write_multiscale(
    [tczyx],
    group,
    fmt=FormatV05(),
    axes=[{"name": "t", "type": "time"}, {"name": "c", "type": "channel"}] + axes,
    coordinate_transformations=[[{"type": "scale", "scale": [1.0, 1.0, 3.0, 2.0, 1.0]}]],
    storage_options={"chunks": (1, 1, 2, 3, 4)},
    name="tczyx",
)
print("tczyx_v05.ome.zarr", dict(group.attrs))
