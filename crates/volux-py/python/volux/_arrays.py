"""How a numpy array becomes a grid's samples: read in place when Volux holds its type, or
converted once, said in a warning (never a silent change of values)."""

import numpy as np

#: The types a grid holds, read in place when C-contiguous in native byte order.
IN_PLACE = (np.uint8, np.uint16, np.int16, np.float32)


def volume_array(array):
    """``(array, note)``: the array to read in place and, when it had to be converted, a
    sentence saying how (``None`` when it is read as it is)."""
    a = np.asarray(array)
    if a.ndim != 3:
        raise ValueError(
            f"a volume is a 3-D array indexed [z, y, x]; this one has shape {a.shape}"
        )
    native = a.dtype.isnative
    if a.dtype.type in IN_PLACE and native and a.flags.c_contiguous and a.flags.aligned:
        return a, None
    target = _target_type(a)
    converted = np.ascontiguousarray(a, dtype=target)
    if a.dtype.type in IN_PLACE and a.dtype.newbyteorder("=") == np.dtype(target):
        why = "not C-contiguous" if native else "not in native byte order"
        if native and not a.flags.aligned:
            why = "not aligned"
        note = f"the {a.dtype} array was copied ({why}): changes to it are not seen"
    else:
        note = f"the {a.dtype} array was converted to {np.dtype(target).name}"
        if np.dtype(target) == np.float32 and a.dtype.kind in "iuf" and a.dtype.itemsize > 4:
            note += " (float32 keeps 24 bits of precision)"
        note += ": changes to it are not seen"
    return converted, note


def _target_type(a):
    """The type that holds `a`'s values: its own, the smallest integer type that holds an
    integer array's range exactly, else float32."""
    kind = a.dtype.kind
    if a.dtype.type in IN_PLACE:
        return a.dtype.newbyteorder("=").type
    if kind == "b":
        return np.uint8
    if kind in "iu":
        if a.size == 0:
            return np.int16
        lo, hi = int(a.min()), int(a.max())
        for t in (np.uint8, np.int16, np.uint16):
            info = np.iinfo(t)
            if info.min <= lo and hi <= info.max:
                return t
        return np.float32
    if kind == "f":
        return np.float32
    raise TypeError(
        f"a volume holds numbers; this array is {a.dtype} (convert it with .astype(np.float32))"
    )
