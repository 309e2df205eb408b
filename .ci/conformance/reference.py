"""What the reference libraries say a file holds: values and geometry.

Each reader returns a `Reference`: the values as a float64 array indexed (x, y, z) or, for
colour, (x, y, z, c); the index-to-LPS affine (4x4, millimetres) when the file defines one;
the tolerance of the comparison (0 for lossless data, the codec's own for lossy ones); and
the Volux options that choose the same volume (say `--timepoint 3`). A file the library
cannot decode raises `NoReference`; a file that is not an image raises `NotImage`.

Conventions, each the reference library's own:
- DICOM (pydicom): `pixel_array`, then the Modality LUT (`apply_modality_lut`: rescale or the
  Modality LUT Sequence), RT Dose's DoseGridScaling, PALETTE COLOR through `apply_color_lut`;
  YBR is converted to RGB by pydicom. Geometry from ImagePositionPatient,
  ImageOrientationPatient and PixelSpacing (top level or functional groups), RT Dose frames
  placed by GridFrameOffsetVector.
- NIfTI, Analyze, MGH, MINC (nibabel): the scaled data (`dataobj`), the affine nibabel picks
  (sform, else qform, else its default), RAS turned to LPS. An image whose header has neither
  sform nor qform has no defined orientation: its geometry is not compared.
- NRRD (pynrrd): the data and `space directions` / `space origin` in the header's space.
- MetaImage and files written by SimpleITK: SimpleITK (ITK's readers, LPS).
- TIFF (tifffile): pages as z slices; MINISWHITE inverted (white is 0 in the file).
"""
from __future__ import annotations

import dataclasses
import os
from typing import Optional

import numpy as np

LPS_FROM_RAS = np.diag([-1.0, -1.0, 1.0, 1.0])


class NoReference(Exception):
    """The reference library cannot decode the file."""


class NotImage(Exception):
    """The file holds no image (a DICOM plan, a streamline file...)."""


@dataclasses.dataclass
class Reference:
    values: np.ndarray  # (x, y, z) or (x, y, z, c), float64
    affine: Optional[np.ndarray]  # 4x4 index -> LPS mm, or None
    tol: float = 0.0  # largest absolute difference accepted (lossy codecs)
    args: tuple = ()  # Volux options choosing this volume
    why_no_geometry: str = ""
    expect_note: str = ""  # a word Volux's notes must contain (a value transform it applies)


def zyx_to_xyz(arr: np.ndarray, color: bool) -> np.ndarray:
    """(z, y, x[, c]) -> (x, y, z[, c])."""
    return arr.transpose(2, 1, 0, 3) if color else arr.transpose(2, 1, 0)


def affine_from(origin, columns) -> np.ndarray:
    """4x4 affine with the index axes' steps as columns."""
    a = np.eye(4)
    a[:3, :3] = np.column_stack([np.asarray(c, float) for c in columns])
    a[:3, 3] = np.asarray(origin, float)
    return a


# --------------------------------------------------------------------------------------- DICOM


def _fg(ds, frame: int, seq: str, attr: str):
    """An attribute of a functional group macro: per-frame first, then shared."""
    for groups, i in (("PerFrameFunctionalGroupsSequence", frame), ("SharedFunctionalGroupsSequence", 0)):
        g = ds.get(groups)
        if g is not None and len(g) > i:
            inner = g[i].get(seq)
            if inner is not None and len(inner) and attr in inner[0]:
                return inner[0].get(attr)
    return None


