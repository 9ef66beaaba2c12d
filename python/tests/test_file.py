"""test_file.py: the binding against the C tool (`cbvh raycast` on the same file), threads, corrupt and
truncated files, and errors."""
import os
import subprocess

import numpy as np
import pytest

import cbvh
import reference
from cbvh.cook import cbvh_command


def wuson_rays(f, count, seed):
    rng = np.random.default_rng(seed)
    low, high = np.array(f.info["bounds_min"]), np.array(f.info["bounds_max"])
    middle, size = (low + high) / 2, float(np.max(high - low))
    directions = rng.normal(size=(count, 3))
    origins = middle - directions / np.linalg.norm(directions, axis=1, keepdims=True) * size
    targets = rng.uniform(low, high, (count, 3))
    return origins.astype(np.float32), (targets - origins).astype(np.float32)


def test_same_answers_as_cbvh_raycast(wuson):
    """Bit for bit: the package's raycast and occluded against `cbvh raycast --binary` on the same file."""
    f = cbvh.open(wuson)
    origins, directions = wuson_rays(f, 5000, 1)
    tmax = np.where(np.arange(5000) % 3 == 0, np.float32(0.9), np.float32(np.inf)).astype(np.float32)
    records = np.zeros(5000, cbvh.RAY)
    records["org"], records["dir"], records["tmax"] = origins, directions, tmax
    run = subprocess.run([cbvh_command(), "raycast", "--binary", wuson], input=records.tobytes(),
                         capture_output=True, check=True)
    tool = np.frombuffer(run.stdout, cbvh.HIT)
    hits = f.raycast(origins, directions, 0, tmax)
    assert np.count_nonzero(hits.hit) > 1000
    assert np.array_equal(hits.tri, tool["tri"])
    hit = hits.hit
    for field in ("t", "u", "v"):
        assert np.array_equal(getattr(hits, field)[hit], tool[field][hit])
    run = subprocess.run([cbvh_command(), "raycast", "--binary", "--any", wuson], input=records.tobytes(),
                         capture_output=True, check=True)
    assert np.array_equal(f.occluded(origins, directions, 0, tmax), np.frombuffer(run.stdout, np.uint8) == 1)


def test_path_and_bytes_and_expanded_give_the_same_answers(wuson):
    with open(wuson, "rb") as source:
        data = source.read()
    files = [cbvh.open(wuson), cbvh.open(data), cbvh.open(wuson, expand_triangles=True)]
    assert files[2].info["expanded_bytes"] > 0 or files[0].info["expanded_bytes"] == 0
    origins, directions = wuson_rays(files[0], 2000, 2)
    answers = [f.raycast(origins, directions) for f in files]
    for other in answers[1:]:
        assert np.array_equal(answers[0].tri, other.tri) and np.array_equal(answers[0].t, other.t)


def test_threads_give_identical_answers(wuson):
    f = cbvh.open(wuson)
    origins, directions = wuson_rays(f, 20000, 3)
    one = f.raycast(origins, directions)
    rng = np.random.default_rng(4)
    low, high = np.array(f.info["bounds_min"]), np.array(f.info["bounds_max"])
    centers = rng.uniform(low, high, (3000, 3)).astype(np.float32)
    radius = np.float32(0.03 * np.max(high - low))
    deltas = rng.normal(0, 0.2 * np.max(high - low), (3000, 3)).astype(np.float32)
    queries = {
        "occluded": lambda n: f.occluded(origins, directions, threads=n),
        "sweep": lambda n: f.sweep_box(centers, [radius] * 3, deltas, threads=n),
        "overlap": lambda n: f.overlap_capsule(centers, centers + deltas, radius, threads=n),
        "contacts": lambda n: f.contacts_sphere(centers, 3 * radius, threads=n),
    }
    for threads in (2, 3, 8):
        many = f.raycast(origins, directions, threads=threads)
        for field in ("tri", "t", "u", "v", "normal", "material"):
            assert np.array_equal(getattr(one, field), getattr(many, field)), field
        for name, query in queries.items():
            a, b = query(1), query(threads)
            for field in (a.__dict__ if hasattr(a, "__dict__") else ["array"]):
                x, y = (getattr(a, field), getattr(b, field)) if field != "array" else (a, b)
                assert np.array_equal(x, y), "%s.%s with %d threads" % (name, field, threads)
    assert len(queries["overlap"](1).tri) > 3000  # ragged results that grow the buffer


