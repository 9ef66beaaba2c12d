"""test_queries.py: every query of cbvh.File against the numpy double-precision brute force of reference.py,
on small meshes (a sphere, a triangle soup, a quantized binary-layout soup). Queries whose answer turns on
less than a rounding error (a ray through an edge, a shape that just touches) are left out and counted."""
import numpy as np
import pytest

import cbvh
import reference

EDGE = 1e-6  # how near an edge (barycentric) or a boundary (relative distance) an answer is left out


def random_rays(scene, count, seed):
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(count, 3))
    origins = -directions / np.linalg.norm(directions, axis=1, keepdims=True) * 2.5 * scene.extent
    origins[: count // 4] = rng.uniform(-0.5, 0.5, (count // 4, 3)) * scene.extent  # from inside
    directions = rng.uniform(-0.8, 0.8, (count, 3)) * scene.extent - origins
    tmin = np.where(rng.random(count) < 0.2, rng.uniform(0, 0.5, count), 0.0)
    tmax = np.where(rng.random(count) < 0.3, rng.uniform(0.5, 1.5, count), np.inf)
    return origins.astype(np.float32), directions.astype(np.float32), tmin.astype(np.float32), tmax.astype(np.float32)


def test_raycast_and_occluded_match_brute_force(scene):
    origins, directions, tmin, tmax = random_rays(scene, 600, 7)
    hits = scene.file.raycast(origins, directions, tmin, tmax)
    occluded = scene.file.occluded(origins, directions, tmin, tmax)
    normals = reference.face_normals(scene.tris)
    checked = hit_count = 0
    for i in range(len(origins)):
        t, u, v, margin = reference.ray_triangles(origins[i], directions[i], scene.tris)
        near_edge = np.abs(margin) < EDGE
        t_all = np.where(np.isfinite(t), t, 0)
        near_bound = np.isfinite(t) & ((np.abs(t_all - tmin[i]) < EDGE * (1 + t_all)) |
                                       (np.abs(t_all - tmax[i]) < EDGE * (1 + t_all)))
        if near_edge.any() or near_bound.any():
            continue
        checked += 1
        inside = np.isfinite(t) & (t >= tmin[i]) & (t <= tmax[i])
        assert occluded[i] == inside.any(), "ray %d" % i
        if not inside.any():
            assert hits.tri[i] == cbvh.NO_HIT and hits.t[i] == np.inf, "ray %d: cbvh hit, brute force missed" % i
            continue
        hit_count += 1
        best = np.min(t[inside])
        tri = int(hits.tri[i])
        assert tri != cbvh.NO_HIT, "ray %d: cbvh missed, brute force hit at t=%g" % (i, best)
        assert hits.t[i] == pytest.approx(best, rel=1e-5, abs=1e-6)
        assert t[tri] == pytest.approx(best, rel=1e-5, abs=1e-6), "ray %d: triangle %d is not the nearest" % (i, tri)
        assert (hits.u[i], hits.v[i]) == pytest.approx((u[tri], v[tri]), abs=1e-4)
        assert hits.normal[i] == pytest.approx(normals[tri], abs=1e-5)
        assert hits.material[i] == scene.materials[tri]
    assert checked > 0.95 * len(origins) and hit_count > 0.3 * len(origins), (checked, hit_count)


def shape_queries(scene, count, seed):
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-1.1, 1.1, (count, 3)) * scene.extent
    radius = rng.uniform(0.02, 0.3, count) * scene.extent
    half = rng.uniform(0.02, 0.3, (count, 3)) * scene.extent
    rotations = rng.normal(size=(count, 4))
    rotations[: count // 3] = 0  # axis-aligned boxes too
    other_ends = centers + rng.normal(0, 0.3, (count, 3)) * scene.extent
    return (centers.astype(np.float32), radius.astype(np.float32), half.astype(np.float32),
            rotations.astype(np.float32), other_ends.astype(np.float32))


def ragged_sets(result):
    return [set(result.tri[result.offsets[i]:result.offsets[i + 1]].tolist()) for i in range(len(result.offsets) - 1)]


def assert_same_sets(found, distances, scale, what):
    """found: the ids cbvh reports; distances: the brute force's, <= 0 overlapping. Near-zero ones may go
    either way."""
    sure = set(np.nonzero(distances < -EDGE * scale)[0].tolist())
    possible = set(np.nonzero(distances <= EDGE * scale)[0].tolist())
    assert sure <= found <= possible, "%s: missing %s, extra %s" % (what, sorted(sure - found), sorted(found - possible))


def test_overlaps_match_brute_force(scene):
    centers, radius, half, rotations, ends = shape_queries(scene, 90, 11)
    spheres = ragged_sets(scene.file.overlap_sphere(centers, radius))
    capsules = ragged_sets(scene.file.overlap_capsule(centers, ends, radius))
    boxes = ragged_sets(scene.file.overlap_box(centers, half, rotations))
    touched = 0
    for i in range(len(centers)):
        s = scene.extent
        assert_same_sets(spheres[i], reference.point_distances(centers[i], scene.tris) - radius[i], s, "sphere %d" % i)
        assert_same_sets(capsules[i], reference.segment_distances(centers[i], ends[i], scene.tris) - radius[i], s,
                         "capsule %d" % i)
        assert_same_sets(boxes[i], reference.box_separation(centers[i], half[i], scene.tris, rotations[i]), s,
                         "box %d" % i)
        touched += bool(spheres[i]) + bool(capsules[i]) + bool(boxes[i])
    assert touched > len(centers) // 2  # the queries are not all misses


def test_contacts_match_brute_force(scene):
    centers, radius, half, rotations, ends = shape_queries(scene, 60, 12)
    spheres = scene.file.contacts_sphere(centers, radius)
    capsules = scene.file.contacts_capsule(centers, ends, radius)
    boxes = scene.file.contacts_box(centers, half, rotations)
    assert ragged_sets(spheres) == ragged_sets(scene.file.overlap_sphere(centers, radius))
    assert ragged_sets(boxes) == ragged_sets(scene.file.overlap_box(centers, half, rotations))
    tol = 1e-4 * scene.extent
    for i in range(len(centers)):
        for k in range(spheres.offsets[i], spheres.offsets[i + 1]):
            tri = scene.tris[spheres.tri[k]][None]
            nearest = reference.closest_on_triangles(centers[i].astype(np.float64), tri)[0]
            distance = np.linalg.norm(centers[i] - nearest)
            assert spheres.point[k] == pytest.approx(nearest, abs=tol)
            assert spheres.depth[k] == pytest.approx(radius[i] - distance, abs=tol)
            if distance > 1e-3 * scene.extent:
                assert spheres.normal[k] == pytest.approx((centers[i] - nearest) / distance, abs=1e-3)
        for k in range(capsules.offsets[i], capsules.offsets[i + 1]):
            tri = scene.tris[capsules.tri[k]][None]
            distance = reference.segment_distances(centers[i], ends[i], tri)[0]
            if distance > 0:
                assert capsules.depth[k] == pytest.approx(radius[i] - distance, abs=tol)
            else:  # the segment crosses the triangle: lifted radius above its plane, on the nearer side
                n = reference.face_normals(tri)[0]
                heights = np.array([np.dot(centers[i] - tri[0, 0], n), np.dot(ends[i] - tri[0, 0], n)])
                lifts = [radius[i] - heights.min(), radius[i] + heights.max()]
                assert capsules.depth[k] == pytest.approx(min(lifts), abs=tol)
                assert capsules.normal[k] == pytest.approx(n if lifts[0] <= lifts[1] else -n, abs=1e-4)
        for k in range(boxes.offsets[i], boxes.offsets[i + 1]):
            tri = scene.tris[boxes.tri[k]][None]
            depth, normal = float(boxes.depth[k]), boxes.normal[k].astype(np.float64)
            assert depth >= 0 and np.linalg.norm(normal) == pytest.approx(1, abs=1e-5)
            # Moving the box by depth * normal leaves it touching at most; by less it still overlaps.
            moved = lambda d: reference.box_separation(centers[i] + d * normal, half[i], tri, rotations[i])[0]
            assert moved(depth + tol) > 0
            if depth > 2 * tol:
                assert moved(depth - tol) < 0
            local = boxes.point[k] - centers[i]
            if np.any(rotations[i]):
                local = local @ reference.quaternion_matrix(rotations[i])
            assert np.all(np.abs(local) <= half[i] + tol)


def first_contact(gap, steps=100):
    """The brute force's first t in [0, 1] where gap(t) <= 0 (sampled, then bisected), or None; and the
    sampled gaps."""
    ts = np.linspace(0, 1, steps + 1)
    gaps = np.array([gap(t) for t in ts])
    touching = np.nonzero(gaps <= 0)[0]
    if len(touching) == 0:
        return None, ts, gaps
    k = touching[0]
    if k == 0:
        return 0.0, ts, gaps
    lo, hi = ts[k - 1], ts[k]
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if gap(mid) <= 0 else (mid, hi)
    return hi, ts, gaps


@pytest.mark.parametrize("kind", ["sphere", "capsule", "box"])
def test_sweeps_match_brute_force(scene, kind):
    centers, radius, half, rotations, ends = shape_queries(scene, 20, 13)
    rng = np.random.default_rng(14)
    deltas = (rng.uniform(-0.5, 0.5, (len(centers), 3)) * scene.extent - centers * 1.5).astype(np.float32)
    if kind == "sphere":
        result = scene.file.sweep_sphere(centers, radius, deltas)
        gaps = lambda i, t, tris: reference.point_distances(centers[i] + t * deltas[i], tris) - radius[i]
    elif kind == "capsule":
        result = scene.file.sweep_capsule(centers, ends, radius, deltas)
        gaps = lambda i, t, tris: reference.segment_distances(centers[i] + t * deltas[i], ends[i] + t * deltas[i],
                                                             tris) - radius[i]
    else:
        result = scene.file.sweep_box(centers, half, deltas, rotations)
        gaps = lambda i, t, tris: reference.box_separation(centers[i] + t * deltas[i], half[i], tris, rotations[i])
    tol = 1e-4 * scene.extent
    contacts = 0
    for i in range(len(centers)):
        t_brute, ts, sampled = first_contact(lambda t: gaps(i, t, scene.tris).min())
        if t_brute == 0.0:
            continue  # starts overlapping: t = 0 either way, checked below only for a contact reported
        tri = int(result.tri[i])
        if tri == cbvh.NO_HIT:
            assert t_brute is None and sampled.min() > -tol, "%s %d: cbvh missed, brute force t=%s" % (kind, i, t_brute)
            continue
        contacts += 1
        t = float(result.t[i])
        # At cbvh's t the shape touches its triangle, and no triangle was touched earlier.
        assert abs(gaps(i, t, scene.tris[tri][None])[0]) < tol, "%s %d" % (kind, i)
        assert sampled[ts < t - 1e-4].min(initial=np.inf) > -tol, "%s %d: an earlier contact" % (kind, i)
        if t_brute is not None:
            assert t <= t_brute + 1e-4
        assert result.material[i] == scene.materials[tri]
        on_plane = np.dot(result.point[i] - scene.tris[tri][0], reference.face_normals(scene.tris[tri][None])[0])
        assert abs(on_plane) < tol
    assert contacts >= 4


def test_single_query_values_broadcast(scene):
    """One origin for many directions, one radius for many centers: the same as the spelled-out arrays."""
    origins, directions, _, _ = random_rays(scene, 50, 3)
    a = scene.file.raycast(origins[0], directions)
    b = scene.file.raycast(np.repeat(origins[:1], 50, axis=0), directions)
    assert np.array_equal(a.tri, b.tri) and np.array_equal(a.t, b.t)
    centers, radius, _, _, _ = shape_queries(scene, 20, 4)
    c = scene.file.overlap_sphere(centers, 0.2)
    d = scene.file.overlap_sphere(centers, np.full(20, 0.2))
    assert np.array_equal(c.offsets, d.offsets) and np.array_equal(c.tri, d.tri)
