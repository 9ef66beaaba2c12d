"""file.py: an opened cbvh file and its batched queries over numpy arrays (rays, sweeps, overlaps, contacts).

Every query releases the GIL while cbvh runs (cffi does on each call), and `threads=N` splits a batch into N
parts run at once on one opened file, which cbvh allows: an opened file is immutable. The answers do not
depend on N.
"""
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np

from ._lib import CONTACT, HIT, NO_HIT, SHAPE, SWEEP_RECORD, CbvhError, ffi, lib, pointer, raise_for

ArrayLike = Union[np.ndarray, float, List[float], Tuple[float, ...]]
# Rays the streams take a batch (the library's scratch holds at most 4096; `cbvh raycast` uses 1024 too).
_STREAM_BATCH = 1024


@dataclass
class Hits:
    """Closest hits, one entry per ray: tri is the original triangle id (NO_HIT, 0xFFFFFFFF, for a miss), t
    the distance in units of the direction (inf for a miss), u and v the barycentrics of the point
    (1-u-v)*v0 + u*v1 + v*v2, normal the unit geometric normal (v1-v0) x (v2-v0), material the triangle's
    material id (zeros for a miss). tri, t, u and v are views of one array of cbvh_hit records (cbvh.HIT)."""
    tri: np.ndarray
    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    normal: Optional[np.ndarray]
    material: Optional[np.ndarray]

    @property
    def hit(self) -> np.ndarray:
        return self.tri != NO_HIT


@dataclass
class SweepHits:
    """First contacts of sweeps, one entry per shape (cbvh_sweep_record): tri (NO_HIT for none), t in [0, 1]
    of the motion, point on the triangle, unit normal from the triangle towards the shape, depth (how far a
    shape overlapping at t = 0 reaches in) and material."""
    tri: np.ndarray
    t: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    material: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        return self.tri != NO_HIT


@dataclass
class Overlaps:
    """The triangles each shape overlaps, ragged: those of shape i are tri[offsets[i]:offsets[i + 1]]."""
    offsets: np.ndarray
    tri: np.ndarray

    def __getitem__(self, i: int) -> np.ndarray:
        return self.tri[self.offsets[i]:self.offsets[i + 1]]


@dataclass
class Contacts:
    """Contacts of each shape, ragged as Overlaps: for each overlapping triangle tri, the depth the shape
    reaches in, the unit normal from the triangle towards the shape and the triangle's point nearest the
    shape's core (a box: a point of the triangle inside it); moving the shape by depth * normal separates
    it."""
    offsets: np.ndarray
    tri: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    point: np.ndarray


def _vectors(name: str, value: ArrayLike, width: int = 3) -> np.ndarray:
    a = np.asarray(value, dtype=np.float32)
    if a.ndim not in (1, 2) or a.shape[-1] != width:
        raise ValueError("%s must have shape (N, %d) or (%d,), not %s" % (name, width, width, a.shape))
    return a


def _scalars(name: str, value: ArrayLike) -> np.ndarray:
    a = np.asarray(value, dtype=np.float32)
    if a.ndim > 1:
        raise ValueError("%s must be a number or have shape (N,), not %s" % (name, a.shape))
    return a


def _batch_size(vectors: Dict[str, np.ndarray], scalars: Dict[str, np.ndarray]) -> int:
    sizes = {a.shape[0] for a in vectors.values() if a.ndim == 2}
    sizes |= {a.shape[0] for a in scalars.values() if a.ndim == 1}
    if len(sizes) > 1:
        raise ValueError("the arrays hold different numbers of queries: %s" % ", ".join(
            "%s %s" % (name, a.shape) for name, a in {**vectors, **scalars}.items()))
    return sizes.pop() if sizes else 1