def test_large_batches_details_against_the_tool_and_the_triangles(tmp_path):
    """A batch of many pieces of the stream (not a whole number of them), on a mesh with dropped degenerate
    triangles: occlusion, and tri, t, u, v, bit for bit as `cbvh raycast --binary`; each hit's normal the unit
    normal of its triangle as the file decodes it, its material the mesh's; misses all zeros. Without a
    MATERIALS section every material is 0."""
    vertices, triangles, materials = reference.triangle_soup(300, seed=11)
    materials = np.arange(len(triangles), dtype=np.uint32) * 7 + 3
    triangles = np.concatenate([triangles, [[0, 0, 1], [2, 2, 2]]])  # no area: dropped by the cook
    materials = np.concatenate([materials, [1, 2]]).astype(np.uint32)
    count = 150_003
    rng = np.random.default_rng(12)
    origins = rng.uniform(-2, 2, (count, 3)).astype(np.float32)
    directions = (rng.uniform(-1, 1, (count, 3)) - origins).astype(np.float32)
    records = np.zeros(count, cbvh.RAY)
    records["org"], records["dir"], records["tmax"] = origins, directions, np.inf
    for keep_materials in (True, False):
        path = tmp_path / "soup.cbvh"
        path.write_bytes(cbvh.cook(vertices, triangles, materials=materials, keep_materials=keep_materials))
        f = cbvh.open(str(path))
        assert f.info["original_triangle_count"] == len(triangles) == f.info["triangle_count"] + 2
        run = subprocess.run([cbvh_command(), "raycast", "--binary", str(path)], input=records.tobytes(),
                             capture_output=True, check=True)
        tool = np.frombuffer(run.stdout, cbvh.HIT)
        run = subprocess.run([cbvh_command(), "raycast", "--binary", "--any", str(path)], input=records.tobytes(),
                             capture_output=True, check=True)
        tool_occluded = np.frombuffer(run.stdout, np.uint8) == 1
        for threads in (3, 1):  # the first raycast makes the table of normals (here in 3 threads)
            assert np.array_equal(f.occluded(origins, directions, threads=threads), tool_occluded)
            hits = f.raycast(origins, directions, threads=threads)
            hit = hits.hit
            assert 0.2 * count < np.count_nonzero(hit) < 0.9 * count
            assert np.array_equal(hits.tri, tool["tri"])
            for field in ("t", "u", "v"):
                assert np.array_equal(getattr(hits, field)[hit], tool[field][hit])
            normals = reference.face_normals(f.triangles[hits.tri[hit]].astype(np.float64))
            assert np.allclose(hits.normal[hit], normals, rtol=0, atol=1e-6)
            expected = materials[hits.tri[hit]] if keep_materials else 0
            assert np.array_equal(hits.material[hit], np.broadcast_to(expected, hits.material[hit].shape))
            assert not hits.normal[~hit].any() and not hits.material[~hit].any()
            assert np.all(hits.t[~hit] == np.inf) and not hits.u[~hit].any() and not hits.v[~hit].any()


def small_file():
    vertices, triangles, materials = reference.triangle_soup(40, seed=9)
    return cbvh.cook(vertices, triangles, materials=materials, material_names={1: "stone"})


def test_truncated_and_damaged_files_raise(tmp_path):
    data = small_file()
    good = cbvh.open(data)
    origins = np.zeros((8, 3), np.float32) - 3
    directions = np.ones((8, 3), np.float32) + np.arange(24, dtype=np.float32).reshape(8, 3) / 50
    for size in list(range(0, 300)) + list(range(300, len(data), 7)):
        with pytest.raises(cbvh.CbvhError) as error:
            cbvh.open(data[:size])
        assert error.value.code == cbvh.lib.CBVH_ERROR_CORRUPT, size
    with pytest.raises(cbvh.CbvhError) as error:
        cbvh.open(data + b"\0" * 64)
    assert error.value.code == cbvh.lib.CBVH_ERROR_CORRUPT
    truncated = tmp_path / "truncated.cbvh"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(cbvh.CbvhError, match="truncated.cbvh"):
        cbvh.open(str(truncated))
    opened = 0
    for offset in range(len(data)):
        damaged = bytearray(data)
        damaged[offset] ^= 0x5A
        try:
            f = cbvh.open(bytes(damaged))
        except cbvh.CbvhError as e:
            assert e.code in (cbvh.lib.CBVH_ERROR_CORRUPT, cbvh.lib.CBVH_ERROR_UNSUPPORTED), (offset, e)
            continue
        opened += 1  # a byte no check covers (padding): the file must still answer as the original
        assert np.array_equal(f.raycast(origins, directions).tri, good.raycast(origins, directions).tri)
    assert opened < len(data) // 4


