"""cook.py: cooking meshes into cbvh files, from numpy arrays (the library's cbvh_cook) or from mesh files
(the `cbvh cook` command, whose assimp importer and options it shares)."""
import json
import os
import shutil
import subprocess
import time
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ._lib import CbvhError, ffi, lib, pointer, raise_for

PathLike = Union[str, "os.PathLike[str]"]
_LAYOUTS = {"wide4": lib.CBVH_LAYOUT_WIDE4, "binary": lib.CBVH_LAYOUT_BINARY}
# The names `cbvh cook --json` gives the sections (by type, the ancillary bit left out) and the cook's phases.
_SECTION_NAMES = {lib.CBVH_SECTION_NODES: "nodes", lib.CBVH_SECTION_TRIANGLES: "triangles",
                  lib.CBVH_SECTION_VERTICES: "vertices", lib.CBVH_SECTION_REMAP: "remap",
                  lib.CBVH_SECTION_MATERIALS: "materials",
                  lib.CBVH_SECTION_MATERIAL_NAMES & 0x7FFFFFFF: "material-names"}
_PHASE_NAMES = {lib.CBVH_PHASE_PREPARE: "prepare", lib.CBVH_PHASE_BUILD: "build", lib.CBVH_PHASE_LAYOUT: "layout",
                lib.CBVH_PHASE_WRITE: "write"}


class CookError(CbvhError):
    """A mesh file that `cbvh cook` could not cook: `status` is its exit status (1: the input is not a
    usable mesh, 2: usage or I/O error), `file` the file at fault, `message` what is wrong."""

    def __init__(self, status: int, file: str, message: str):
        self.status = status
        self.file = file
        super().__init__(None, "%s: %s" % (file, message))


def _apply_options(options, layout: str = "wide4", max_leaf_size: Optional[int] = None,
                   sah_bins: Optional[int] = None, traversal_cost: Optional[float] = None,
                   intersection_cost: Optional[float] = None, quantize_vertices: bool = False,
                   compress_level: int = 0, keep_remap: bool = True, keep_materials: bool = True) -> None:
    if layout not in _LAYOUTS:
        raise ValueError("layout must be one of %s, not %r" % (", ".join(_LAYOUTS), layout))
    options.layout = _LAYOUTS[layout]
    if max_leaf_size is not None:
        options.max_leaf_size = max_leaf_size
    if sah_bins is not None:
        options.sah_bins = sah_bins
    if traversal_cost is not None:
        options.traversal_cost = traversal_cost
    if intersection_cost is not None:
        options.intersection_cost = intersection_cost
    options.vertex_format = lib.CBVH_VERTEX_QUANTIZED16 if quantize_vertices else lib.CBVH_VERTEX_FLOAT32
    options.compress_level = compress_level
    options.keep_remap = int(bool(keep_remap))
    options.keep_materials = int(bool(keep_materials))


def _stats_report(st, total_seconds: float) -> Dict[str, Any]:
    """cbvh_cook_stats as a dict laid out as `cbvh cook --json`'s report, less what only the command knows
    (its input and output paths, the importer's dropped points and lines, material names, missing files,
    the import's seconds)."""
    per_triangle = 1.0 / st.triangles if st.triangles else 0.0
    sections = []
    for kind in range(lib.CBVH_SECTION_NODES, lib.CBVH_STATS_SECTION_TYPES):
        if st.section_size[kind]:
            sections.append({"name": _SECTION_NAMES.get(kind, "ancillary"),
                             "stored_bytes": st.section_stored_size[kind], "raw_bytes": st.section_size[kind],
                             "stored_bytes_per_triangle": st.section_stored_size[kind] * per_triangle,
                             "raw_bytes_per_triangle": st.section_size[kind] * per_triangle})
    return {
        "triangles": {"input": st.input_triangles, "kept": st.triangles, "dropped_degenerate": st.dropped_degenerate},
        "vertices": {"input": st.input_vertices, "flushed_coordinates": st.flushed_coordinates,
                     "kept": st.vertices, "max_error": st.vertex_max_error},
        "tree": {"nodes": st.nodes, "leaves": st.leaves, "depth": st.depth, "sah_cost": st.sah_cost},
        "file_size": st.file_size,
        "peak_memory": st.peak_memory,
        "bytes_per_triangle": st.file_size * per_triangle,
        "sections": sections,
        "seconds": dict({name: st.seconds[phase] for phase, name in _PHASE_NAMES.items()}, total=total_seconds),
    }