def _dicom_geometry(ds, frames: int):
    iop = ds.get("ImageOrientationPatient") or _fg(ds, 0, "PlaneOrientationSequence", "ImageOrientationPatient")
    ps = ds.get("PixelSpacing") or _fg(ds, 0, "PixelMeasuresSequence", "PixelSpacing")
    positions = None
    if ds.get("PerFrameFunctionalGroupsSequence") is not None:
        p = [_fg(ds, f, "PlanePositionSequence", "ImagePositionPatient") for f in range(frames)]
        if all(x is not None for x in p):
            positions = [np.array([float(v) for v in x]) for x in p]
    ipp = ds.get("ImagePositionPatient")
    if positions is None and ipp is not None:
        ipp = np.array([float(v) for v in ipp])
        offsets = ds.get("GridFrameOffsetVector")
        if frames > 1 and offsets is not None and iop is not None:
            r, c = np.array(iop[:3], float), np.array(iop[3:], float)
            n = np.cross(r, c)
            positions = [ipp + float(o) * n for o in offsets]
            if len(positions) != frames:
                return None, "GridFrameOffsetVector does not have one offset per frame"
        elif frames == 1:
            positions = [ipp]
    if iop is None or positions is None:
        return None, "no ImageOrientationPatient / ImagePositionPatient"
    r, c = np.array([float(v) for v in iop[:3]]), np.array([float(v) for v in iop[3:]])
    ps = [float(v) for v in ps] if ps is not None else [1.0, 1.0]
    n = np.cross(r, c)
    if frames > 1:
        step = (positions[-1] - positions[0]) / (frames - 1)
        for k, p in enumerate(positions):
            if np.linalg.norm(positions[0] + k * step - p) > 1e-3 * max(1.0, np.linalg.norm(step)):
                return None, "frames not evenly spaced"
        if np.linalg.norm(step) < 1e-9:
            return None, "frames at one position"
    else:
        step = n
    return affine_from(positions[0], [r * ps[1], c * ps[0], step]), ""


LOSSY = {
    "1.2.840.10008.1.2.4.81": 0.0,  # JPEG-LS near-lossless: decoders agree exactly (NEAR bounds the loss)
    "1.2.840.10008.1.2.4.50": 3.0,  # JPEG baseline: decoders differ by rounding (IDCT)
    "1.2.840.10008.1.2.4.51": 3.0,
    "1.2.840.10008.1.2.4.91": 1.0,  # JPEG 2000 (lossy): OpenJPEG decodes identically
    "1.2.840.10008.1.2.4.203": 1.0,  # HTJ2K
}

# The JPEG DCT processes, whose chroma upsampling ITU-T T.81 leaves to the decoder.
JPEG_DCT = ("1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51")
# Colour JPEG with subsampled chroma (4:2:2, 4:2:0): decoders upsample as they choose, so the
# tolerance is the reference decoders' own disagreement. On pydicom-data's
# color3d_jpeg_baseline.dcm (YBR_FULL_422) libjpeg-turbo (Pillow) and pylibjpeg-libjpeg
# differ by up to 5 at 840 of 110592000 samples.
SUBSAMPLED_CHROMA_TOL = 6.0


