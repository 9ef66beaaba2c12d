"""farm.py: cooks a library of assets on a dask.distributed cluster, a batch of assets per task.

Each task runs `cbvh cook --manifest` over its batch on a worker (the same importer, options and bytes as on
one machine; the command starts once a batch, not once an asset), reading inputs from and writing outputs
(and depfiles, OUT.d) to a file system the workers share. A task whose worker dies is run again on another
one by the scheduler; an asset that does not cook is reported with its error while the others go on.

    python -m cbvh.farm --scheduler tcp://host:8786 --manifest assets.txt --output-dir cooked
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence

from .cook import CookError, cbvh_command, cook_arguments, cook_file


# Dask settings of the local cluster the farm starts (local_cluster), each one used only where the Dask
# configuration (YAML files, DASK_* variables, dask.config.set) holds Dask's own default, so a user's choice
# wins. A worker of the farm spends its time waiting on a `cbvh` process; these keep Dask's periodic work in
# the scheduler, the nannies and the workers from taking CPU from the cooks on the same cores.
LOCAL_CLUSTER_CONFIG: Dict[str, Any] = {
    "distributed.worker.profile.enabled": False,  # the statistical profiler: each worker's threads every 10 ms
    "distributed.admin.tick.interval": "1s",  # each process's event-loop health check (20 ms)
    "distributed.admin.system-monitor.interval": "5s",  # each process's CPU, memory and I/O record (0.5 s)
    "distributed.worker.memory.monitor-interval": "1s",  # each worker's and nanny's memory limits (0.1 s)
    # a worker is sent its next task when it is free (1.1: one waits on each worker), so that at the end no
    # task waits behind a long one while the other workers are idle
    "distributed.scheduler.worker-saturation": 1.0,
}


def local_cluster(workers: Optional[int] = None, **kwargs: Any) -> Any:
    """A dask.distributed LocalCluster for the farm: `workers` worker processes (default: one a core) of one
    thread each (a cook is a process of its own), no dashboard, LOCAL_CLUSTER_CONFIG for the settings the Dask
    configuration leaves at their defaults. kwargs go to LocalCluster and override these."""
    import dask
    from distributed import LocalCluster

    defaults = dask.config.merge(*dask.config.defaults)
    chosen = {key: value for key, value in LOCAL_CLUSTER_CONFIG.items()
              if dask.config.get(key) == dask.config.get(key, config=defaults)}
    with dask.config.set(chosen):  # read as the scheduler, nannies and workers start (and restart)
        return LocalCluster(**dict(dict(n_workers=workers, threads_per_worker=1, processes=True,
                                        dashboard_address=None), **kwargs))


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


def _worker_address() -> Optional[str]:
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return None


def cook_asset(asset: Asset, options: Dict[str, Any], depfiles: bool = True) -> AssetResult:
    """Cooks one asset with cook_file; a cook failure is returned, not raised."""
    start = time.perf_counter()
    result = AssetResult(asset.input, asset.output, ok=False, worker=_worker_address())
    try:
        os.makedirs(os.path.dirname(asset.output) or ".", exist_ok=True)
        result.stats = cook_file(asset.input, asset.output,
                                 **dict(options, depfile=asset.output + ".d" if depfiles else None))
        result.ok = True
    except CookError as e:
        result.error, result.status = e.message, e.status
    result.seconds = time.perf_counter() - start
    return result


def _manifest_line(asset: Asset) -> Optional[str]:
    """The line of a `cbvh cook --manifest` naming the asset, or None when its paths cannot be written in one
    (a tab or line break in a path, an input starting with #, a line longer than the command reads)."""
    paths = (asset.input, asset.output)
    if any(not p or any(c in p for c in "\t\r\n") for p in paths) or asset.input.startswith("#"):
        return None
    line = "%s\t%s\n" % paths
    return line if len(os.fsencode(line)) < 8000 else None


def cook_batch(assets: Sequence[Asset], options: Dict[str, Any], depfiles: bool = True) -> List[AssetResult]:
    """Cooks a batch of assets (the task each worker runs) with one `cbvh cook --manifest - --json` run: the
    command imports, cooks and writes each as it would alone, and reports each on a line of its own. Assets
    whose paths a manifest cannot hold are cooked one by one (cook_asset). A failed cook is returned as its
    asset's result; the command stopping before it reported every asset raises RuntimeError (the task is then
    run again)."""
    worker = _worker_address()
    lines = [_manifest_line(a) for a in assets]
    results: List[Optional[AssetResult]] = [None] * len(assets)
    batch = [k for k, line in enumerate(lines) if line is not None]
    if batch:
        command = [cbvh_command(), "cook", "--quiet", "--json", "--manifest", "-"] + cook_arguments(**options)
        if depfiles:
            command.append("--depfiles")
        for k in batch:
            os.makedirs(os.path.dirname(assets[k].output) or ".", exist_ok=True)
        with tempfile.TemporaryFile() as errors:
            start = time.perf_counter()
            run = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors)
            try:  # the command reads the whole manifest before it cooks
                run.stdin.write(os.fsencode("".join(lines[k] for k in batch)))  # type: ignore[union-attr]
                run.stdin.close()  # type: ignore[union-attr]
            except BrokenPipeError:  # it stopped at once: its message is on its standard error
                pass
            reports, rest = [], []
            for line in run.stdout:  # type: ignore[union-attr]
                finished = time.perf_counter()
                text = line.decode("utf-8", "surrogateescape")
                if text.startswith('{"input"'):  # an asset's report, on one line
                    reports.append((json.loads(text), finished - start))
                    start = finished
                else:  # the report of the command as a whole (it could not run the batch), over lines
                    rest.append(text)
            status = run.wait()
            if len(reports) < len(batch):
                try:
                    error = json.loads("".join(rest))["error"]
                except (ValueError, KeyError, TypeError):
                    errors.seek(0)
                    detail = errors.read().decode("utf-8", "replace").strip()
                    raise RuntimeError("cbvh cook --manifest reported %d of its %d assets (exit status %d)%s" % (
                        len(reports), len(batch), status, ": " + detail[-2000:] if detail else ""))
                reports += [({"error": error}, 0.0)] * (len(batch) - len(reports))
        for k, (report, seconds) in zip(batch, reports):  # one line an asset, in the manifest's order
            result = AssetResult(assets[k].input, assets[k].output, ok="error" not in report, worker=worker,
                                 seconds=seconds)
            if result.ok:
                result.stats = report
            else:
                error = report["error"]
                result.error, result.status = str(error.get("message", "")), int(error.get("status", 1))
            results[k] = result
    for k, line in enumerate(lines):
        if line is None:
            results[k] = cook_asset(assets[k], options, depfiles)
    return results  # type: ignore[return-value]