def test_errors_carry_code_and_message(tmp_path):
    with pytest.raises(cbvh.CbvhError) as error:
        cbvh.open(str(tmp_path / "missing.cbvh"))
    assert error.value.code == cbvh.lib.CBVH_ERROR_IO and "missing.cbvh" in str(error.value)
    with pytest.raises(cbvh.CbvhError) as error:
        cbvh.cook([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], [[0, 1, 2]])
    assert error.value.code == cbvh.lib.CBVH_ERROR_BAD_MESH and "vertex 2" in error.value.message
    with pytest.raises(cbvh.CbvhError) as error:
        cbvh.cook([[0, 0, 0], [1, 0, 0]], [[0, 1, 1]])
    assert error.value.code == cbvh.lib.CBVH_ERROR_EMPTY_MESH
    with pytest.raises(cbvh.CbvhError) as error:
        cbvh.cook([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], max_leaf_size=99)
    assert error.value.code == cbvh.lib.CBVH_ERROR_INVALID_ARGUMENT
    with pytest.raises(TypeError):
        cbvh.cook([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], leaf=4)
    f = cbvh.open(small_file())
    with pytest.raises(cbvh.CbvhError, match="sweep 1"):
        f.sweep_sphere([[0, 0, 0], [0, 0, 0]], [0.1, -1], [1, 0, 0])
    with pytest.raises(cbvh.CbvhError, match="shape 2"):
        f.overlap_sphere([[0, 0, 0], [1, 1, 1], [0, np.inf, 0]], 0.5)
    with pytest.raises(ValueError):
        f.raycast(np.zeros((3, 3)), np.ones((4, 3)))
    with pytest.raises(ValueError):
        f.raycast(np.zeros((3, 2)), np.ones((3, 2)))
    with pytest.raises(ValueError):
        f.raycast(np.zeros((3, 3)), np.ones((3, 3)), threads=0)
    assert not f.raycast([[0, 0, 0]], [[0, 0, 0]]).hit[0]  # an invalid ray (zero direction) is a miss
    assert f.material_names == {1: ["stone"]}
    f.close()
    with pytest.raises(cbvh.CbvhError, match="closed"):
        f.raycast([[0, 0, 0]], [[1, 0, 0]])


def test_cook_statistics_are_the_commands(tmp_path):
    """cook(stats=True) on a mesh written as OBJ and cooked by `cbvh cook --json` (cook_file) too: the same
    bytes, and the same statistics as the command's report, key for key (the phases' seconds aside); the
    mesh has one triangle of no area and one coordinate below CBVH_COORDINATE_MIN, which both count."""
    rng = np.random.default_rng(5)
    count = 300
    centers = np.round(rng.uniform(-4, 4, (count, 1, 3)) * 64) / 64  # exact in float32 and in the OBJ text
    corners = centers + np.round(rng.uniform(-0.5, 0.5, (count, 3, 3)) * 64) / 64
    corners[7] = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]
    corners[8, 0, 2] = 1e-13
    vertices = corners.reshape(-1, 3).astype(np.float32)
    triangles = np.arange(3 * count).reshape(count, 3)
    obj = tmp_path / "soup.obj"
    obj.write_text("".join("v %r %r %r\n" % tuple(float(x) for x in p) for p in vertices) +
                   "".join("f %d %d %d\n" % tuple(t) for t in triangles + 1))
    for options in ({}, {"quantize_vertices": True, "compress_level": 6, "layout": "binary"}):
        report = cbvh.cook_file(obj, tmp_path / "soup.cbvh", **options)
        # assimp gives every triangle its default material (id 0, named), which the command stores
        names = {m["id"]: m["name"] for m in report["material_names"]}
        data, stats = cbvh.cook(vertices, triangles, materials=np.zeros(count, np.uint32), material_names=names,
                                stats=True, **options)
        assert data == (tmp_path / "soup.cbvh").read_bytes()
        assert data == cbvh.cook(vertices, triangles, materials=np.zeros(count, np.uint32), material_names=names,
                                 **options)
        assert stats["triangles"]["dropped_degenerate"] == 1 and stats["vertices"]["flushed_coordinates"] == 1
        assert stats["file_size"] == len(data)
        for key, value in stats.items():
            if key == "seconds":
                assert set(value) == {"prepare", "build", "layout", "write", "total"}
                assert all(s >= 0 for s in value.values())
            elif isinstance(value, dict):
                assert value == {k: report[key][k] for k in value}, key
            else:
                assert value == report[key], key


def test_cook_file_matches_cook_and_reports_failures(tmp_path):
    """cook_file's options reach the command; a mesh that does not cook raises CookError with its message."""
    out = tmp_path / "a.cbvh"
    stats = cbvh.cook_file("gen:sphere:500", out, layout="binary", max_leaf_size=2, compress_level=5,
                           depfile=tmp_path / "a.d")
    f = cbvh.open(str(out))
    assert f.info["layout"] == "binary" and f.info["max_leaf_size"] <= 2 and stats["file_size"] == os.path.getsize(out)
    assert (tmp_path / "a.d").read_text().startswith(str(out) + ":")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(cbvh.CookError) as error:
        cbvh.cook_file(bad, tmp_path / "bad.cbvh")
    assert error.value.status == 1 and "bad.obj" in str(error.value)
    assert not (tmp_path / "bad.cbvh").exists()