def dicom(path: str) -> Reference:
    import pydicom
    from pydicom.pixels import apply_color_lut, apply_modality_lut

    try:
        ds = pydicom.dcmread(path)
    except Exception as e:  # noqa: BLE001 - any failure of the reference is "no reference"
        raise NoReference(f"pydicom: {e}") from e
    if not any(t in ds for t in ("PixelData", "FloatPixelData", "DoubleFloatPixelData")):
        raise NotImage("no pixel data")
    try:
        arr = ds.pixel_array
    except Exception as e:  # noqa: BLE001
        raise NoReference(f"pydicom pixel_array: {str(e).splitlines()[0]}") from e
    frames = int(ds.get("NumberOfFrames", 1) or 1)
    spp = int(ds.get("SamplesPerPixel", 1))
    photometric = str(ds.get("PhotometricInterpretation", ""))
    expect_note = ""
    if photometric == "PALETTE COLOR":
        if str(ds.file_meta.get("TransferSyntaxUID", "")) == "1.2.840.10008.1.2.2":
            # pydicom 3.0's apply_color_lut reads the (non-segmented) LUT data's OW bytes as
            # little-endian words whatever the byte order; a big-endian file's words are
            # big-endian (PS3.5 7.3), so they are swapped here first.
            for c in ("Red", "Green", "Blue"):
                kw = f"{c}PaletteColorLookupTableData"
                if kw in ds:
                    ds[kw].value = np.frombuffer(ds[kw].value, ">u2").astype("<u2").tobytes()
        arr = apply_color_lut(arr, ds)
        spp = 3
        expect_note = "palette"
    elif spp == 1:
        if "ModalityLUTSequence" in ds:
            expect_note = "Modality LUT"
        rescale = any(
            t in ds for t in ("RescaleSlope", "RescaleIntercept", "ModalityLUTSequence")
        )
        if rescale:
            arr = apply_modality_lut(arr, ds)
        else:
            slope = _fg(ds, 0, "PixelValueTransformationSequence", "RescaleSlope")
            inter = _fg(ds, 0, "PixelValueTransformationSequence", "RescaleIntercept")
            if slope is not None or inter is not None:
                per = [
                    (
                        float(_fg(ds, f, "PixelValueTransformationSequence", "RescaleSlope") or 1),
                        float(_fg(ds, f, "PixelValueTransformationSequence", "RescaleIntercept") or 0),
                    )
                    for f in range(frames)
                ]
                a = arr.astype(np.float64).reshape((frames,) + arr.shape[-2:])
                arr = np.stack([a[f] * s + i for f, (s, i) in enumerate(per)])
        if "DoseGridScaling" in ds:
            arr = arr.astype(np.float64) * float(ds.DoseGridScaling)
            expect_note = "DoseGridScaling"
    color = spp > 1
    arr = np.asarray(arr, dtype=np.float64)
    want = 4 if color else 3
    while arr.ndim < want:
        arr = arr[np.newaxis]
    if color and spp == 4:
        raise NoReference("4 samples per pixel")
    affine, why = _dicom_geometry(ds, frames)
    tsuid = str(ds.file_meta.get("TransferSyntaxUID", ""))
    tol = LOSSY.get(tsuid, 0.0)
    if tol and color and tsuid in JPEG_DCT and _chroma_subsampled(ds):
        tol = SUBSAMPLED_CHROMA_TOL
    if tol and int(ds.get("BitsStored", 8)) > 8:
        tol *= 2 ** (int(ds.BitsStored) - 8)
    return Reference(zyx_to_xyz(arr, color), affine, tol, (), why, expect_note)


def _chroma_subsampled(ds) -> bool:
    """Whether the first JPEG frame's SOF gives its components different sampling factors."""
    from pydicom.encaps import generate_frames

    try:
        frame = next(generate_frames(ds.PixelData, number_of_frames=int(ds.get("NumberOfFrames", 1) or 1)))
    except Exception:
        return False
    for marker in (b"\xff\xc0", b"\xff\xc1", b"\xff\xc2"):
        i = frame.find(marker)
        if i >= 0 and len(frame) > i + 10:
            n = frame[i + 9]
            factors = {frame[i + 11 + 3 * c] for c in range(n) if len(frame) > i + 11 + 3 * c}
            return len(factors) > 1
    return False


# ------------------------------------------------------------------------------------ nibabel


