"""test_farm.py: cbvh.farm on a LocalCluster of two worker processes over assimp's test models: every output
byte for byte as `cbvh cook` writes it, depfiles as the command writes them, failed assets reported while
the rest cook, and a worker killed in the middle of the run survived."""
import json
import os
import signal
import subprocess

import pytest

from cbvh import farm
from cbvh.cook import cbvh_command
from conftest import MODELS

distributed = pytest.importorskip("distributed")

MESH_EXTENSIONS = (".obj", ".ply", ".stl", ".off", ".3ds", ".dae", ".ase", ".ac", ".x", ".lwo", ".ms3d", ".nff",
                   ".smd", ".md2", ".glb", ".gltf", ".fbx")


def corpus(limit=120, max_bytes=400_000):
    """Small meshes of assimp-testmodels spread over its formats, with distinct stems (the manifest's IN-only
    lines name outputs by stem), and the broken ones of models/invalid."""
    if not os.path.isdir(MODELS):
        pytest.skip("assimp-testmodels is not installed (%s)" % MODELS)
    eligible, stems = [], set()
    for asset in farm.assets_from_folder(MODELS, "/unused", MESH_EXTENSIONS):
        stem = farm.output_stem(asset.input).lower()
        if stem in stems or os.path.getsize(asset.input) > max_bytes or " " in asset.input:
            continue
        stems.add(stem)
        eligible.append(asset.input)
    invalid = [p for p in eligible if "/invalid/" in p]
    others = [p for p in eligible if "/invalid/" not in p]
    step = max(1, len(others) // (limit - len(invalid)))
    return others[::step][: limit - len(invalid)] + invalid


def test_farm_cooks_as_the_command_and_survives_a_killed_worker(tmp_path):
    inputs = corpus()
    manifest = tmp_path / "assets.txt"
    manifest.write_text("# assimp test models\n" + "".join(p + "\n" for p in inputs))
    # The reference: `cbvh cook`'s own batch over the same manifest (outputs named DIR/STEM.cbvh).
    expected = tmp_path / "cli"
    expected.mkdir()
    subprocess.run([cbvh_command(), "cook", "--quiet", "--jobs", "2", "--manifest", str(manifest), "--output-dir",
                    str(expected)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    assets = farm.assets_from_manifest(str(manifest), str(tmp_path / "farm"))
    assert [a.input for a in assets] == inputs

    cluster = farm.local_cluster(2)
    client = distributed.Client(cluster)
    try:
        before = client.run(os.getpid)
        killed = []

        def kill_a_worker(result):
            if len(killed) == 0 and result.ok:
                pid = next(iter(before.values()))
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        results = farm.cook_assets(assets, client, on_result=kill_a_worker)
        client.wait_for_workers(2, timeout=60)
        after = client.run(os.getpid)
    finally:
        client.close()
        cluster.close()
    assert killed and killed[0] not in after.values(), "the worker was not killed"

    assert [r.input for r in results] == inputs
    cooked = sorted(os.listdir(expected))
    assert len(cooked) > len(inputs) // 2
    for asset, result in zip(assets, results):
        reference = expected / os.path.basename(asset.output)
        assert result.ok == reference.exists(), (asset.input, result.error)
        if result.ok:
            assert open(asset.output, "rb").read() == reference.read_bytes(), asset.input
            assert result.stats["file_size"] == reference.stat().st_size
        else:
            assert result.error and result.status in (1, 2), asset.input
            assert not os.path.exists(asset.output)
    assert sum(not r.ok for r in results) >= 5  # models/invalid and the formats assimp gives no mesh for
    assert len({r.worker for r in results if r.ok}) >= 2


def test_farm_depfiles_are_the_commands(tmp_path):
    """A depfile as `cbvh cook --depfile` writes it (the OBJ's .mtl named), for each asset."""
    corpus()  # skips without the models
    folder = os.path.join(MODELS, "OBJ")
    inputs = sorted(os.path.join(folder, p) for p in os.listdir(folder) if p.endswith(".obj"))[:16]
    assets = [farm.Asset(p, str(tmp_path / "farm" / ("%d.cbvh" % k))) for k, p in enumerate(inputs)]
    with farm.local_cluster(2) as cluster, distributed.Client(cluster) as client:
        results = farm.cook_assets(assets, client, compress_level=3)
    side_files = 0
    for asset, result in zip(assets, results):
        if not result.ok:
            continue
        out = str(tmp_path / "cli" / os.path.basename(asset.output))
        os.makedirs(os.path.dirname(out), exist_ok=True)
        subprocess.run([cbvh_command(), "cook", "--quiet", "--compress=3", "--depfile", out + ".d", asset.input, out],
                       check=True, stdout=subprocess.DEVNULL)
        assert open(asset.output, "rb").read() == open(out, "rb").read()
        expected = open(out + ".d").read().replace(out, asset.output, 1)
        depfile = open(asset.output + ".d").read()
        assert depfile == expected
        side_files += depfile.count(".mtl")
    assert sum(r.ok for r in results) >= 6 and side_files >= 1


def test_farm_batches_of_any_size_and_paths_a_manifest_cannot_hold(tmp_path):
    """Any batch size gives the command's bytes; an asset whose path holds a tab (which a manifest line
    cannot) is cooked alone, as the others; a batch the command refuses as a whole (a material map that is
    not there) comes back as every asset of it failed, with the command's message."""
    corpus()  # skips without the models
    folder = os.path.join(MODELS, "PLY")
    inputs = sorted(os.path.join(folder, p) for p in os.listdir(folder) if p.endswith(".ply"))[:6]
    odd = tmp_path / "in" / "tab\there.ply"
    odd.parent.mkdir()
    odd.write_bytes(open(inputs[0], "rb").read())
    inputs.append(str(odd))
    expected = {}
    for k, path in enumerate(inputs):
        out = str(tmp_path / "cli" / ("%d.cbvh" % k))
        os.makedirs(os.path.dirname(out), exist_ok=True)
        status = subprocess.run([cbvh_command(), "cook", "--quiet", path, out], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL).returncode
        expected[k] = open(out, "rb").read() if status == 0 else None
    assert sum(v is not None for v in expected.values()) >= 4 and expected[len(inputs) - 1] is not None
    with farm.local_cluster(2) as cluster, distributed.Client(cluster) as client:
        for batch_size in (1, 3, None):
            out = tmp_path / ("farm%s" % batch_size)
            assets = [farm.Asset(p, str(out / ("%d.cbvh" % k))) for k, p in enumerate(inputs)]
            results = farm.cook_assets(assets, client, batch_size=batch_size)
            assert [r.input for r in results] == inputs
            for k, result in enumerate(results):
                assert result.ok == (expected[k] is not None), (result.input, result.error)
                if result.ok:
                    assert open(assets[k].output, "rb").read() == expected[k]
                    assert open(assets[k].output + ".d").read().startswith(assets[k].output + ":")
                    assert result.stats["file_size"] == len(expected[k])
        assets = [farm.Asset(p, str(tmp_path / "unmapped" / ("%d.cbvh" % k))) for k, p in enumerate(inputs[:4])]
        results = farm.cook_assets(assets, client, batch_size=4, retries=0,
                                   material_map=str(tmp_path / "missing.map"))
        assert all(not r.ok and "missing.map" in r.error for r in results), [r.error for r in results]
        assert not any(os.path.exists(a.output) or os.path.exists(a.output + ".d") for a in assets)
        with pytest.raises(ValueError, match="batch_size"):
            farm.cook_assets(assets, client, batch_size=0)


def test_batches_cover_every_asset_once_and_each_samples_the_whole_list():
    for count in list(range(0, 300)) + [452, 5000, 100_000]:
        for workers in (1, 2, 3, 8):
            batches = farm.plan_batches(count, workers)
            assert sorted(k for batch in batches for k in batch) == list(range(count)), (count, workers)
            sizes = [len(batch) for batch in batches]
            assert len(batches) == min(count, max(8 * workers, -(-count // 64))), (count, workers)
            assert max(sizes or [0]) <= 64 and max(sizes or [0]) - min(sizes or [0]) <= 1, (count, workers)
            for batch in batches:  # every len(batches)-th asset
                assert all(b - a == len(batches) for a, b in zip(batch, batch[1:])), (count, workers, batch)
    for workers in (1, 2):
        assert [len(b) for b in farm.plan_batches(10, workers, batch_size=4)] == [4, 3, 3]
    with pytest.raises(ValueError, match="batch_size"):
        farm.plan_batches(10, 2, batch_size=0)


def test_local_cluster_settings_unless_the_user_chose_them():
    """The farm's Dask settings reach the scheduler and the worker processes; a setting the user's Dask
    configuration holds (here the event-loop check's interval) is kept."""
    import dask
    with dask.config.set({"distributed.admin.tick.interval": "300ms"}):
        cluster = farm.local_cluster(1)
    with cluster, distributed.Client(cluster) as client:
        on_worker = client.run(lambda: [dask.config.get(key) for key in farm.LOCAL_CLUSTER_CONFIG])
        saturation = client.run_on_scheduler(lambda dask_scheduler: dask_scheduler.WORKER_SATURATION)
    expected = [value for value in farm.LOCAL_CLUSTER_CONFIG.values()]
    expected[list(farm.LOCAL_CLUSTER_CONFIG).index("distributed.admin.tick.interval")] = "300ms"
    assert list(on_worker.values()) == [expected]
    assert saturation == farm.LOCAL_CLUSTER_CONFIG["distributed.scheduler.worker-saturation"] != \
        dask.config.get("distributed.scheduler.worker-saturation")


def test_manifest_and_folder_naming(tmp_path):
    (tmp_path / "a" / "b").mkdir(parents=True)
    for name in ("a/x.obj", "a/x.ply", "a/b/y.obj.gz", "a/b/.hidden"):
        (tmp_path / name).write_text("")
    found = farm.assets_from_folder(str(tmp_path / "a"), str(tmp_path / "out"))
    assert sorted(os.path.relpath(a.output, tmp_path / "out") for a in found) == \
        sorted(["x.obj.cbvh", "x.ply.cbvh", "b/y.cbvh", "b/.hidden.cbvh"])
    manifest = tmp_path / "m.txt"
    manifest.write_text("# c\n\na/x.obj\ta/custom.cbvh\n")
    os.chdir(tmp_path)
    assert farm.assets_from_manifest(str(manifest)) == [farm.Asset(str(tmp_path / "a/x.obj"),
                                                                   str(tmp_path / "a/custom.cbvh"))]
    manifest.write_text("a/x.obj\n")
    with pytest.raises(ValueError, match="line 1"):
        farm.assets_from_manifest(str(manifest))


def test_command_line(tmp_path, capsys):
    """python -m cbvh.farm: one JSON line per asset, exit status 1 when one failed."""
    corpus()  # skips without the models
    good = os.path.join(MODELS, "PLY", "Wuson.ply")
    bad = tmp_path / "bad.obj"
    bad.write_text("f 1 2 3\n")
    manifest = tmp_path / "m.txt"
    manifest.write_text("%s\n%s\t%s\n" % (good, bad, tmp_path / "out" / "bad.cbvh"))
    status = farm.main(["--manifest", str(manifest), "--output-dir", str(tmp_path / "out"), "--workers", "1"])
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert status == 1 and len(lines) == 2
    by_input = {line["input"]: line for line in lines}
    assert by_input[good]["ok"] and os.path.exists(tmp_path / "out" / "Wuson.cbvh")
    assert not by_input[str(bad)]["ok"] and by_input[str(bad)]["status"] == 1
    assert os.path.exists(tmp_path / "out" / "Wuson.cbvh.d")
