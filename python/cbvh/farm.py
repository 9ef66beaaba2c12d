"""farm.py: cooks a library of assets on a dask.distributed cluster, one task per asset.

Each task runs cbvh.cook_file on a worker (the `cbvh cook` command: the same importer, options and bytes as
on one machine), reading its input from and writing its output (and depfile, OUT.d) to a file system the
workers share. A task whose worker dies is run again on another one by the scheduler; an asset that does
not cook is reported with its error while the others go on.

    python -m cbvh.farm --scheduler tcp://host:8786 --manifest assets.txt --output-dir cooked
"""
import argparse
import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence

from .cook import CookError, cook_file


@dataclass
class Asset:
    """An input mesh file and the cbvh file to cook it into (absolute paths)."""
    input: str
    output: str


@dataclass
class AssetResult:
    """What became of an asset: ok, or the error (`status`: cbvh cook's exit status; None when the task
    itself failed, after its retries), the cook's statistics (cbvh cook --json), the worker and seconds."""
    input: str
    output: str
    ok: bool
    error: Optional[str] = None
    status: Optional[int] = None
    stats: Optional[Dict[str, Any]] = None
    worker: Optional[str] = None
    seconds: float = 0.0


def output_stem(path: str) -> str:
    """The file name of `path` without its extension (and without .gz), as `cbvh cook --output-dir` names
    its outputs."""
    name = os.path.basename(path)
    if len(name) > 3 and name.endswith(".gz"):
        name = name[:-3]
    dot = name.rfind(".")
    return name[:dot] if dot >= 1 else name


def assets_from_manifest(path: str, output_dir: Optional[str] = None) -> List[Asset]:
    """The assets of a manifest in `cbvh cook --manifest`'s syntax: a line per asset, IN (cooked into
    output_dir/STEM.cbvh) or IN<TAB>OUT; blank lines and lines starting with # are skipped. Relative paths
    are taken from the current folder."""
    assets = []
    with open(path, encoding="utf-8") as manifest:
        for number, line in enumerate(manifest, 1):
            line = line.rstrip("\r\n")
            if not line or line.startswith("#"):
                continue
            source, tab, target = line.partition("\t")
            if not source or (tab and not target):
                raise ValueError("%s: line %d: an empty input or output path" % (path, number))
            if not tab and output_dir is None:
                raise ValueError("%s: line %d: '%s' names no output (IN<TAB>OUT) and no output folder was given"
                                 % (path, number, source))
            target = target if tab else os.path.join(output_dir, output_stem(source) + ".cbvh")
            assets.append(Asset(os.path.abspath(source), os.path.abspath(target)))
    return assets


def assets_from_folder(folder: str, output_dir: str, extensions: Optional[Sequence[str]] = None) -> List[Asset]:
    """Every file under `folder` (or those whose names end with one of `extensions`, case-insensitive),
    each cooked into output_dir/SUBFOLDER/STEM.cbvh, keeping the subfolders so that names never collide.
    Files sharing a stem in one folder (a.obj, a.ply) keep their extension instead: a.obj.cbvh."""
    assets = []
    for root, folders, files in os.walk(folder):
        folders.sort()
        chosen = sorted(f for f in files if not extensions or f.lower().endswith(tuple(e.lower() for e in extensions)))
        stems = [output_stem(f) for f in chosen]
        for name, stem in zip(chosen, stems):
            relative = os.path.relpath(root, folder)
            unique = stem if stems.count(stem) == 1 else name
            target = os.path.normpath(os.path.join(output_dir, relative, unique + ".cbvh"))
            assets.append(Asset(os.path.abspath(os.path.join(root, name)), os.path.abspath(target)))
    return assets


def cook_asset(asset: Asset, options: Dict[str, Any], depfiles: bool = True) -> AssetResult:
    """Cooks one asset (the task each worker runs); a cook failure is returned, not raised."""
    start = time.perf_counter()
    worker = None
    try:
        from distributed import get_worker
        worker = get_worker().address
    except (ImportError, ValueError):
        pass
    result = AssetResult(asset.input, asset.output, ok=False, worker=worker)
    try:
        os.makedirs(os.path.dirname(asset.output) or ".", exist_ok=True)
        result.stats = cook_file(asset.input, asset.output,
                                 **dict(options, depfile=asset.output + ".d" if depfiles else None))
        result.ok = True
    except CookError as e:
        result.error, result.status = e.message, e.status
    result.seconds = time.perf_counter() - start
    return result


def cook_assets(assets: Iterable[Asset], client: Any = None, *, retries: int = 2, depfiles: bool = True,
                on_result: Optional[Callable[[AssetResult], None]] = None, **options: Any) -> List[AssetResult]:
    """Cooks every asset on the cluster of `client` (a dask.distributed Client, or a scheduler address such
    as "tcp://host:8786"), one task each, and returns their results in the assets' order. Options are
    cook_file's (layout, compress_level, scale, material_map ...). A task is run again `retries` times when it
    raises (a file system error on a worker), and by the scheduler when its worker dies (up to the
    scheduler's allowed-failures); a task that still fails is reported as a failed asset, the others go on.
    on_result(result) is called as each asset finishes."""
    from distributed import Client, as_completed

    assets = list(assets)
    own_client = None
    if client is None or isinstance(client, str):
        client = own_client = Client(client) if client else Client()
    try:
        futures = client.map(cook_asset, assets, options=options, depfiles=depfiles, retries=retries, pure=False)
        index = {future.key: k for k, future in enumerate(futures)}
        results: List[Optional[AssetResult]] = [None] * len(assets)
        for future in as_completed(futures):
            k = index[future.key]
            try:
                results[k] = future.result()
            except Exception as e:  # the task itself failed (after its retries), or its workers kept dying
                results[k] = AssetResult(assets[k].input, assets[k].output, ok=False,
                                         error="%s: %s" % (type(e).__name__, e))
            if on_result:
                on_result(results[k])
        return results  # type: ignore[return-value]
    finally:
        if own_client is not None:
            own_client.close()


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m cbvh.farm",
                                     description="Cook assets on a dask.distributed cluster; one JSON line per "
                                                 "asset on stdout, exit status 1 when some asset failed.")
    parser.add_argument("--scheduler", help="the scheduler's address (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="worker processes of the local cluster")
    parser.add_argument("--manifest", help="assets, one a line: IN or IN<TAB>OUT (cbvh cook --manifest)")
    parser.add_argument("--folder", help="cook every file under this folder")
    parser.add_argument("--output-dir", help="where IN-only assets go (DIR/STEM.cbvh)")
    parser.add_argument("--no-depfiles", action="store_true", help="write no OUT.d")
    parser.add_argument("--compress", type=int, default=0, metavar="LEVEL", help="zlib level 1..9")
    args = parser.parse_args(argv)
    if bool(args.manifest) == bool(args.folder):
        parser.error("give --manifest or --folder")
    if args.folder and not args.output_dir:
        parser.error("--folder needs --output-dir")
    assets = (assets_from_manifest(args.manifest, args.output_dir) if args.manifest
              else assets_from_folder(args.folder, args.output_dir))
    if args.scheduler:
        client: Any = args.scheduler
    else:
        from distributed import Client, LocalCluster
        client = Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True))
    start = time.perf_counter()
    results = cook_assets(assets, client, depfiles=not args.no_depfiles, compress_level=args.compress,
                          on_result=lambda r: print(json.dumps(asdict(r)), flush=True))
    failed = sum(not r.ok for r in results)
    print("%d assets cooked, %d failed in %.1f s" % (len(results) - failed, failed, time.perf_counter() - start),
          file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
