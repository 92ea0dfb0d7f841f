"""qdmr.study.run(..., client=...): one shard per Dask worker, merged into the results folder."""
from __future__ import annotations

import os
import time
from typing import Any, Dict, Optional

from . import _qdmr


def _run_shard(spec: Any, folder: str, shard: tuple, threads: Optional[int], force: bool,
               base_dir: Optional[str]) -> Dict[str, Any]:
    """On a worker: one shard, into its own folder, resumed where an earlier run of it stopped."""
    if threads is None:
        try:
            from distributed import get_worker
            threads = get_worker().state.nthreads
        except (ImportError, ValueError, AttributeError):
            threads = None
    run = _qdmr.run_study(spec, folder, resume=True, threads=threads, jobs=1, shard=shard, force=force,
                          base_dir=base_dir)
    run["pid"] = os.getpid()
    return run


def run(spec: Any, out: Any, client: Any, *, resume: bool, threads: Optional[int], force: bool,
        base_dir: Any) -> Dict[str, Any]:
    start = time.perf_counter()
    # Workers may run elsewhere: every path absolute, the spec checked here before anything is sent.
    if isinstance(spec, dict):
        base_dir = os.path.abspath(os.fspath(base_dir) if base_dir is not None else os.getcwd())
    elif isinstance(spec, (str, os.PathLike)):
        spec = os.path.abspath(os.fspath(spec))
    out = os.path.abspath(os.fspath(out))
    total = _qdmr.study_size(spec, force, base_dir)
    shards_dir = os.path.join(out, "shards")
    existing = sorted(name for name in os.listdir(shards_dir)) if os.path.isdir(shards_dir) else []
    if existing or os.path.exists(os.path.join(out, "study.json")):
        if not resume:
            raise _qdmr.SceneError(out + ": holds the results of a study already: pass resume=True to continue it, "
                                   "or choose another out")
    if existing:
        count = int(existing[0].split("-of-")[1])  # resumed: the shards of the first run
    else:
        workers = len(client.scheduler_info()["workers"])
        count = max(1, min(workers, total))
    worker_addresses = list(client.scheduler_info()["workers"])
    futures = []
    for index in range(1, count + 1):
        folder = os.path.join(shards_dir, f"{index}-of-{count}")
        target = [worker_addresses[(index - 1) % len(worker_addresses)]] if worker_addresses else None
        futures.append(client.submit(_run_shard, spec, folder, (index, count), threads, force, base_dir,
                                     pure=False, workers=target, allow_other_workers=True,
                                     key=f"qdmr-study-shard-{index}-of-{count}-{os.getpid()}-{time.time_ns()}"))
    try:
        runs = client.gather(futures)
    except BaseException:
        client.cancel(futures)  # Ctrl-C or a failed shard: the others stop too; their rows so far are kept
        raise
    folders = [os.path.join(shards_dir, f"{index}-of-{count}") for index in range(1, count + 1)]
    _qdmr.merge_studies(folders, out)
    result: Dict[str, Any] = {key: sum(r[key] for r in runs) for key in ("total", "rendered", "resumed", "asset_builds")}
    result["seconds"] = time.perf_counter() - start
    result["shards"] = count
    result["processes"] = len({r["pid"] for r in runs})  # worker processes that drew a shard
    return result
