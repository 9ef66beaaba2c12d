"""reference.py: brute-force geometry in numpy double precision, every triangle tested, for the tests to
check cbvh's answers against (nothing here comes from cbvh)."""
import numpy as np


def sphere_mesh(subdivisions: int = 2, seed: int = 1):
    """An icosphere with its vertices pushed in and out at random, and random material ids."""
    t = (1 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11],
         [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    vertices = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        middle = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                p = vertices[a] + vertices[b]
                vertices.append(p / np.linalg.norm(p))
                middle[key] = len(vertices) - 1
            return middle[key]

        f = [g for a, b, c in f for g in ([a, mid(a, b), mid(c, a)], [b, mid(b, c), mid(a, b)],
                                          [c, mid(c, a), mid(b, c)], [mid(a, b), mid(b, c), mid(c, a)])]
    rng = np.random.default_rng(seed)
    vertices = np.array(vertices) * rng.uniform(0.8, 1.2, (len(vertices), 1))
    triangles = np.array(f, np.uint32)
    return vertices.astype(np.float32), triangles, rng.integers(0, 5, len(triangles)).astype(np.uint32)


def triangle_soup(count: int = 200, seed: int = 2):
    """Random triangles of assorted sizes in [-1, 1]^3 (unshared vertices)."""
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-1, 1, (count, 1, 3))
    corners = centers + rng.normal(0, 0.15, (count, 3, 3)) * rng.uniform(0.2, 1.5, (count, 1, 1))
    return (corners.reshape(-1, 3).astype(np.float32), np.arange(3 * count, dtype=np.uint32).reshape(-1, 3),
            rng.integers(0, 7, count).astype(np.uint32))


def corners(vertices, triangles):
    """(T, 3, 3) float64 corners."""
    return np.asarray(vertices, np.float64)[np.asarray(triangles, np.int64)]


def face_normals(tris):
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def ray_triangles(origin, direction, tris):
    """Möller-Trumbore for one ray against every triangle: t, u, v per triangle (t = inf on a miss) and the
    smallest of u, v, 1-u-v (how far inside the edges the ray passes; near 0: an edge case)."""
    o = np.asarray(origin, np.float64)
    d = np.asarray(direction, np.float64)
    e1 = tris[:, 1] - tris[:, 0]
    e2 = tris[:, 2] - tris[:, 0]
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - tris[:, 0]
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
    margin = np.minimum(np.minimum(u, v), 1 - u - v)
    ok = (det != 0) & (margin >= 0)
    return np.where(ok, t, np.inf), u, v, np.where(det != 0, margin, -np.inf)


def closest_on_segments(p, a, b):
    """Closest points on segments a-b (broadcast) to points p."""
    ab = b - a
    denom = np.einsum("...i,...i->...", ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(np.einsum("...i,...i->...", p - a, ab) / denom, 0, 1)
    s = np.where(denom > 0, s, 0)
    return a + s[..., None] * ab


def closest_on_triangles(p, tris):
    """The point of each triangle nearest p: its projection on the plane when inside, else the nearest
    point of the three edges."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    projected = p - (np.einsum("ij,ij->i", p - a, n) / nn)[:, None] * n
    inside = np.ones(len(tris), bool)
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(y - x, projected - x), n) >= 0
    candidates = np.stack([closest_on_segments(p, x, y) for x, y in ((a, b), (b, c), (c, a))])
    distances = np.linalg.norm(candidates - p, axis=-1)
    nearest_edge = candidates[np.argmin(distances, axis=0), np.arange(len(tris))]
    return np.where(inside[:, None], projected, nearest_edge)


def point_distances(p, tris):
    return np.linalg.norm(closest_on_triangles(np.asarray(p, np.float64), tris) - p, axis=-1)


def segment_segment_distance(p0, p1, q0, q1):
    """Distance between segments p0-p1 and q0-q1 (q's broadcast over triangles' edges), Ericson's clamping."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...i,...i->...", d1, d1) * np.ones(d2.shape[:-1])
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-300, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = (b * s + f) / e
        s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
        t = np.clip(t, 0, 1)
    s = np.where(a > 0, s, 0)
    closest_p = p0 + s[..., None] * d1
    closest_q = q0 + t[..., None] * d2
    return np.linalg.norm(closest_p - closest_q, axis=-1)


def segment_distances(p0, p1, tris):
    """Distance from the segment p0-p1 to each triangle (0 where it crosses it)."""
    p0 = np.asarray(p0, np.float64)
    p1 = np.asarray(p1, np.float64)
    d = np.minimum(point_distances(p0, tris), point_distances(p1, tris))
    for i, j in ((0, 1), (1, 2), (2, 0)):
        d = np.minimum(d, segment_segment_distance(p0, p1, tris[:, i], tris[:, j]))
    if np.any(p1 != p0):
        t, _, _, _ = ray_triangles(p0, p1 - p0, tris)
        d = np.where((t >= 0) & (t <= 1), 0.0, d)
    return d


def quaternion_matrix(q):
    x, y, z, w = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def box_separation(center, half, tris, rotation=None):
    """Separating-axis test of a box against each triangle: the largest gap over the 13 axes (box faces,
    triangle normal, edge crosses), > 0 when they are apart, <= 0 when they overlap."""
    local = tris - np.asarray(center, np.float64)
    if rotation is not None and np.any(rotation):
        local = local @ quaternion_matrix(rotation)  # row vectors: R^T p
    h = np.asarray(half, np.float64)
    edges = [local[:, 1] - local[:, 0], local[:, 2] - local[:, 1], local[:, 0] - local[:, 2]]
    axes = [np.broadcast_to(np.eye(3)[k], local[:, 0].shape) for k in range(3)]
    axes.append(np.cross(edges[0], edges[1]))
    axes += [np.cross(np.eye(3)[k], e) for k in range(3) for e in edges]
    gap = np.full(len(tris), -np.inf)
    for axis in axes:
        length = np.linalg.norm(axis, axis=-1)
        usable = length > 1e-12 * (1 + np.abs(local).max())
        unit = axis / np.where(usable, length, 1)[:, None]
        projections = np.einsum("tvi,ti->tv", local, unit)
        radius = np.abs(unit) @ h
        axis_gap = np.maximum(projections.min(axis=1) - radius, -radius - projections.max(axis=1))
        gap = np.where(usable, np.maximum(gap, axis_gap), gap)
    return gap