def nibabel(path: str, volume: int = 0) -> list[Reference]:
    """NIfTI-1/2, Analyze, MGH, MINC through nibabel: the first volume, and the last when
    the image has more than one along its 4th axis."""
    import nibabel as nib

    try:
        img = nib.load(path)
        if not hasattr(img, "affine"):
            raise NoReference("no affine (a CIFTI matrix, not a volume)")
        data = np.asanyarray(img.dataobj)
    except NoReference:
        raise
    except Exception as e:  # noqa: BLE001
        raise NoReference(f"nibabel: {str(e).splitlines()[0]}") from e
    if data.ndim < 2:
        raise NoReference("fewer than 2 dimensions")
    color = data.dtype.names is not None
    if color:
        data = np.stack([data[n] for n in data.dtype.names], axis=-1)
    data = data.astype(np.float64)
    while data.ndim < 3:
        data = data[..., np.newaxis]
    if getattr(img, "affine", None) is None:
        raise NoReference("no affine (a CIFTI matrix, not a volume)")
    affine = LPS_FROM_RAS @ np.asarray(img.affine, float)
    why = ""
    hdr = img.header
    if hasattr(hdr, "get_value_label") and "sform_code" in hdr:
        if int(hdr["sform_code"]) == 0 and int(hdr["qform_code"]) == 0:
            affine, why = None, "neither sform nor qform (orientation undefined)"
    extra = data.shape[3:] if not color else data.shape[3:-1]
    out = []
    if not extra:
        return [Reference(data, affine, why_no_geometry=why)]
    n_t = extra[0]
    for t in sorted({0, n_t - 1}):
        v = data[:, :, :, t]
        while v.ndim > (4 if color else 3):
            v = v[:, :, :, 0]
        args = ("--timepoint", str(t)) if t else ()
        out.append(Reference(v, affine, args=args, why_no_geometry=why))
    return out


# -------------------------------------------------------------------------------------- NRRD

NRRD_SPACES = {
    "left-posterior-superior": np.eye(3),
    "lps": np.eye(3),
    "right-anterior-superior": np.diag([-1.0, -1.0, 1.0]),
    "ras": np.diag([-1.0, -1.0, 1.0]),
    "left-anterior-superior": np.diag([1.0, -1.0, 1.0]),
    "las": np.diag([1.0, -1.0, 1.0]),
}


def nrrd(path: str) -> list[Reference]:
    import nrrd as pynrrd

    try:
        data, hdr = pynrrd.read(path)
    except Exception as e:  # noqa: BLE001
        raise NoReference(f"pynrrd: {str(e).splitlines()[0]}") from e
    data = np.asarray(data)
    kinds = [k.lower() for k in hdr.get("kinds", ["domain"] * data.ndim)]
    dirs = hdr.get("space directions")
    space = str(hdr.get("space", "")).lower()
    spatial = [i for i, k in enumerate(kinds) if k in ("domain", "space")]
    if dirs is not None:
        spatial = [i for i in range(data.ndim) if dirs[i] is not None and not np.any(np.isnan(np.asarray(dirs[i], float)))]
    if len(spatial) < 2 or len(spatial) > 3:
        raise NoReference(f"{len(spatial)} spatial axes")
    others = [i for i in range(data.ndim) if i not in spatial]
    data = data.astype(np.float64)
    color_axis = [i for i in others if kinds[i] in ("rgb-color", "rgba-color", "3-color", "4-color")]
    affine, why = None, "no space directions"
    if dirs is not None and space in NRRD_SPACES:
        to_lps = NRRD_SPACES[space]
        cols = [to_lps @ np.asarray(dirs[i], float) for i in spatial]
        if len(cols) == 2:
            cols.append(np.cross(cols[0], cols[1]) / np.linalg.norm(np.cross(cols[0], cols[1])))
        origin = to_lps @ np.asarray(hdr.get("space origin", np.zeros(3)), float)
        affine, why = affine_from(origin, cols), ""
    elif dirs is not None:
        why = f"space '{space}' is not patient space"
    out = []
    rest = [i for i in others if i not in color_axis]
    order = spatial + color_axis + rest
    d = data.transpose(order)
    if len(spatial) == 2:
        d = d[:, :, np.newaxis]
    color = bool(color_axis)
    base = 4 if color else 3
    if d.ndim == base:
        return [Reference(d, affine, why_no_geometry=why)]
    if color:
        raise NoReference("colour with further axes")
    # a 4th axis (time, list, vector): its first and last entries
    flag = "--component" if kinds[rest[0]] in ("vector", "covariant-vector", "list", "point", "normal", "3-vector") else "--timepoint"
    n = d.shape[3]
    for t in sorted({0, n - 1}):
        v = d[:, :, :, t]
        while v.ndim > 3:
            v = v[..., 0]
        out.append(Reference(v, affine, args=(flag, str(t)) if t else (), why_no_geometry=why))
    return out


