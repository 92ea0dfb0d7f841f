"""qdmr.study.run(..., client=...): the configurations spread over the Dask workers, one task each. Every worker
process keeps one StudyMeasurer (persistent renderers) across its tasks and starts on a run of configurations that
share baselines and asset sets, so it prepares and draws those once; a worker whose run is done takes from the end
of the longest other run. The caller appends the rows to the results folder."""
from __future__ import annotations

import collections
import os
import threading
import time
from typing import Any, Deque, Dict, List, Optional

from . import _qdmr

# This worker process's measurer: (key, StudyMeasurer). One at a time: a task of another spec replaces it.
_measurer: Optional[tuple] = None
_measurer_lock = threading.Lock()  # a worker with several threads runs one configuration at a time

IN_FLIGHT = 2  # tasks queued per worker: the next one starts while the caller takes the last one's row


def _keep_freed_memory() -> None:
    """Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536 (distributed.nanny.pre-spawn-environ). Setting
    it also pins glibc's mmap threshold at 128 KiB: every frame-sized buffer a configuration allocates is then mapped
    fresh, zeroed by the kernel and unmapped when freed (4x the page faults, ~15 % more CPU per configuration than
    in one process). This worker process gets glibc's own ceilings back: the dynamic mmap threshold's 32 MiB, and
    trimming above twice that."""
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ:
        return
    try:
        import ctypes
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 << 20)  # M_MMAP_THRESHOLD
        libc.mallopt(-1, 64 << 20)  # M_TRIM_THRESHOLD
    except (OSError, AttributeError):  # not glibc: nothing to undo
        pass


def _worker_threads() -> Optional[int]:
    try:
        from distributed import get_worker
        return get_worker().state.nthreads
    except (ImportError, ValueError, AttributeError):
        return None


def _measure(spec: Any, base_dir: Optional[str], force: bool, threads: Optional[int], spec_hash: str, out: str,
             index: int) -> tuple:
    """On a worker: configuration `index`'s row (JSON text) by the worker's persistent measurer, the worker's
    process id and whether its assets were built (1) or reused (0)."""
    global _measurer
    if threads is None:
        threads = _worker_threads()
    key = (spec_hash, threads, force, base_dir, out)
    with _measurer_lock:
        if _measurer is None or _measurer[0] != key:
            _measurer = None  # the previous spec's renderers go before the next one's prepare
            _keep_freed_memory()
            measurer = _qdmr.StudyMeasurer(spec, threads=threads, force=force, base_dir=base_dir)
            if measurer.spec_hash != spec_hash:
                raise _qdmr.SceneError(f"{spec}: changed while the study ran ({measurer.spec_hash}, the run's "
                                       f"is {spec_hash})")
            _measurer = (key, measurer)
        measurer = _measurer[1]
        builds = measurer.asset_builds
        row = measurer.measure(index, out)
        return os.getpid(), row, measurer.asset_builds - builds


def _assign(measurer: Any, pending: List[int], count: int) -> List[Deque[int]]:
    """Each worker's run of configurations: those that share a baseline (the image difference's) stay together,
    the groups dealt largest first to the worker with the fewest configurations; each run is then put in the
    order that re-prepares least (configurations sharing asset sets side by side)."""
    groups: Dict[str, List[int]] = {}
    for index in pending:
        groups.setdefault(measurer.baseline_key(index), []).append(index)
    runs: List[List[int]] = [[] for _ in range(count)]
    for group in sorted(groups.values(), key=len, reverse=True):  # stable: ties keep the first configuration's order
        min(runs, key=len).extend(group)
    return [collections.deque(measurer.reuse_order(sorted(run))) for run in runs]


def _next(queues: List[Deque[int]], own: int) -> Optional[int]:
    """The next configuration for worker `own`: the front of its run; when that is done, the back of the longest
    run left (its owner would reach it last), so the workers finish together whatever the configurations cost."""
    if queues[own]:
        return queues[own].popleft()
    longest = max(range(len(queues)), key=lambda k: len(queues[k]))
    return queues[longest].pop() if queues[longest] else None


def run(spec: Any, out: Any, client: Any, *, resume: bool, threads: Optional[int], force: bool,
        base_dir: Any) -> Dict[str, Any]:
    start = time.perf_counter()
    from distributed import as_completed

    # Workers may run elsewhere: every path absolute, the spec checked here before anything is sent.
    if isinstance(spec, dict):
        base_dir = os.path.abspath(os.fspath(base_dir) if base_dir is not None else os.getcwd())
    elif isinstance(spec, (str, os.PathLike)):
        spec = os.path.abspath(os.fspath(spec))
    out = os.path.abspath(os.fspath(out))
    workers_info = client.scheduler_info()["workers"]
    workers = sorted(workers_info)
    if not workers:
        raise ValueError("study.run(): the Dask client has no workers")
    header_threads = threads if threads is not None else workers_info[workers[0]].get("nthreads")
    folder = _qdmr.StudyFolder(spec, out, resume=resume, force=force, threads=header_threads, base_dir=base_dir)
    result: Dict[str, Any] = {"total": folder.configurations, "rendered": 0, "resumed": folder.resumed,
                              "asset_builds": 0}
    pids = set()
    futures: Dict[Any, int] = {}  # future -> the worker it was given to
    try:
        done = set(folder.done)
        pending = [i for i in range(folder.configurations) if i not in done]
        if pending:
            queues = _assign(_qdmr.StudyMeasurer(spec, threads=1, force=force, base_dir=base_dir), pending,
                             len(workers))
            tag = f"{folder.spec_hash[5:13]}-{os.getpid()}-{time.time_ns()}"
            running = as_completed()

            def submit(worker: int) -> None:
                index = _next(queues, worker)
                if index is None:
                    return
                future = client.submit(_measure, spec, base_dir, force, threads, folder.spec_hash, out, index,
                                       key=f"qdmr-study-{tag}-{index}", pure=False, workers=[workers[worker]],
                                       allow_other_workers=True)
                futures[future] = worker
                running.add(future)

            for _ in range(IN_FLIGHT):
                for worker in range(len(workers)):
                    submit(worker)
            for future in running:
                worker = futures.pop(future)
                pid, row, built = future.result()
                folder.append(row)
                pids.add(pid)
                result["rendered"] += 1
                result["asset_builds"] += built
                submit(worker)
    except BaseException:
        client.cancel(list(futures))  # Ctrl-C or a failed configuration: the rows so far are kept (resume)
        raise
    finally:
        folder.close()
    result["seconds"] = time.perf_counter() - start
    result["processes"] = len(pids)  # worker processes that drew configurations
    return result
