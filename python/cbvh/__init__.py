"""cbvh: cook triangle meshes into quantized BVH files and query them (rays, sweeps, overlaps, contacts)
with numpy arrays, over the cbvh C library."""
from ._lib import CONTACT, HIT, NO_HIT, RAY, SHAPE, SWEEP_RECORD, CbvhError, ffi, lib
from .cook import CookError, cook, cook_file
from .file import Contacts, File, Hits, Overlaps, SweepHits, open

__version__ = ffi.string(lib.cbvh_version_string()).decode()

__all__ = ["CbvhError", "CookError", "Contacts", "File", "Hits", "NO_HIT", "Overlaps", "SHAPE", "SweepHits",
           "cook", "cook_file", "open", "RAY", "HIT", "SWEEP_RECORD", "CONTACT"]