def cook(vertices: np.ndarray, triangles: np.ndarray, *, materials: Optional[np.ndarray] = None,
         material_names: Optional[Mapping[int, Union[str, Sequence[str]]]] = None, stats: bool = False,
         **options: Any) -> Union[bytes, Tuple[bytes, Dict[str, Any]]]:
    """Cooks a triangle mesh into a cbvh file held in bytes (deterministic: the same mesh and options give
    the same bytes). With stats=True returns (bytes, statistics): what the cook did (cbvh_cook_stats) as a
    dict laid out as cook_file's report (`cbvh cook --json`): triangles (input, kept, dropped_degenerate),
    vertices (input, flushed_coordinates, kept, max_error), tree (nodes, leaves, depth, sah_cost),
    file_size, peak_memory, bytes_per_triangle, sections and seconds (per phase, and total).

    vertices: (V, 3) positions (converted to float32); triangles: (T, 3) vertex indices; materials: (T,)
    material ids or None; material_names: {id: name or [names]}. Options (the library's defaults when
    left out): layout ("wide4" or "binary"), max_leaf_size, sah_bins, traversal_cost, intersection_cost,
    quantize_vertices, compress_level (0 raw, 1..9 zlib), keep_remap, keep_materials.
    Raises CbvhError naming the triangle or vertex at fault (NaN coordinates, indices out of range, no
    triangle left)."""
    positions = np.ascontiguousarray(vertices, dtype=np.float32)
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise ValueError("vertices must have shape (V, 3), not %s" % (positions.shape,))
    indices = np.asarray(triangles)
    if indices.ndim != 2 or indices.shape[1] != 3:
        raise ValueError("triangles must have shape (T, 3), not %s" % (indices.shape,))
    if indices.size and (indices.min() < 0 or indices.max() > 0xFFFFFFFF):
        raise ValueError("triangles hold an index out of 0..2^32-1")
    indices = np.ascontiguousarray(indices, dtype=np.uint32)
    material_ids = None
    if materials is not None:
        material_ids = np.ascontiguousarray(materials, dtype=np.uint32)
        if material_ids.shape != (len(indices),):
            raise ValueError("materials must have one id per triangle, shape (%d,)" % len(indices))

    cook_options = ffi.new("cbvh_cook_options *")
    raise_for(lib.cbvh_cook_options_init(cook_options, ffi.sizeof("cbvh_cook_options")))
    _apply_options(cook_options, **options)
    keep_alive = []
    if material_names:
        pairs = [(int(i), n) for i, names in material_names.items()
                 for n in ([names] if isinstance(names, str) else names)]
        table = ffi.new("cbvh_material_name[]", len(pairs))
        for k, (material_id, name) in enumerate(pairs):
            keep_alive.append(ffi.new("char[]", name.encode()))
            table[k].id = material_id
            table[k].name = keep_alive[-1]
        cook_options.material_names = table
        cook_options.material_name_count = len(pairs)

    mesh = ffi.new("cbvh_mesh *")
    mesh.positions = pointer("float *", positions)
    mesh.vertex_count = len(positions)
    mesh.position_stride = 0
    mesh.indices = pointer("uint32_t *", indices)
    mesh.triangle_count = len(indices)
    mesh.material_ids = pointer("uint32_t *", material_ids)
    data = ffi.new("void **")
    size = ffi.new("size_t *")
    err = ffi.new("cbvh_error *")
    cook_stats = ffi.new("cbvh_cook_stats *")
    raise_for(lib.cbvh_cook_stats_init(cook_stats, ffi.sizeof("cbvh_cook_stats")))
    start = time.perf_counter()
    raise_for(lib.cbvh_cook(mesh, cook_options, ffi.NULL, data, size, cook_stats, err), err)
    seconds = time.perf_counter() - start
    try:
        cooked = bytes(ffi.buffer(data[0], size[0]))
    finally:
        lib.cbvh_buffer_free(ffi.NULL, data[0])
    return (cooked, _stats_report(cook_stats, seconds)) if stats else cooked