def _parts(count: int, threads: int) -> List[Tuple[int, int]]:
    if not isinstance(threads, int) or threads < 1:
        raise ValueError("threads must be a positive integer, not %r" % (threads,))
    parts = min(threads, max(count, 1))
    bounds = [count * k // parts for k in range(parts + 1)]
    return list(zip(bounds[:-1], bounds[1:]))


def _run_parts(count: int, threads: int, run: Callable[[int, int], Any]) -> List[Any]:
    parts = _parts(count, threads)
    if len(parts) == 1:
        return [run(*parts[0])]
    with ThreadPoolExecutor(max_workers=len(parts)) as pool:
        return list(pool.map(lambda p: run(*p), parts))


def _join_ragged(pieces: List[Tuple[np.ndarray, np.ndarray]]) -> Tuple[np.ndarray, np.ndarray]:
    """Concatenates (offsets, records) parts of consecutive queries."""
    offsets = [np.zeros(1, np.int64)]
    base = 0
    for part_offsets, records in pieces:
        offsets.append(part_offsets[1:].astype(np.int64) + base)
        base += len(records)
    return np.concatenate(offsets), np.concatenate([records for _, records in pieces])


class File:
    """An opened, validated cbvh file. Opening checks everything (header, checksums, every node and index):
    a corrupt, truncated or unsupported file raises CbvhError, and queries never read outside it.

    source: a path (read into memory, so that later changes to the file on disk do not matter) or the bytes
    of a file (kept referenced while open). expand_triangles: cbvh_file_expand_triangles (faster rays on
    small meshes, 36 bytes a triangle)."""

    def __init__(self, source: Union[str, "os.PathLike[str]", bytes, bytearray, memoryview],
                 *, expand_triangles: bool = False):
        handle = ffi.new("cbvh_file **")
        err = ffi.new("cbvh_error *")
        if isinstance(source, (bytes, bytearray, memoryview)):
            self._data = bytes(source)
            code = lib.cbvh_open_memory(ffi.from_buffer(self._data), len(self._data), ffi.NULL, handle, err)
            where = "%d bytes" % len(self._data)
        else:
            self._data = None
            where = os.fspath(source)
            code = lib.cbvh_open_path_read(os.fsencode(where), ffi.NULL, handle, err)
        raise_for(code, err, where)
        self._file = ffi.gc(handle[0], lib.cbvh_close)
        if expand_triangles:
            raise_for(lib.cbvh_file_expand_triangles(self._file, err), err, where)
        info = ffi.new("cbvh_file_info *")
        raise_for(lib.cbvh_file_get_info(self._file, info, ffi.sizeof("cbvh_file_info")))
        self._info = {name: (tuple(getattr(info, name)) if name.startswith(("bounds", "grid")) else
                             int(getattr(info, name)))
                      for name, _ in ffi.typeof("cbvh_file_info").fields if name != "struct_size"}
        self._info["layout"] = {lib.CBVH_LAYOUT_WIDE4: "wide4", lib.CBVH_LAYOUT_BINARY: "binary"}.get(
            self._info["layout"], self._info["layout"])
        self._details: Optional[np.ndarray] = None  # cbvhpy_details of every triangle, made on first use
        self._details_lock = threading.Lock()

    # -- the file ---------------------------------------------------------------------------------------

    def close(self) -> None:
        """Releases the file now (else when it is garbage collected). Queries after close raise; close must
        not run while another thread is querying the file."""
        if self._file is not None:
            ffi.release(self._file)
            self._file = None
            self._details = None

    def __enter__(self) -> "File":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _handle(self):
        if self._file is None:
            raise CbvhError(lib.CBVH_ERROR_INVALID_ARGUMENT, "the file is closed")
        return self._file

    @property
    def info(self) -> Dict[str, Any]:
        """cbvh_file_info as a dict: triangle_count, vertex_count, node_count, depth, layout, bounds_min ..."""
        return dict(self._info)

    @property
    def triangles(self) -> np.ndarray:
        """The vertices of every triangle by original id, shape (original_triangle_count, 3, 3), float32, as
        the queries see them (an id the cook dropped as degenerate: zeros)."""
        count = self._info["original_triangle_count"]
        out = np.empty((count, 3, 3), np.float32)
        lib.cbvhpy_triangles(self._handle(), count, pointer("float *", out))
        return out

    @property
    def material_names(self) -> Dict[int, List[str]]:
        """The names stored for each material id."""
        names: Dict[int, List[str]] = {}
        material_id = ffi.new("uint32_t *")
        for index in range(self._info["material_name_count"]):
            name = lib.cbvh_file_get_material_name(self._handle(), index, material_id)
            names.setdefault(int(material_id[0]), []).append(ffi.string(name).decode("utf-8", "replace"))
        return names

    # -- rays -------------------------------------------------------------------------------------------

    def _details_table(self, threads: int) -> np.ndarray:
        """Each triangle's unit normal and material (cbvhpy_details, 16 bytes a triangle by original id), which
        raycast copies to its hits: computed once (by `threads` threads), on the first raycast that asks for
        them, so that a hit costs one read of a table instead of decoding its triangle again."""
        with self._details_lock:
            if self._details is None:
                table = np.empty((self._info["original_triangle_count"], 4), np.float32)
                handle = self._handle()
                _run_parts(len(table), threads, lambda first, end: lib.cbvhpy_details_table(
                    handle, first, end, pointer("cbvhpy_details *", table)))
                self._details = table
            return self._details

    @staticmethod
    def _rays(origins: ArrayLike, directions: ArrayLike, tmin: ArrayLike, tmax: ArrayLike):
        """The rays as cbvhpy_rays over contiguous float32 arrays (kept alive in the returned list) and
        their count; a single origin, direction or bound serves every ray."""
        vectors = {"origins": _vectors("origins", origins), "directions": _vectors("directions", directions)}
        scalars = {"tmin": _scalars("tmin", tmin), "tmax": _scalars("tmax", tmax)}
        count = _batch_size(vectors, scalars)
        arrays = [np.ascontiguousarray(a).reshape(a.shape) for a in (*vectors.values(), *scalars.values())]
        rays = ffi.new("cbvhpy_rays *")
        for name, array, width in zip(("org", "dir", "tmin", "tmax"), arrays, (3, 3, 1, 1)):
            per_ray = array.ndim == (2 if width == 3 else 1)
            setattr(rays, name, pointer("float *", array))
            setattr(rays, name + "_step", width if per_ray else 0)
        return rays, arrays, count

    def raycast(self, origins: ArrayLike, directions: ArrayLike, tmin: ArrayLike = 0.0,
                tmax: ArrayLike = np.inf, *, details: bool = True, threads: int = 1) -> Hits:
        """Closest hits of the rays origins + t * directions, t in [tmin, tmax] (arrays (N, 3) and (N,), or
        one value for all). A ray cbvh calls invalid (NaN, zero direction, tmin < 0 or > tmax) misses. The
        answers are cbvh_raycast's, ray by ray (through cbvh_raycast_stream_scratch). details=False leaves
        normal and material out (None)."""
        rays, keep_alive, count = self._rays(origins, directions, tmin, tmax)
        records = np.empty(count, HIT)
        handle = self._handle()
        table = self._details_table(threads) if details else None
        normal = np.empty((count, 3), np.float32) if details else None
        # Without a MATERIALS section every id is 0: np.zeros, whose pages stay the system's zero page
        with_materials = details and self._info["has_materials"]
        material = np.empty(count, np.uint32) if with_materials else np.zeros(count, np.uint32) if details else None
        scratch_size = lib.cbvh_stream_scratch_size(_STREAM_BATCH)

        def run(begin: int, end: int) -> None:
            scratch = ffi.new("char[]", scratch_size)
            code = lib.cbvhpy_raycast(handle, rays, begin, end, pointer("cbvh_hit *", records),
                                      pointer("cbvhpy_details *", table), pointer("float *", normal),
                                      pointer("uint32_t *", material if with_materials else None), scratch,
                                      scratch_size)
            raise_for(code, None, "%d rays" % (end - begin))

        _run_parts(count, threads, run)
        return Hits(records["tri"], records["t"], records["u"], records["v"], normal, material)

    def occluded(self, origins: ArrayLike, directions: ArrayLike, tmin: ArrayLike = 0.0,
                 tmax: ArrayLike = np.inf, *, threads: int = 1) -> np.ndarray:
        """Whether each ray hits any triangle in [tmin, tmax] (bool array; cbvh_occluded's answers)."""
        rays, keep_alive, count = self._rays(origins, directions, tmin, tmax)
        out = np.empty(count, np.uint8)
        handle = self._handle()
        scratch_size = lib.cbvh_stream_scratch_size(_STREAM_BATCH)

        def run(begin: int, end: int) -> None:
            scratch = ffi.new("char[]", scratch_size)
            raise_for(lib.cbvhpy_occluded(handle, rays, begin, end, pointer("uint8_t *", out), scratch, scratch_size),
                      None, "%d rays" % (end - begin))

        _run_parts(count, threads, run)
        return out.view(bool)

    # -- shapes -----------------------------------------------------------------------------------------

    @staticmethod
    def _shapes(kind: int, vectors: Dict[str, np.ndarray], scalars: Dict[str, np.ndarray]) -> np.ndarray:
        shapes = np.zeros(_batch_size(vectors, scalars), SHAPE)
        shapes["kind"] = kind
        for field, value in {**vectors, **scalars}.items():
            shapes[field] = value
        return shapes

    @classmethod
    def _sphere(cls, centers: ArrayLike, radius: ArrayLike) -> np.ndarray:
        return cls._shapes(lib.CBVH_SHAPE_SPHERE, {"center": _vectors("centers", centers)},
                           {"radius": _scalars("radius", radius)})

    @classmethod
    def _capsule(cls, p0: ArrayLike, p1: ArrayLike, radius: ArrayLike) -> np.ndarray:
        return cls._shapes(lib.CBVH_SHAPE_CAPSULE, {"p0": _vectors("p0", p0), "p1": _vectors("p1", p1)},
                           {"radius": _scalars("radius", radius)})

    @classmethod
    def _box(cls, centers: ArrayLike, half_extents: ArrayLike, rotations: Optional[ArrayLike]) -> np.ndarray:
        vectors = {"center": _vectors("centers", centers), "half_extent": _vectors("half_extents", half_extents)}
        if rotations is not None:
            vectors["rotation"] = _vectors("rotations", rotations, 4)
        return cls._shapes(lib.CBVH_SHAPE_BOX, vectors, {})

    def sweep(self, shapes: np.ndarray, deltas: ArrayLike, *, threads: int = 1) -> SweepHits:
        """First contacts of `shapes` (an array of dtype cbvh.SHAPE) moved by `deltas` (cbvh_sweep_with)."""
        motion = np.ascontiguousarray(np.broadcast_to(_vectors("deltas", deltas), (len(shapes), 3)))
        shapes = np.ascontiguousarray(shapes, SHAPE)
        records = np.empty(len(shapes), SWEEP_RECORD)
        handle = self._handle()

        def run(begin: int, end: int) -> None:
            failed = ffi.new("size_t *")
            code = lib.cbvhpy_sweeps(handle, pointer("cbvh_shape *", shapes[begin:end]),
                                     pointer("float *", motion[begin:end]), end - begin,
                                     pointer("cbvh_sweep_record *", records[begin:end]), failed)
            raise_for(code, None, "sweep %d: the shape or its motion is invalid (every value finite, radii and "
                                  "half extents >= 0)" % (begin + failed[0]))

        _run_parts(len(shapes), threads, run)
        return SweepHits(records["tri"].copy(), records["t"].copy(), records["point"].copy(),
                         records["normal"].copy(), records["depth"].copy(), records["material"].copy())

    def sweep_sphere(self, centers: ArrayLike, radius: ArrayLike, deltas: ArrayLike, *, threads: int = 1) -> SweepHits:
        """Spheres moved from `centers` by `deltas`."""
        return self.sweep(self._sphere(centers, radius), deltas, threads=threads)

    def sweep_capsule(self, p0: ArrayLike, p1: ArrayLike, radius: ArrayLike, deltas: ArrayLike,
                      *, threads: int = 1) -> SweepHits:
        """Capsules (segment p0-p1, radius) moved by `deltas`."""
        return self.sweep(self._capsule(p0, p1, radius), deltas, threads=threads)

    def sweep_box(self, centers: ArrayLike, half_extents: ArrayLike, deltas: ArrayLike,
                  rotations: Optional[ArrayLike] = None, *, threads: int = 1) -> SweepHits:
        """Boxes (center, half extents, optional quaternions x, y, z, w turning their axes) moved by `deltas`."""
        return self.sweep(self._box(centers, half_extents, rotations), deltas, threads=threads)

    def _ragged(self, shapes: np.ndarray, record: np.dtype, threads: int) -> Tuple[np.ndarray, np.ndarray]:
        shapes = np.ascontiguousarray(shapes, SHAPE)
        handle = self._handle()
        contacts = record == CONTACT

        def run(begin: int, end: int) -> Tuple[np.ndarray, np.ndarray]:
            count = end - begin
            part = shapes[begin:end]
            offsets = np.zeros(count + 1, np.uint64)
            out = np.empty(max(64, 4 * count), record)
            state = ffi.new("size_t[3]")  # the query, its first triangle still to write, records written
            while True:
                code = lib.cbvhpy_overlaps(handle, pointer("cbvh_shape *", part), count, state, state + 1,
                                           ffi.NULL if contacts else pointer("uint32_t *", out),
                                           pointer("cbvh_contact *", out) if contacts else ffi.NULL,
                                           len(out), state + 2, pointer("uint64_t *", offsets))
                raise_for(code, None, "shape %d: invalid (every value finite, radii and half extents >= 0)"
                          % (begin + state[0]))
                if state[0] == count:
                    return offsets, out[:state[2]]
                grown = np.empty(2 * len(out), record)
                grown[:state[2]] = out[:state[2]]
                out = grown

        return _join_ragged(_run_parts(len(shapes), threads, run))

    def overlap(self, shapes: np.ndarray, *, threads: int = 1) -> Overlaps:
        """The triangles each of `shapes` (dtype cbvh.SHAPE) overlaps (exact tests; cbvh_overlap_with)."""
        return Overlaps(*self._ragged(shapes, np.dtype(np.uint32), threads))

    def overlap_sphere(self, centers: ArrayLike, radius: ArrayLike, *, threads: int = 1) -> Overlaps:
        return self.overlap(self._sphere(centers, radius), threads=threads)

    def overlap_capsule(self, p0: ArrayLike, p1: ArrayLike, radius: ArrayLike, *, threads: int = 1) -> Overlaps:
        return self.overlap(self._capsule(p0, p1, radius), threads=threads)

    def overlap_box(self, centers: ArrayLike, half_extents: ArrayLike, rotations: Optional[ArrayLike] = None,
                    *, threads: int = 1) -> Overlaps:
        return self.overlap(self._box(centers, half_extents, rotations), threads=threads)

    def contacts(self, shapes: np.ndarray, *, threads: int = 1) -> Contacts:
        """Contacts of each of `shapes` with every triangle it overlaps (cbvh_contacts_with)."""
        offsets, records = self._ragged(shapes, CONTACT, threads)
        return Contacts(offsets, records["tri"].copy(), records["depth"].copy(), records["normal"].copy(),
                        records["point"].copy())

    def contacts_sphere(self, centers: ArrayLike, radius: ArrayLike, *, threads: int = 1) -> Contacts:
        return self.contacts(self._sphere(centers, radius), threads=threads)

    def contacts_capsule(self, p0: ArrayLike, p1: ArrayLike, radius: ArrayLike, *, threads: int = 1) -> Contacts:
        return self.contacts(self._capsule(p0, p1, radius), threads=threads)

    def contacts_box(self, centers: ArrayLike, half_extents: ArrayLike, rotations: Optional[ArrayLike] = None,
                     *, threads: int = 1) -> Contacts:
        return self.contacts(self._box(centers, half_extents, rotations), threads=threads)


def open(source: Union[str, "os.PathLike[str]", bytes, bytearray, memoryview], *,
         expand_triangles: bool = False) -> File:
    """Opens a cbvh file from a path or bytes (see File)."""
    return File(source, expand_triangles=expand_triangles)