def plan_batches(asset_count: int, worker_count: int, batch_size: Optional[int] = None) -> List[List[int]]:
    """The batches (lists of asset indices, one task each, in the order they are submitted) cook_assets makes
    of asset_count assets: at most batch_size assets each, or by default about 8 a worker (so that the
    workers stay equally busy to the end, and a task lost with a worker costs little) of at most 64 assets.
    The k-th of n batches takes every n-th asset from the k-th: a run of large assets is spread over the
    batches, and a list sorted from the costliest down puts the costliest first in every batch and the
    lightest batches last."""
    if batch_size is not None:
        if not isinstance(batch_size, int) or batch_size < 1:
            raise ValueError("batch_size must be a positive integer, not %r" % (batch_size,))
        count = math.ceil(asset_count / batch_size)
    else:
        count = min(asset_count, max(8 * max(worker_count, 1), math.ceil(asset_count / 64)))
    return [list(range(first, asset_count, count)) for first in range(count)]


def cook_assets(assets: Iterable[Asset], client: Any = None, *, retries: int = 2, depfiles: bool = True,
                batch_size: Optional[int] = None, on_result: Optional[Callable[[AssetResult], None]] = None,
                **options: Any) -> List[AssetResult]:
    """Cooks every asset on the cluster of `client` (a dask.distributed Client, a scheduler address such as
    "tcp://host:8786", or None: a local_cluster() for this call) and returns their results in the assets'
    order. The assets go to the workers in batches, one task each (cook_batch), as plan_batches makes them
    (at most batch_size assets a batch, or about 8 batches a worker). Options are cook_file's
    (layout, compress_level, scale, material_map ...; depfiles=True writes OUT.d beside each output). A task
    is run again `retries` times when it raises (a file system error on a worker), and by the scheduler when
    its worker dies (up to the scheduler's allowed-failures); the assets of a task that still fails are
    reported as failed, the others go on. on_result(result) is called for each asset as its batch finishes."""
    from distributed import Client, as_completed

    if "depfile" in options:
        raise ValueError("cook_assets writes each asset's depfile to OUT.d with depfiles=True, not depfile=")
    assets = list(assets)
    own_client = own_cluster = None
    try:
        if client is None:
            own_cluster = local_cluster()
            client = own_client = Client(own_cluster)
            client.wait_for_workers(len(own_cluster.workers))  # the batches are made for the workers there are
        elif isinstance(client, str):
            client = own_client = Client(client)
        batches = plan_batches(len(assets), len(client.scheduler_info().get("workers", {})), batch_size)
        futures = client.map(cook_batch, [[assets[k] for k in batch] for batch in batches], options=options,
                             depfiles=depfiles, retries=retries, pure=False)
        index = {future.key: b for b, future in enumerate(futures)}
        results: List[Optional[AssetResult]] = [None] * len(assets)
        for future in as_completed(futures):
            batch = batches[index[future.key]]
            try:
                done = future.result()
            except Exception as e:  # the task itself failed (after its retries), or its workers kept dying
                done = [AssetResult(assets[k].input, assets[k].output, ok=False,
                                    error="%s: %s" % (type(e).__name__, e)) for k in batch]
            for k, result in zip(batch, done):
                results[k] = result
                if on_result:
                    on_result(result)
        return results  # type: ignore[return-value]
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()


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
    parser.add_argument("--batch-size", type=int, metavar="N", help="assets a task (default: about 8 tasks a worker)")
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
        from distributed import Client
        cluster = local_cluster(args.workers)
        client = Client(cluster)
        client.wait_for_workers(len(cluster.workers))  # the batches are made for the workers there are
    start = time.perf_counter()
    results = cook_assets(assets, client, depfiles=not args.no_depfiles, batch_size=args.batch_size,
                          compress_level=args.compress, on_result=lambda r: print(json.dumps(asdict(r)), flush=True))
    failed = sum(not r.ok for r in results)
    print("%d assets cooked, %d failed in %.1f s" % (len(results) - failed, failed, time.perf_counter() - start),
          file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