# -------------------------------------------------------------------------------- SimpleITK


def sitk(path: str) -> Reference:
    import SimpleITK as s

    try:
        img = s.ReadImage(path)
    except Exception as e:  # noqa: BLE001
        raise NoReference(f"SimpleITK: {str(e).strip().splitlines()[-1]}") from e
    if img.GetDimension() not in (2, 3):
        raise NoReference(f"{img.GetDimension()}-D image")
    arr = s.GetArrayFromImage(img).astype(np.float64)
    color = img.GetNumberOfComponentsPerPixel() > 1
    if img.GetDimension() == 2:
        arr = arr[np.newaxis]
    d = np.array(img.GetDirection(), float).reshape(img.GetDimension(), img.GetDimension())
    sp, org = list(img.GetSpacing()), list(img.GetOrigin())
    if img.GetDimension() == 2:
        d3 = np.eye(3)
        d3[:2, :2] = d
        d, sp, org = d3, sp + [1.0], org + [0.0]
    cols = [d[:, i] * sp[i] for i in range(3)]
    return Reference(zyx_to_xyz(arr, color), affine_from(org, cols))


# ------------------------------------------------------------------------------------- TIFF


def tiff(path: str) -> Reference:
    import tifffile

    try:
        with tifffile.TiffFile(path) as tf:
            page = tf.pages[0]
            photometric = int(page.photometric)
            arr = tf.asarray()
            colormap = page.colormap
            compression = int(page.compression)
            bits = int(page.bitspersample)
            series_axes = tf.series[0].axes
    except Exception as e:  # noqa: BLE001
        raise NoReference(f"tifffile: {str(e).splitlines()[0]}") from e
    note = ""
    arr = np.asarray(arr)
    if "S" in series_axes and not series_axes.endswith("S"):
        # planar samples (PlanarConfiguration 2): tifffile puts S before Y and X
        arr = np.moveaxis(arr, series_axes.index("S"), -1)
        series_axes = series_axes.replace("S", "") + "S"
    if photometric == 0:  # MINISWHITE
        # unsigned (bilevel too, which tifffile returns as bool): the type's maximum minus
        # the value, 2**BitsPerSample - 1 (1 for bilevel, 15 for 4-bit samples tifffile
        # returns as uint8); signed and float: the negated value
        unsigned = arr.dtype.kind in "bu"
        arr = ((2.0**bits - 1) - arr.astype(np.float64)) if unsigned else -arr.astype(np.float64)
        note = "MINISWHITE"
    color = False
    if photometric == 3 and colormap is not None:  # PALETTE
        arr = np.moveaxis(colormap[:, arr], 0, -1)
        color, note = True, "palette"
    elif photometric in (2, 6) or (arr.ndim >= 3 and series_axes.endswith("S")):
        color = True
    if color and series_axes.endswith("S") is False and photometric != 3:
        pass
    arr = arr.astype(np.float64)
    want = 4 if color else 3
    if arr.ndim > want:
        raise NoReference(f"{arr.ndim}-D TIFF series ({series_axes})")
    while arr.ndim < want:
        arr = arr[np.newaxis]
    tol = 0.0
    if compression == 7:  # JPEG
        tol = 3.0 * 2 ** max(0, bits - 8)
    return Reference(zyx_to_xyz(arr, color), None, tol, why_no_geometry="TIFF geometry is not compared", expect_note=note)


def for_file(path: str, kind: str) -> list[Reference]:
    """The references of `path`, read as `kind` (see corpus.py)."""
    if kind == "dicom":
        return [dicom(path)]
    if kind == "nibabel":
        return nibabel(path)
    if kind == "nrrd":
        return nrrd(path)
    if kind == "sitk":
        return [sitk(path)]
    if kind == "tiff":
        return [tiff(path)]
    raise ValueError(kind)


def file_size(path: str) -> int:
    if os.path.isdir(path):
        return sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(path) for f in fs)
    return os.path.getsize(path)
