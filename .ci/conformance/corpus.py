"""The files of the conformance test: the reference libraries' own test data, as installed,
and files written by them (the habits of the tools that clinics and labs export with).

`corpus(work)` returns entries (path, kind, source, scope): `kind` names the reference reader
(see reference.py), `source` where the file comes from, `scope` "in" for formats Volux reads
or should read (issue 40), or the name of a format outside its list (PAR/REC, AFNI, ECAT,
MINC-1, surfaces and streamlines), which is listed but not counted.
"""
from __future__ import annotations

import gzip
import os
import shutil
from pathlib import Path

import numpy as np

DIMS = (7, 6, 5)  # x, y, z: odd and unequal, so a transposition or a flip shows


def _rotation():
    """An oblique rotation (about 20, -10 and 30 degrees), as scanners write for tilted slabs."""
    a, b, c = np.radians([20.0, -10.0, 30.0])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


ROTATION = _rotation()


def site(pkg: str) -> Path:
    mod = __import__(pkg)
    return Path(mod.__file__).parent


def _pattern(dtype, shape=DIMS, seed=1):
    """Values that use the dtype's range, in (x, y, z) order."""
    rng = np.random.default_rng(seed)
    dt = np.dtype(dtype)
    if dt.kind == "f":
        return (rng.standard_normal(shape) * 1000).astype(dt)
    info = np.iinfo(dt)
    lo, hi = max(info.min, -(2**40)), min(info.max, 2**40)
    v = rng.integers(lo, hi, size=shape, endpoint=True, dtype=np.int64 if dt.kind == "i" or dt.itemsize < 8 else np.uint64)
    return v.astype(dt)


# ------------------------------------------------------------------------------- shipped files


def shipped(work: Path):
    out = []
    pyd = site("pydicom") / "data" / "test_files"
    for p in sorted(pyd.glob("*.dcm")):
        out.append((str(p), "dicom", "pydicom", "in"))
    data_store = site("data_store") / "data"
    for p in sorted(data_store.glob("*.dcm")):
        out.append((str(p), "dicom", "pydicom-data", "in"))
    nib = site("nibabel")
    for p in sorted((nib / "nicom" / "tests" / "data").iterdir()):
        if p.name.endswith(".dcm"):
            out.append((str(p), "dicom", "nibabel", "in"))
        elif p.name.endswith(".dcm.gz"):
            dst = work / "nibabel-nicom" / p.name[:-3]
            dst.parent.mkdir(parents=True, exist_ok=True)
            with gzip.open(p) as src, open(dst, "wb") as f:
                shutil.copyfileobj(src, f)
            out.append((str(dst), "dicom", "nibabel", "in"))
    for p in sorted((nib / "tests" / "data").iterdir()):
        n = p.name.lower()
        if n.endswith(".dcm"):
            out.append((str(p), "dicom", "nibabel", "in"))
        elif n.endswith((".nii", ".nii.gz", ".mgz", ".mgh")) or (n.endswith(".hdr")):
            out.append((str(p), "nibabel", "nibabel", "in"))
        elif n.endswith(".mnc"):
            scope = "in" if _is_hdf5(p) else "MINC-1 (netCDF)"
            out.append((str(p), "nibabel", "nibabel", scope))
        elif n.endswith(".par"):
            out.append((str(p), "nibabel", "nibabel", "Philips PAR/REC"))
        elif n.endswith(".head"):
            out.append((str(p), "nibabel", "nibabel", "AFNI BRIK"))
        elif n.endswith(".v"):
            out.append((str(p), "nibabel", "nibabel", "ECAT"))
    return out


def _is_hdf5(p: Path) -> bool:
    with open(p, "rb") as f:
        return f.read(8) == b"\x89HDF\r\n\x1a\n"


# ------------------------------------------------------------------------------ written files