def cbvh_command() -> str:
    """The `cbvh` command cook_file runs: the one built with this package, else $CBVH_COMMAND, else cbvh on
    PATH. Raises CbvhError when there is none (a package built without assimp)."""
    packaged = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin", "cbvh")
    for candidate in (packaged, os.environ.get("CBVH_COMMAND"), shutil.which("cbvh")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    raise CbvhError(lib.CBVH_ERROR_INVALID_ARGUMENT,
                    "cook_file runs the cbvh command, and there is none: this package was built without it (its "
                    "build needs libassimp-dev), no cbvh is on PATH and CBVH_COMMAND names none; cbvh.cook "
                    "cooks numpy arrays without it")


def cook_arguments(depfile: Optional[PathLike] = None, material_map: Optional[PathLike] = None,
                   select: Optional[str] = None, scale: Optional[float] = None, up_axis: Optional[str] = None,
                   max_memory: Optional[int] = None, layout: Optional[str] = None,
                   max_leaf_size: Optional[int] = None, sah_bins: Optional[int] = None,
                   traversal_cost: Optional[float] = None, intersection_cost: Optional[float] = None,
                   quantize_vertices: bool = False, compress_level: int = 0, keep_remap: bool = True,
                   keep_materials: bool = True) -> List[str]:
    """The `cbvh cook` options for cook_file's keyword arguments (named as cook()'s)."""
    flags = {"--depfile": depfile, "--material-map": material_map, "--select": select, "--scale": scale,
             "--up-axis": up_axis, "--max-memory": max_memory, "--layout": layout,
             "--leaf-size": max_leaf_size, "--bins": sah_bins, "--traversal-cost": traversal_cost,
             "--intersection-cost": intersection_cost}
    arguments = []
    for flag, value in flags.items():
        if value is not None:
            arguments += [flag, os.fspath(value) if isinstance(value, os.PathLike) else str(value)]
    if quantize_vertices:
        arguments.append("--quantize-vertices")
    if compress_level:
        arguments.append("--compress=%d" % compress_level)
    if not keep_remap:
        arguments.append("--no-remap")
    if not keep_materials:
        arguments.append("--no-materials")
    return arguments


def cook_file(path: PathLike, out_path: PathLike, **options: Any) -> Dict[str, Any]:
    """Cooks the mesh file at `path` (any format assimp reads, or gen:SCENE) into the cbvh file `out_path`
    with `cbvh cook`: the same importer, options and bytes. Options: cook()'s, and depfile, material_map,
    select, scale, up_axis, max_memory (`cbvh cook --help` says what each does). Returns the cook's
    statistics (the command's --json output); raises CookError when the asset does not cook."""
    command = [cbvh_command(), "cook", "--quiet", "--json"] + cook_arguments(**options)
    command += ["--", os.fspath(path), os.fspath(out_path)]
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        report = json.loads(run.stdout)
    except ValueError:
        report = None
    if run.returncode == 0 and isinstance(report, dict):
        return report
    if isinstance(report, dict) and "error" in report:
        error = report["error"]
        raise CookError(int(error.get("status", run.returncode)), str(error.get("file", path)),
                        str(error.get("message", "")))
    detail = run.stderr.strip() or "exit status %d" % run.returncode
    raise CookError(run.returncode if run.returncode > 0 else 2, os.fspath(path),
                    "cbvh cook failed: %s" % detail)
