#!/usr/bin/env python3
"""Volux's Python package beside pyvista (VTK's `add_volume`), the tool a Python user would
pick, in one run: the same grid, transfer function and camera orbit, 512x512, warm frames.

Data: Marschner-Lobb (f_M = 6, alpha = 0.25) on an N^3 vertex-centred grid over [-1, 1]^3,
as ../shared/bench/make_data.py writes it; transfer function ../shared/bench/tf-37-knots.json
(extinction per world unit); camera ../shared/bench/camera.json (distance 7, elevation 30
degrees, azimuth 30 + 3 per frame, 30 degree view angle).

Each renderer draws FRAMES warm frames of the orbit after WARM frames; the median time per
frame is reported. Accuracy: every picture is compared with Volux's reference integrator
(`integrator="reference"`, the exact integral of the trilinear field's piecewise-linear TF
along each ray) at the same camera, as PSNR of the linear RGB composited over black. VTK's
colours are given linear (Volux's TF colours) and VTK composites without a gamma, so its
framebuffer is read as linear; its opacity is the TF's extinction turned into opacity per
unit distance at the sample spacing (exact at the knots, piecewise-linear between them).

Usage (from the repository root, with `pip install ./crates/volux-py pyvista`):
  python3 docs/bench/python_vs_pyvista.py [--size 128] [--frames 5] [--json]
"""

import argparse
import json
import math
import pathlib
import statistics
import sys
import time

import numpy as np

import volux

BENCH = pathlib.Path(__file__).resolve().parents[3] / "shared" / "bench"


def marschner_lobb(n, fm=6.0, alpha=0.25):
    sp = 2.0 / (n - 1)
    ax = -1.0 + sp * np.arange(n)
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    r = np.sqrt(x * x + y * y)
    rho_r = np.cos(2.0 * np.pi * fm * np.cos(np.pi * r / 2.0))
    v = (1.0 - np.sin(np.pi * z / 2.0) + alpha * (1.0 + rho_r)) / (2.0 * (1.0 + alpha))
    return v.astype(np.float32), sp


def camera(frame):
    az = math.radians(30 + 3 * frame)
    el = math.radians(30)
    eye = [7 * math.cos(el) * math.cos(az), 7 * math.cos(el) * math.sin(az), 7 * math.sin(el)]
    return {"eye": eye, "target": [0, 0, 0], "up": [0, 0, 1], "projection": "perspective", "fov_y_deg": 30}