def by_nibabel(work: Path):
    import nibabel as nib

    d = work / "nibabel"
    d.mkdir(parents=True, exist_ok=True)
    out = []
    oblique = np.eye(4)
    oblique[:3, :3] = ROTATION @ np.diag([0.9, 1.1, 2.5])
    oblique[:3, 3] = [10.5, -20.0, 30.25]

    def save(img, name):
        p = d / name
        nib.save(img, str(p))
        out.append((str(p), "nibabel", "nibabel-written", "in"))

    for dt in ("uint8", "int8", "int16", "uint16", "int32", "uint32", "int64", "float32", "float64"):
        img = nib.Nifti1Image(_pattern(dt), oblique, dtype=dt)
        save(img, f"n1_{dt}.nii.gz")
    img = nib.Nifti1Image(_pattern("int16"), oblique)
    img.header.set_slope_inter(0.5, -1024.0)
    save(img, "n1_scaled.nii")
    img = nib.Nifti1Image(_pattern("int16"), None)
    img.header.set_qform(np.diag([-1.2, 1.5, 2.0, 1.0]), code=1)
    img.header.set_sform(None, code=0)
    save(img, "n1_qform_only.nii")
    img = nib.Nifti1Image(_pattern("float32"), oblique)
    save(img, "n1_pair.img")
    four = np.stack([_pattern("int16", seed=s) for s in range(4)], axis=-1)
    img = nib.Nifti1Image(four, oblique)
    img.header.set_xyzt_units("mm", "sec")
    img.header["pixdim"][4] = 2.5
    save(img, "n1_fmri_4d.nii.gz")
    five = np.stack([_pattern("float32", seed=s) for s in range(3)], axis=-1)[:, :, :, np.newaxis, :]
    img = nib.Nifti1Image(five, oblique)
    img.header.set_intent("vector")
    save(img, "n1_vector_5d.nii.gz")
    rgb = np.zeros(DIMS, dtype=[("R", "u1"), ("G", "u1"), ("B", "u1")])
    for i, c in enumerate("RGB"):
        rgb[c] = _pattern("uint8", seed=10 + i)
    save(nib.Nifti1Image(rgb, oblique), "n1_rgb24.nii")
    for dt in ("int16", "float32", "uint8"):
        img = nib.Nifti2Image(_pattern(dt), oblique)
        save(img, f"n2_{dt}.nii")
    save(nib.Nifti2Image(four, oblique), "n2_4d.nii.gz")
    for dt in ("int16", "float32", "uint8"):
        img = nib.AnalyzeImage(_pattern(dt), np.diag([-2.0, 2.0, 3.0, 1.0]))
        save(img, f"analyze_{dt}.img")
    # SPM's variant: the origin voxel in the originator field (set through nibabel's SPM2
    # header; saving an Spm2AnalyzeImage would also write a .mat, which needs scipy).
    save(nib.AnalyzeImage(_pattern("int16"), np.diag([-2.0, 2.0, 3.0, 1.0])), "analyze_spm_origin.img")
    spm_hdr = d / "analyze_spm_origin.hdr"
    with open(spm_hdr, "rb") as f:
        hdr = nib.Spm2AnalyzeHeader.from_fileobj(f)
    hdr["origin"][:3] = [3, 4, 2]
    with open(spm_hdr, "r+b") as f:
        hdr.write_to(f)
    for dt in ("uint8", "int16", "uint16", "int32", "float32"):
        img = nib.MGHImage(_pattern(dt), oblique)
        save(img, f"mgh_{dt}.mgz")
    save(nib.MGHImage(_pattern("float32"), oblique), "mgh_float32.mgh")
    save(nib.MGHImage(four.astype(np.float32), oblique), "mgh_frames.mgz")
    return out


def by_pynrrd(work: Path):
    import nrrd

    d = work / "pynrrd"
    d.mkdir(parents=True, exist_ok=True)
    out = []
    dirs = (ROTATION @ np.diag([0.9, 1.2, 2.5])).T  # rows: the axes' steps
    base = {"space": "left-posterior-superior", "space directions": dirs, "space origin": np.array([1.5, -2.0, 30.0])}

    def save(data, name, header, **kw):
        p = d / name
        nrrd.write(str(p), data, header, **kw)
        out.append((str(p), "nrrd", "pynrrd-written", "in"))

    for dt in ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32", "float64"):
        save(_pattern(dt), f"{dt}.nrrd", dict(base))
    for enc in ("raw", "gzip", "bzip2", "ascii"):
        save(_pattern("int16"), f"enc_{enc}.nrrd", dict(base, encoding=enc))
    save(_pattern("float32"), "big_endian.nrrd", dict(base, endian="big"))
    save(_pattern("int16"), "detached.nhdr", dict(base), detached_header=True)
    save(_pattern("uint16"), "ras.nrrd", dict(base, space="right-anterior-superior"))
    save(_pattern("int16"), "spacings.nrrd", {"spacings": [0.5, 0.7, 2.0]})
    four = np.stack([_pattern("int16", seed=s) for s in range(4)], axis=-1)
    save(four, "time_4d.nrrd", dict(base, **{"space directions": np.vstack([dirs, [np.nan] * 3]), "kinds": ["domain", "domain", "domain", "time"]}))
    vec = np.stack([_pattern("float32", seed=s) for s in range(3)], axis=0)
    save(vec, "vector_4d.nrrd", dict(base, **{"space directions": np.vstack([[np.nan] * 3, dirs]), "kinds": ["vector", "domain", "domain", "domain"]}))
    rgb = np.stack([_pattern("uint8", seed=s) for s in range(3)], axis=0)
    save(rgb, "rgb.nrrd", dict(base, **{"space directions": np.vstack([[np.nan] * 3, dirs]), "kinds": ["RGB-color", "domain", "domain", "domain"]}))
    return out


