"""vs_trimesh.py: cbvh against trimesh's ray intersectors on the same mesh and rays, single thread: Embree
through Python (trimesh.ray.ray_pyembree, needs embreex) and trimesh's pure-numpy intersector
(trimesh.ray.ray_triangle, on a sample of the rays: it is slow). Closest hit per ray: which triangle, how
often the answers agree, and rays per second of the process's CPU time (a machine busy with other work
stretches wall time, not CPU time; every intersector here runs on the calling thread).

    pip install trimesh embreex
    python python/benchmarks/vs_trimesh.py MESH [MESH ...] [--rays 1000000] [--repeats 3]
"""
import argparse
import os
import tempfile
import time

import numpy as np
import trimesh

import cbvh

try:
    from trimesh.ray import ray_pyembree
except ImportError:  # no embreex
    ray_pyembree = None


def best_time(run, repeats):
    best, result = np.inf, None
    for _ in range(repeats):
        t0 = time.process_time()
        result = run()
        best = min(best, time.process_time() - t0)
    return best, result


def agreement(cbvh_tri, other_tri):
    """The share of rays with the same closest triangle (or both a miss)."""
    ours = np.where(cbvh_tri == cbvh.NO_HIT, -1, cbvh_tri.astype(np.int64))
    return float(np.mean(ours == other_tri))


def compare(path, count, repeats, pure_rays):
    # Both take the triangles cbvh's queries see (imported by `cbvh cook`), in the same order: the ids agree.
    with tempfile.TemporaryDirectory() as tmp:
        cbvh.cook_file(path, os.path.join(tmp, "mesh.cbvh"))
        f = cbvh.open(os.path.join(tmp, "mesh.cbvh"))
    triangles = f.triangles.reshape(-1, 3)
    faces = np.arange(len(triangles)).reshape(-1, 3)
    mesh = trimesh.Trimesh(vertices=triangles, faces=faces, process=False)
    rng = np.random.default_rng(1)
    low, high = mesh.bounds
    directions = rng.normal(size=(count, 3))
    origins = (low + high) / 2 - directions / np.linalg.norm(directions, axis=1, keepdims=True) * np.max(high - low)
    directions = rng.uniform(low, high, (count, 3)) - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)  # trimesh wants unit directions
    o32, d32 = origins.astype(np.float32), directions.astype(np.float32)
    print("%s: %d triangles, %d rays, best of %d" % (path, len(faces), count, repeats))
    runs = {"cbvh": lambda: f.raycast(o32, d32, details=False), "details": lambda: f.raycast(o32, d32)}
    if ray_pyembree is not None:
        embree = ray_pyembree.RayMeshIntersector(mesh)
        runs["embree"] = lambda: embree.intersects_first(origins, directions)
    best = {name: np.inf for name in runs}
    answers = {}
    for round_ in range(repeats + 1):  # the first round warms up; rounds alternate so that a busy moment hurts all
        for name, run in runs.items():
            seconds, answers[name] = best_time(run, 1)
            if round_ > 0:
                best[name] = min(best[name], seconds)
    hits = answers["cbvh"]
    print("  cbvh raycast:                      %8.3f s  %7.2f MRays/s  %.1f%% hit" % (
        best["cbvh"], count / best["cbvh"] / 1e6, 100 * np.mean(hits.hit)))
    print("  cbvh raycast, normals, materials:  %8.3f s  %7.2f MRays/s" % (best["details"], count / best["details"] / 1e6))
    if "embree" in runs:
        print("  trimesh + embreex intersects_first:%8.3f s  %7.2f MRays/s  same triangle %.4f  (cbvh %.2fx as fast)" % (
            best["embree"], count / best["embree"] / 1e6, agreement(hits.tri, answers["embree"]),
            best["embree"] / best["cbvh"]))
    else:
        print("  trimesh + embreex: embreex is not installed")
    n = min(pure_rays, count)
    pure = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    seconds, tri = best_time(lambda: pure.intersects_first(origins[:n], directions[:n]), 1)
    print("  trimesh ray_triangle (%d rays):    %8.3f s  %7.0f rays/s   same triangle %.4f" % (
        n, seconds, n / seconds, agreement(hits.tri[:n], tri)))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("meshes", nargs="+")
    parser.add_argument("--rays", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--pure-rays", type=int, default=10_000, help="rays for trimesh's numpy intersector")
    args = parser.parse_args()
    for path in args.meshes:
        compare(path, args.rays, args.repeats, args.pure_rays)


if __name__ == "__main__":
    main()
