"""farm_scaling.py: assets per second of cbvh.farm on its local cluster (farm.local_cluster) of 1, 2 ...
worker processes (one thread each) over a folder of assets, by default every mesh file of assimp-testmodels,
beside the `cbvh cook` command's own batch (`cbvh cook --manifest M --jobs N`, no Dask) on the same assets:
what the machine allows. The cluster's start is not counted. Each run cooks into a folder of its own; the
outputs must be identical.

    python python/benchmarks/farm_scaling.py [--folder /usr/share/assimp/models] [--workers 1 2] [--repeats 1]
"""
import argparse
import filecmp
import os
import subprocess
import tempfile
import time

from distributed import Client

from cbvh import farm
from cbvh.cook import cbvh_command

# Files of assimp-testmodels that are not meshes (textures, notes, side files of other assets).
NOT_MESHES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".dds", ".gif", ".tif", ".txt", ".md", ".mtl", ".bin",
              ".pdf", ".html", ".skeleton", ".material", ".json", ".ktx", ".ktx2", ".webp", ".exr", ".hdr")


def farm_run(assets, workers: int) -> float:
    with farm.local_cluster(workers) as cluster, Client(cluster) as client:
        client.wait_for_workers(workers)
        start = time.perf_counter()
        farm.cook_assets(assets, client, depfiles=True)
        return time.perf_counter() - start


def command_run(assets, jobs: int, manifest: str) -> float:
    with open(manifest, "w") as f:
        f.write("".join("%s\t%s\n" % (a.input, a.output) for a in assets))
    for a in assets:  # the command writes into existing folders only (the farm makes them)
        os.makedirs(os.path.dirname(a.output), exist_ok=True)
    start = time.perf_counter()
    subprocess.run([cbvh_command(), "cook", "--quiet", "--depfiles", "--jobs", str(jobs), "--manifest", manifest],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--folder", default="/usr/share/assimp/models")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=1, help="rounds, alternated; the best of each is kept")
    args = parser.parse_args()
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        outputs = {}
        best = {}
        for round_ in range(args.repeats):
            for workers in args.workers:
                for kind, run in (("farm", farm_run), ("cbvh cook", command_run)):
                    out = os.path.join(tmp, "%s-%d-%d" % (kind.replace(" ", "-"), workers, round_))
                    assets = [a for a in farm.assets_from_folder(args.folder, out)
                              if not a.input.lower().endswith(NOT_MESHES)]
                    seconds = run(assets, workers) if kind == "farm" else run(assets, workers, out + ".txt")
                    best[kind, workers] = min(best.get((kind, workers), seconds), seconds)
                    outputs[kind, workers, round_] = {os.path.relpath(a.output, out): a.output for a in assets
                                                      if os.path.exists(a.output)}
        count = len(assets)
        print("%d assets (%d cooked) under %s, best of %d round%s; load average (1, 5, 15 min) before %s, after %s" % (
            count, len(next(iter(outputs.values()))), args.folder, args.repeats, "" if args.repeats == 1 else "s",
            " ".join("%.2f" % x for x in load_before), " ".join("%.2f" % x for x in os.getloadavg())))
        print("workers  farm s  farm assets/s  farm speed-up  cbvh cook --jobs s  assets/s  speed-up")
        first = args.workers[0]
        for workers in args.workers:
            f, c = best["farm", workers], best["cbvh cook", workers]
            print("%7d  %6.2f  %13.1f  %12.2fx  %18.2f  %8.1f  %7.2fx" % (
                workers, f, count / f, best["farm", first] / f, c, count / c, best["cbvh cook", first] / c))
        reference_run, reference = next(iter(outputs.items()))
        for run, files in outputs.items():
            differ = sorted(files.keys() ^ reference.keys()) + sorted(
                k for k in files.keys() & reference.keys() if not filecmp.cmp(reference[k], files[k], shallow=False))
            assert not differ, "outputs of %s and %s differ: %s" % (reference_run, run, ", ".join(differ[:10]))
        print("outputs identical across runs (farm and cbvh cook)")


if __name__ == "__main__":
    main()