def linear_over_black(rgba_u8):
    """sRGB straight-alpha RGBA8 over black, as linear RGB floats."""
    c = rgba_u8[..., :3].astype(np.float64) / 255.0
    a = rgba_u8[..., 3:4].astype(np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return lin * a


def psnr(a, b):
    mse = float(np.mean((a - b) ** 2))
    return float("inf") if mse == 0 else 10 * math.log10(1.0 / mse)


def volux_frames(vol, tf, size, frames, warm, **kw):
    r = volux.Renderer(vol, backend="cpu")
    times, images = [], []
    for f in range(warm + frames):
        t = time.perf_counter()
        img = r.render(tf=tf, camera=camera(f), size=(size, size), progress=False, **kw)
        dt = time.perf_counter() - t
        if f >= warm:
            times.append(dt * 1e3)
            images.append(img)
    return times, images


def vtk_frames(data, sp, tf_json, size, frames, warm, mapper):
    import pyvista as pv
    import vtk

    n = data.shape[0]
    grid = pv.ImageData(dimensions=(n, n, n), spacing=(sp, sp, sp), origin=(-1, -1, -1))
    grid.point_data["v"] = data.ravel(order="C")
    pl = pv.Plotter(off_screen=True, window_size=(size, size))
    pl.set_background("black")
    actor = pl.add_volume(grid, scalars="v", mapper=mapper, show_scalar_bar=False)
    prop = actor.GetProperty()
    ctf = vtk.vtkColorTransferFunction()
    for s, r, g, b in tf_json["color"]:
        ctf.AddRGBPoint(s, r, g, b)
    otf = vtk.vtkPiecewiseFunction()
    unit = sp * 0.5
    for s, tau in tf_json["extinction"]:
        otf.AddPoint(s, 1.0 - math.exp(-tau * unit))
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    m = actor.GetMapper()
    if hasattr(m, "SetSampleDistance"):
        m.SetSampleDistance(unit)
    if hasattr(m, "SetAutoAdjustSampleDistances"):
        m.SetAutoAdjustSampleDistances(False)
    times, shots = [], []
    for f in range(warm + frames):
        c = camera(f)
        pl.camera.position, pl.camera.focal_point, pl.camera.up = c["eye"], c["target"], c["up"]
        pl.camera.view_angle = 30
        t = time.perf_counter()
        pl.render()
        dt = time.perf_counter() - t
        if f >= warm:
            times.append(dt * 1e3)
            shots.append(np.asarray(pl.screenshot(return_img=True))[..., :3].astype(np.float64) / 255.0)
    pl.close()
    return times, shots


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--size", type=int, default=128, help="grid samples per axis")
    p.add_argument("--image", type=int, default=512)
    p.add_argument("--frames", type=int, default=5)
    p.add_argument("--warm", type=int, default=2)
    p.add_argument("--mappers", default="fixed_point,smart", help="pyvista mappers to run")
    p.add_argument("--json", action="store_true")
    a = p.parse_args()

    tf_json = json.loads((BENCH / "tf-37-knots.json").read_text())
    data, sp = marschner_lobb(a.size)
    vol = volux.Volume(data, spacing=(sp, sp, sp), origin=(-1, -1, -1))
    tf = volux.tf_from_dict(tf_json)

    rows = []
    ref = [
        linear_over_black(volux.render(vol, tf=tf, camera=camera(a.warm + f), size=(a.image, a.image),
                                       integrator="reference", progress=False).to_numpy())
        for f in range(a.frames)
    ]
    times, images = volux_frames(vol, tf, a.image, a.frames, a.warm, integrator="riemann", step=0.5)
    acc = [psnr(linear_over_black(i.to_numpy()), r) for i, r in zip(images, ref)]
    rows.append({"renderer": "volux (Python), Riemann 0.5 voxel", "ms": statistics.median(times), "psnr_db": min(acc)})
    times, images = volux_frames(vol, tf, a.image, a.frames, a.warm, integrator="adaptive-simpson", tol=0.01)
    acc = [psnr(linear_over_black(i.to_numpy()), r) for i, r in zip(images, ref)]
    rows.append({"renderer": "volux (Python), adaptive Simpson 0.01", "ms": statistics.median(times), "psnr_db": min(acc)})
    for mapper in [m for m in a.mappers.split(",") if m]:
        try:
            times, shots = vtk_frames(data, sp, tf_json, a.image, a.frames, a.warm, mapper)
        except Exception as e:  # a mapper this VTK build lacks is said, not hidden
            rows.append({"renderer": f"pyvista add_volume({mapper!r})", "error": str(e)})
            continue
        acc = [psnr(s, r) for s, r in zip(shots, ref)]
        rows.append({"renderer": f"pyvista add_volume(mapper={mapper!r})", "ms": statistics.median(times), "psnr_db": min(acc)})

    if a.json:
        print(json.dumps({"size": a.size, "image": a.image, "frames": a.frames, "rows": rows}))
        return
    print(f"Marschner-Lobb {a.size}^3, {a.image}x{a.image}, median of {a.frames} warm frames")
    print(f"{'renderer':48} {'ms/frame':>9} {'PSNR dB':>8}")
    for r in rows:
        if "error" in r:
            print(f"{r['renderer']:48} {'-':>9} {'-':>8}  ({r['error']})")
        else:
            print(f"{r['renderer']:48} {r['ms']:9.1f} {r['psnr_db']:8.1f}")


if __name__ == "__main__":
    sys.exit(main())
