"""raycast_throughput.py: batched raycast from numpy (cbvh.File.raycast: rays taken from the arrays, the
stream, with and without the hits' normals and materials; and with them on a newly opened file, whose first
such call makes the file's table of triangle normals) against the C library's own call on the same rays
(raycast_loop.c: cbvh_raycast_stream_scratch on the same records, already in memory), single thread. Times
are the process's CPU time (a machine busy with other work stretches wall time, not CPU time).

    python python/benchmarks/raycast_throughput.py MESH_OR_CBVH [--rays 1000000] [--repeats 5]

MESH_OR_CBVH: a .cbvh file, or a mesh cooked first with cbvh.cook_file. Builds raycast_loop.c with cc
against the library the package was built from (python/build/native, or --library-build DIR).
"""
import argparse
import os
import subprocess
import tempfile
import time

import numpy as np

import cbvh

HERE = os.path.dirname(os.path.abspath(__file__))
REPOSITORY = os.path.dirname(os.path.dirname(HERE))


def rays_at(f: cbvh.File, count: int, seed: int = 1):
    """Rays from a sphere around the mesh towards random points of its bounds (about half hit)."""
    rng = np.random.default_rng(seed)
    low, high = np.array(f.info["bounds_min"]), np.array(f.info["bounds_max"])
    directions = rng.normal(size=(count, 3))
    origins = (low + high) / 2 - directions / np.linalg.norm(directions, axis=1, keepdims=True) * np.max(high - low)
    return origins.astype(np.float32), (rng.uniform(low, high, (count, 3)) - origins).astype(np.float32)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh")
    parser.add_argument("--rays", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--library-build", default=os.path.join(REPOSITORY, "python", "build", "native"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.mesh
        if not path.endswith(".cbvh"):
            path = os.path.join(tmp, "mesh.cbvh")
            cbvh.cook_file(args.mesh, path)
        f = cbvh.open(path)
        origins, directions = rays_at(f, args.rays)
        records = np.zeros(args.rays, cbvh.RAY)
        records["org"], records["dir"], records["tmax"] = origins, directions, np.inf
        records.tofile(os.path.join(tmp, "rays.bin"))
        loop = os.path.join(tmp, "raycast_loop")
        subprocess.run(["cc", "-O2", "-o", loop, os.path.join(HERE, "raycast_loop.c"),
                        "-I", os.path.join(REPOSITORY, "include"), "-I", os.path.join(args.library_build, "include"),
                        os.path.join(args.library_build, "lib", ".libs", "libcbvh.a"), "-lz", "-lm", "-lpthread"],
                       check=True)
        best = {"C": np.inf, "details": np.inf, "plain": np.inf, "first": np.inf}
        for _ in range(args.repeats):  # alternated, so that a busy moment of the machine hurts all alike
            out = subprocess.run([loop, path, os.path.join(tmp, "rays.bin"), "1"], check=True, capture_output=True,
                                 text=True).stdout.split()
            best["C"] = min(best["C"], float(out[0]))
            for name, details in (("details", True), ("plain", False)):
                t0 = time.process_time()
                hits = f.raycast(origins, directions, details=details)
                best[name] = min(best[name], time.process_time() - t0)
            fresh = cbvh.open(path)  # its first raycast with details also makes the file's details table
            t0 = time.process_time()
            fresh.raycast(origins, directions)
            best["first"] = min(best["first"], time.process_time() - t0)
            fresh.close()
        assert int(out[1]) == int(hits.tri.astype(np.uint64).sum()), "the C loop and the package disagree"
        print("%s: %d triangles, %d rays, %.1f%% hit, best of %d" % (
            args.mesh, f.info["triangle_count"], args.rays, 100 * np.mean(hits.hit), args.repeats))
        rate = {name: args.rays / seconds / 1e6 for name, seconds in best.items()}
        print("C library (cbvh_raycast_stream_scratch, one call):  %.3f s, %.2f MRays/s" % (best["C"], rate["C"]))
        print("cbvh.File.raycast(details=False), from numpy:        %.3f s, %.2f MRays/s, %.2fx C" % (
            best["plain"], rate["plain"], rate["plain"] / rate["C"]))
        print("cbvh.File.raycast() with normals and materials:      %.3f s, %.2f MRays/s, %.2fx C" % (
            best["details"], rate["details"], rate["details"] / rate["C"]))
        print("the same, first call on a newly opened file:         %.3f s, %.2f MRays/s, %.2fx C" % (
            best["first"], rate["first"], rate["first"] / rate["C"]))


if __name__ == "__main__":
    main()
