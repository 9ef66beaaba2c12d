"""farm_scaling.py: assets per second of cbvh.farm on a LocalCluster of 1, 2 ... worker processes (one
thread each) over a folder of assets, by default every mesh file of assimp-testmodels; the cluster's start is
not counted. Each count of workers cooks into a folder of its own; the outputs must be identical.

    python python/benchmarks/farm_scaling.py [--folder /usr/share/assimp/models] [--workers 1 2]
"""
import argparse
import filecmp
import os
import tempfile
import time

from distributed import Client, LocalCluster

from cbvh import farm

# Files of assimp-testmodels that are not meshes (textures, notes, side files of other assets).
NOT_MESHES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".dds", ".gif", ".tif", ".txt", ".md", ".mtl", ".bin",
              ".pdf", ".html", ".skeleton", ".material", ".json", ".ktx", ".ktx2", ".webp", ".exr", ".hdr")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--folder", default="/usr/share/assimp/models")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        outputs = {}
        for workers in args.workers:
            out = os.path.join(tmp, "w%d" % workers)
            assets = [a for a in farm.assets_from_folder(args.folder, out)
                      if not a.input.lower().endswith(NOT_MESHES)]
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster, Client(cluster) as client:
                client.wait_for_workers(workers)
                start = time.perf_counter()
                results = farm.cook_assets(assets, client, depfiles=True)
                seconds = time.perf_counter() - start
            cooked = sum(r.ok for r in results)
            print("%d worker%s: %d assets (%d cooked, %d failed) in %.2f s: %.1f assets/s" % (
                workers, "" if workers == 1 else "s", len(assets), cooked, len(assets) - cooked, seconds,
                len(assets) / seconds))
            outputs[workers] = {os.path.relpath(r.output, out): r.output for r in results if r.ok}
        first = outputs[args.workers[0]]
        for workers, files in outputs.items():
            assert files.keys() == first.keys() and all(
                filecmp.cmp(first[k], files[k], shallow=False) for k in files), "outputs differ"
        print("outputs identical across worker counts")


if __name__ == "__main__":
    main()
