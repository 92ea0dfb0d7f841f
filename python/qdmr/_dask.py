"""qdmr.study.run(..., client=...): the configurations spread over the Dask workers, one task each. Every worker
process keeps one StudyMeasurer (persistent renderers) across its tasks. The configurations come in groups that
share what a measurer computes once for all of them (the exact reference and the heights it is traced on, asset
sets): each worker draws whole groups, in the order that re-prepares least, so together the workers trace and build
about what one process would. A worker whose run is done takes the back half of the longest run left when that
pays for what it then computes again. The caller appends the rows to the results folder."""
from __future__ import annotations

import collections
import os
import threading
import time
from typing import Any, Deque, Dict, List, Optional, Set, Tuple

from . import _qdmr

# This worker process's measurer: (key, StudyMeasurer). One at a time: a task of another spec replaces it.
_measurer: Optional[tuple] = None
_measurer_lock = threading.Lock()  # a worker with several threads runs one configuration at a time

IN_FLIGHT = 2  # tasks queued per worker: the next one starts while the caller takes the last one's row
WATCH_SECONDS = 1.0  # with no row for this long, the caller checks whether a worker has left


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


MIN_STEAL = 12  # a worker takes half of another's run of a group it has not drawn only when the run is this long:
# its first configuration of a new group computes the group's reference and heights again, which costs about as
# much as five of its other configurations (studies/filtering.json), so half a run of 6 is needed to gain


def _assign(measurer: Any, pending: List[int], count: int) -> Tuple[List[Deque[int]], Dict[int, int]]:
    """Each worker's run of configurations and each configuration's group: whole groups (StudyMeasurer.share_groups)
    dealt most expensive first to the worker with the least estimated cost; while there are fewer groups than
    workers, the most expensive group is cut in two halves of about equal cost. Each run is then put in the order
    that re-prepares least (configurations sharing asset sets side by side)."""
    cost = {index: measurer.estimated_cost(index) for index in pending}
    groups = [list(group) for group in measurer.share_groups(pending)]
    group_of = {index: k for k, group in enumerate(groups) for index in group}  # halves below stay one group
    while len(groups) < count:
        largest = max(groups, key=lambda group: sum(cost[i] for i in group))
        if len(largest) < 2:
            break
        total, cut = sum(cost[i] for i in largest), 1
        while cut < len(largest) - 1 and sum(cost[i] for i in largest[:cut + 1]) <= total / 2:
            cut += 1
        groups.remove(largest)
        groups += [largest[:cut], largest[cut:]]
    runs: List[List[int]] = [[] for _ in range(count)]
    loads = [0.0] * count
    # stable: ties keep the groups' order
    for group in sorted(groups, key=lambda group: sum(cost[i] for i in group), reverse=True):
        k = min(range(count), key=lambda w: loads[w])
        runs[k] += group
        loads[k] += sum(cost[i] for i in group)
    return [collections.deque(measurer.reuse_order(sorted(run))) for run in runs], group_of


def _next(queues: List[Deque[int]], own: int, group_of: Dict[int, int], drawn: Set[int],
          lost: Set[int]) -> Optional[int]:
    """The next configuration for worker `own`, which has drawn the groups `drawn`: the front of its run; when that
    is done, the back half of the longest run left (its owner would reach it last), if its last configuration is of
    a group `own` has drawn or the run is at least MIN_STEAL long, or its owner is lost; else none."""
    if not queues[own]:
        longest = max(range(len(queues)), key=lambda k: (k in lost and bool(queues[k]), len(queues[k])))
        left = queues[longest]
        if not left or (longest not in lost and group_of[left[-1]] not in drawn and len(left) < MIN_STEAL):
            return None
        taken = [left.pop() for _ in range(max(1, len(left) // 2))]
        queues[own].extend(reversed(taken))  # in the order its owner would have drawn them
    index = queues[own].popleft()
    drawn.add(group_of[index])
    return index


def _take_back_from_lost_workers(client: Any, workers: List[str], futures: Dict[Any, Tuple[int, int]],
                                 queues: List[Deque[int]], lost: Set[int]) -> None:
    """A worker that has left the cluster (killed, or restarted by its nanny under a new address) never draws the
    configurations given only to it: they go back to the front of its run, which the other workers then take."""
    alive = set(client.scheduler_info()["workers"])
    for worker, address in enumerate(workers):
        if worker in lost or address in alive:
            continue
        lost.add(worker)
        for future, (owner, index) in list(futures.items()):
            if owner == worker:
                del futures[future]
                future.cancel()
                queues[worker].appendleft(index)


def run(spec: Any, out: Any, client: Any, *, resume: bool, threads: Optional[int], force: bool,
        base_dir: Any) -> Dict[str, Any]:
    start = time.perf_counter()
    from distributed import wait

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
    futures: Dict[Any, Tuple[int, int]] = {}  # future -> (the worker it was given to, its configuration)
    try:
        done = set(folder.done)
        pending = [i for i in range(folder.configurations) if i not in done]
        if pending:
            queues, group_of = _assign(_qdmr.StudyMeasurer(spec, threads=1, force=force, base_dir=base_dir), pending,
                                       len(workers))
            drawn: List[Set[int]] = [set() for _ in workers]
            lost: Set[int] = set()
            tag = f"{folder.spec_hash[5:13]}-{os.getpid()}-{time.time_ns()}"

            def submit(worker: int) -> None:
                index = _next(queues, worker, group_of, drawn[worker], lost)
                if index is None:
                    return
                # Only on that worker: Dask's own work stealing would move a queued configuration to an idle worker
                # whose renderers hold another group's reference and heights, and compute them again there.
                future = client.submit(_measure, spec, base_dir, force, threads, folder.spec_hash, out, index,
                                       key=f"qdmr-study-{tag}-{index}", pure=False, workers=[workers[worker]],
                                       allow_other_workers=False)
                futures[future] = (worker, index)

            for _ in range(IN_FLIGHT):
                for worker in range(len(workers)):
                    submit(worker)
            while futures:
                try:
                    finished = wait(list(futures), timeout=WATCH_SECONDS, return_when="FIRST_COMPLETED").done
                except TimeoutError:
                    finished = set()
                for future in finished:
                    worker, _ = futures.pop(future)
                    pid, row, built = future.result()
                    folder.append(row)
                    pids.add(pid)
                    result["rendered"] += 1
                    result["asset_builds"] += built
                    submit(worker)
                if not finished:
                    _take_back_from_lost_workers(client, workers, futures, queues, lost)
                    for worker in range(len(workers)):
                        while worker not in lost and sum(1 for w, _ in futures.values() if w == worker) < IN_FLIGHT:
                            before = len(futures)
                            submit(worker)
                            if len(futures) == before:
                                break
                    if not futures and any(queues):
                        raise RuntimeError(f"study.run(): every Dask worker it started with has left "
                                           f"({folder.configurations - len(folder.done)} configurations without a row: "
                                           f"resume with a client that has workers)")
    except BaseException:
        client.cancel(list(futures))  # Ctrl-C or a failed configuration: the rows so far are kept (resume)
        raise
    finally:
        folder.close()
    result["seconds"] = time.perf_counter() - start
    result["processes"] = len(pids)  # worker processes that drew configurations
    return result
