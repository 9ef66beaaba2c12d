"""_lib.py: the compiled binding, cbvh's error as a Python exception, and numpy views of the C structs."""
from typing import Dict, Optional, Tuple

import numpy as np

from ._native import ffi, lib

NO_HIT = int(lib.CBVH_NO_HIT)


class CbvhError(Exception):
    """An error reported by cbvh: `code` is the cbvh_result value (cbvh.h; None when the cbvh command
    reported it), `name` its description (cbvh_result_string) and `message` what is wrong and where."""

    def __init__(self, code: Optional[int], message: str):
        self.code = code
        self.name = ffi.string(lib.cbvh_result_string(code)).decode() if code is not None else "error"
        self.message = message
        super().__init__("%s: %s" % (self.name, message) if message else self.name)


def raise_for(code: int, err=None, where: str = "") -> None:
    """Raises CbvhError for a failed cbvh_result (with the cbvh_error's message when given)."""
    if code == lib.CBVH_OK:
        return
    message = ffi.string(err.message).decode("utf-8", "replace") if err is not None else ""
    if where:
        message = where + (": " + message if message else "")
    raise CbvhError(int(code), message)


def struct_dtype(ctype: str, fields: Dict[str, Tuple[str, tuple]]) -> np.dtype:
    """A numpy dtype laid out as the C struct `ctype` (offsets and size from the compiler, through cffi), so
    that arrays of it are passed to cbvh without conversion."""
    names = list(fields)
    c_fields = dict(ffi.typeof(ctype).fields)
    for name in names:
        if ffi.sizeof(c_fields[name].type) != np.dtype(fields[name]).itemsize:
            raise ImportError("cbvh: %s.%s does not have the size the binding expects" % (ctype, name))
    return np.dtype({
        "names": names,
        "formats": [np.dtype(fields[n]) for n in names],
        "offsets": [ffi.offsetof(ctype, n) for n in names],
        "itemsize": ffi.sizeof(ctype),
    })


def enum_type(ctype: str) -> str:
    return {1: "<i1", 2: "<i2", 4: "<i4", 8: "<i8"}[ffi.sizeof(ctype)]


RAY = struct_dtype("cbvh_ray", {"org": ("<f4", (3,)), "tmin": ("<f4", ()), "dir": ("<f4", (3,)),
                                "tmax": ("<f4", ())})
HIT = struct_dtype("cbvh_hit", {"tri": ("<u4", ()), "t": ("<f4", ()), "u": ("<f4", ()), "v": ("<f4", ())})
SHAPE = struct_dtype("cbvh_shape", {
    "kind": (enum_type("cbvh_shape_kind"), ()), "center": ("<f4", (3,)), "p0": ("<f4", (3,)),
    "p1": ("<f4", (3,)), "radius": ("<f4", ()), "half_extent": ("<f4", (3,)), "rotation": ("<f4", (4,))})
SWEEP_RECORD = struct_dtype("cbvh_sweep_record", {
    "tri": ("<u4", ()), "t": ("<f4", ()), "point": ("<f4", (3,)), "normal": ("<f4", (3,)),
    "depth": ("<f4", ()), "material": ("<u4", ())})
CONTACT = struct_dtype("cbvh_contact", {"tri": ("<u4", ()), "depth": ("<f4", ()), "normal": ("<f4", (3,)),
                                        "point": ("<f4", (3,))})


def pointer(ctype: str, array: Optional[np.ndarray]):
    """A cffi pointer into a C-contiguous numpy array (ffi.NULL for None)."""
    if array is None:
        return ffi.NULL
    assert array.flags.c_contiguous
    return ffi.cast(ctype, array.ctypes.data)