def by_tifffile(work: Path):
    import tifffile

    d = work / "tifffile"
    d.mkdir(parents=True, exist_ok=True)
    out = []

    def save(data, name, **kw):
        p = d / name
        tifffile.imwrite(str(p), data, **kw)
        out.append((str(p), "tiff", "tifffile-written", "in"))

    zyx = lambda a: np.ascontiguousarray(a.transpose(2, 1, 0))  # noqa: E731
    for dt in ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64"):
        save(zyx(_pattern(dt)), f"{dt}.tif")
    for comp in ("lzw", "zlib", "packbits", "zstd", "lzma"):
        save(zyx(_pattern("uint16")), f"c_{comp}.tif", compression=comp)
    save(zyx(_pattern("uint16")), "predictor.tif", compression="zlib", predictor=True)
    save(zyx(_pattern("float32")), "fpredictor.tif", compression="zlib", predictor=3)
    smooth = np.fromfunction(lambda z, y, x: 40 * x + 10 * y + 5 * z, (5, 16, 16)).astype(np.uint8)
    save(smooth, "c_jpeg.tif", compression="jpeg", photometric="minisblack")
    # values 20..=225 (no wrap-around): colour JPEG, where chroma is subsampled
    smooth_c = np.fromfunction(lambda z, y, x: 20 + 6 * x + 5 * y + 15 * z, (5, 12, 16)).astype(np.uint8)
    save(zyx(_pattern("uint8")), "miniswhite.tif", photometric="miniswhite")
    rgb = np.stack([zyx(_pattern("uint8", seed=s)) for s in range(3)], axis=-1)
    save(rgb, "rgb_contig.tif", photometric="rgb")
    # planar: tifffile takes the samples before y and x (z, s, y, x)
    save(np.ascontiguousarray(np.moveaxis(rgb, -1, 1)), "rgb_planar.tif", photometric="rgb", planarconfig="separate")
    save(zyx(_pattern("uint16")), "tiled.tif", tile=(16, 16))
    save(zyx(_pattern("uint16")), "bigtiff.tif", bigtiff=True)
    cmap = ((np.arange(256 * 3).reshape(3, 256) * 85) % 65536).astype(np.uint16)
    save(zyx(_pattern("uint8")), "palette.tif", photometric="palette", colormap=cmap)
    # colour, sample types and codecs the TIFF reader converts or decodes (issue: TIFF colour)
    save(zyx(_pattern("int16")), "miniswhite_int16.tif", photometric="miniswhite")
    save(zyx(_pattern("float32")), "miniswhite_float32.tif", photometric="miniswhite")
    save(zyx(_pattern("uint8")) % 2 == 0, "bilevel.tif")  # tifffile: 1-bit MINISWHITE
    save(zyx(_pattern("uint8")) % 16, "palette4.tif", photometric="palette", colormap=cmap, bitspersample=4)
    for dt in ("int64", "uint64", "float16"):
        save(zyx(_pattern(dt)), f"{dt}.tif")
    rgb16 = np.stack([zyx(_pattern("uint16", seed=s)) for s in range(3)], axis=-1)
    save(np.ascontiguousarray(np.moveaxis(rgb16, -1, 1)), "rgb16_planar_lzw.tif", photometric="rgb", planarconfig="separate", compression="lzw", predictor=True)
    save(rgb, "rgb_tiled_bigtiff.tif", photometric="rgb", tile=(16, 16), compression="zlib", bigtiff=True)
    smooth_rgb = np.stack([smooth_c, 255 - smooth_c, smooth_c // 2 + 60], axis=-1).astype(np.uint8)
    save(smooth_rgb, "c_jpeg_rgb.tif", photometric="rgb", compression="jpeg")
    save(smooth_rgb, "c_jpeg_rgb_tiled.tif", photometric="rgb", compression="jpeg", tile=(16, 16))
    save(rgb, "c_webp_lossless.tif", photometric="rgb", compression="webp", compressionargs={"lossless": True})
    save(rgb, "imagej_rgb.tif", imagej=True, photometric="rgb", metadata={"axes": "ZYXS"})
    save(rgb, "ome_rgb.ome.tif", photometric="rgb", metadata={"axes": "ZYXS"})
    save(zyx(_pattern("uint16")), "imagej.tif", imagej=True, resolution=(2.0, 2.0), metadata={"spacing": 3.0, "unit": "um", "axes": "ZYX"})
    save(zyx(_pattern("uint16")), "ome.ome.tif", metadata={"axes": "ZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 2.0})
    return out


def by_sitk(work: Path):
    import SimpleITK as sitk

    d = work / "simpleitk"
    d.mkdir(parents=True, exist_ok=True)
    out = []
    direction = (0.8, -0.6, 0.0, 0.6, 0.8, 0.0, 0.0, 0.0, 1.0)

    def save(img, name, compress=False):
        p = d / name
        sitk.WriteImage(img, str(p), compress)
        # NIfTI's reference is nibabel (ITK reads one voxel of oblique.nii.gz as NaN)
        kind = "nibabel" if name.endswith((".nii", ".nii.gz")) else "sitk"
        out.append((str(p), kind, "SimpleITK-written", "in"))

    def image(dt, seed=1):
        img = sitk.GetImageFromArray(np.ascontiguousarray(_pattern(dt, seed=seed).transpose(2, 1, 0)))
        img.SetSpacing((0.7, 0.9, 2.5))
        img.SetOrigin((-10.0, 20.5, 3.0))
        img.SetDirection(direction)
        return img

    for dt in ("uint8", "int8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32", "float64"):
        save(image(dt), f"{dt}.mha")
    save(image("int16"), "compressed.mha", compress=True)
    save(image("int16"), "detached.mhd")
    save(image("int16"), "oblique.nrrd")
    save(image("float32"), "oblique.nii.gz")
    save(image("int16"), "oblique.nii")
    rgb = sitk.Compose([sitk.Cast(image("uint8", s), sitk.sitkUInt8) for s in range(3)])
    save(rgb, "rgb.mha")
    return out


def by_pydicom(work: Path):
    """pydicom's own images transcoded by pydicom and its encoders (pylibjpeg-rle, pyjpegls,
    pylibjpeg-openjpeg), as a PACS archives them: RLE, JPEG-LS lossless and near-lossless,
    JPEG 2000 lossless and lossy, deflated data sets."""
    import pydicom
    from pydicom import uid

    d = work / "pydicom"
    d.mkdir(parents=True, exist_ok=True)
    out = []
    pyd = site("pydicom") / "data" / "test_files"
    store = site("data_store") / "data"
    sources = [pyd / "CT_small.dcm", pyd / "MR_small.dcm", store / "emri_small.dcm", store / "SC_rgb.dcm", store / "SC_rgb_16bit.dcm"]
    syntaxes = [
        ("rle", uid.RLELossless, {}),
        ("jls", uid.JPEGLSLossless, {}),
        ("jlsnear2", uid.JPEGLSNearLossless, {"jls_error": 2}),
        ("j2k", uid.JPEG2000Lossless, {}),
        ("j2kcr10", uid.JPEG2000, {"j2k_cr": [10]}),
    ]
    for src in sources:
        for tag, ts, kw in syntaxes:
            ds = pydicom.dcmread(src)
            try:
                ds.compress(ts, **kw)
            except Exception:  # noqa: BLE001 - an encoder that refuses this image: no file
                continue
            p = d / f"{src.stem}_{tag}.dcm"
            ds.save_as(p, enforce_file_format=True)
            out.append((str(p), "dicom", "pydicom-transcoded", "in"))
        ds = pydicom.dcmread(src)
        ds.file_meta.TransferSyntaxUID = uid.DeflatedExplicitVRLittleEndian
        p = d / f"{src.stem}_deflated.dcm"
        ds.save_as(p, enforce_file_format=True)
        out.append((str(p), "dicom", "pydicom-transcoded", "in"))
    return out


def corpus(work: Path):
    work.mkdir(parents=True, exist_ok=True)
    entries = shipped(work)
    for gen in (by_nibabel, by_pynrrd, by_tifffile, by_sitk, by_pydicom):
        entries += gen(work)
    return entries
