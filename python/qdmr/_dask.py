"""qdmr.study.run(..., client=...): the configurations spread over the Dask workers, a few per task. Every worker
process keeps one StudyMeasurer (persistent renderers) across its tasks. The configurations come in groups that
share what a measurer computes once for all of them (the exact reference and the heights it is traced on, asset
sets): each worker draws whole groups, in the order that re-prepares least, so together the workers trace and build
about what one process would. Tasks carry a few configurations (fewer as a worker's run shrinks: the last are
single), so the scheduler's round trips stay few and the workers can still finish together. A worker whose run is
done takes the end of another's when the times measured so far say both then finish sooner, counting what it
computes again for a group it has not drawn. The caller appends the rows to the results folder."""
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

IN_FLIGHT = 2  # tasks queued per worker: the next one starts while the caller takes the last one's rows
WATCH_SECONDS = 1.0  # with no rows for this long, the caller checks whether a worker has left
FIRST_CHUNK = 3  # configurations in each of a worker's first tasks, before any drawing time is known
CHUNK_SECONDS = 2.0  # later tasks: about this long, or a third of the worker's run left if less (the last are single)
MIN_GAIN = 0.05  # seconds a take from another worker's run must save, by the times measured so far


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
             indices: List[int]) -> tuple:
    """On a worker: the rows (JSON text) of configurations `indices`, in order, by the worker's persistent measurer.
    Returns the worker's process id, one (index, row, asset builds, seconds) per configuration drawn, and the
    indices left undrawn: when a configuration after the first fails, the rows before it come back and the caller
    sends it again alone, so that its error comes through Dask (a failing first configuration raises here)."""
    global _measurer
    if threads is None:
        threads = _worker_threads()
    key = (spec_hash, threads, force, base_dir, out)
    rows: List[Tuple[int, str, int, float]] = []
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
        for k, index in enumerate(indices):
            builds = measurer.asset_builds
            start = time.perf_counter()
            try:
                row = measurer.measure(index, out)
            except Exception:
                if k == 0:
                    raise
                return os.getpid(), rows, indices[k:]
            rows.append((index, row, measurer.asset_builds - builds, time.perf_counter() - start))
    return os.getpid(), rows, []


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


class _Schedule:
    """Which configurations each worker draws next. Each worker has a run (a queue) of whole groups from _assign;
    its tasks take from the front of it. A worker whose run is empty takes the end of another's when that makes the
    later of the two finish sooner, by the drawing times measured so far: each worker's seconds per unit of
    estimated cost (StudyMeasurer.estimated_cost), and what a group's first configuration on a worker costs beyond
    that (its reference and heights computed again). A lost worker's run is taken whatever it costs."""

    def __init__(self, queues: List[Deque[int]], group_of: Dict[int, int], cost: Dict[int, float]):
        count = len(queues)
        self.queues, self.group_of, self.cost = queues, group_of, cost
        self.drawn: List[Set[int]] = [set() for _ in range(count)]  # groups each worker has been given
        self.lost: Set[int] = set()
        self.flight: List[List[int]] = [[] for _ in range(count)]  # configurations given and not yet back
        self.since = [0.0] * count  # when each worker began what it is drawing now (the caller's clock)
        self.seconds = [0.0] * count  # measured: seconds and estimated cost of configurations whose group the
        self.costs = [0.0] * count  # worker had drawn before
        self.entries: List[Tuple[int, float, float]] = []  # (worker, seconds, cost) of a group's first on a worker
        self.first: Set[Tuple[int, int]] = set()  # (worker, index): the group's first configuration on that worker
        self.again: Set[int] = set()  # configurations to send alone (one failed after others in its task)

    def rate(self, worker: int) -> Optional[float]:
        """Seconds per unit of estimated cost: the worker's own, else all workers' together; None before any."""
        if self.costs[worker] > 0:
            return self.seconds[worker] / self.costs[worker]
        total = sum(self.costs)
        return sum(self.seconds) / total if total > 0 else None

    def entry_cost(self) -> Optional[float]:
        """What a group's first configuration on a worker costs beyond its estimate, the mean of those measured."""
        extra = [seconds - cost * rate for worker, seconds, cost in self.entries
                 if (rate := self.rate(worker)) is not None]
        return max(0.0, sum(extra) / len(extra)) if extra else None

    def left(self, worker: int, now: float) -> float:
        """Seconds until the worker is done with what it has been given and its run, by its rate."""
        rate = self.rate(worker) or 0.0
        given = rate * sum(self.cost[i] for i in self.flight[worker])
        if self.flight[worker]:
            given = max(0.0, given - (now - self.since[worker]))
        return given + rate * sum(self.cost[i] for i in self.queues[worker])

    def take(self, own: int, now: float) -> bool:
        """Worker `own`'s run is empty: moves the end of another's to it when that pays. True if it moved any."""
        if any(self.queues[k] for k in self.lost):
            other = max(self.lost, key=lambda k: len(self.queues[k]))
            left = self.queues[other]
            taken = [left.pop() for _ in range(max(1, len(left) // 2))]
            self.queues[own].extend(reversed(taken))  # in the order its owner would have drawn them
            return True
        rate, entry = self.rate(own), self.entry_cost()
        if rate is None or entry is None:
            return False
        mine = self.left(own, now)
        best: Optional[Tuple[float, int, int]] = None  # (gain, worker, count)
        for other, left in enumerate(self.queues):
            if other == own or not left:
                continue
            theirs, their_rate = self.left(other, now), self.rate(other) or rate
            groups: Set[int] = set()
            cost = 0.0
            for count, index in enumerate(reversed(left), 1):
                groups.add(self.group_of[index])
                cost += self.cost[index]
                after = max(mine + entry * len(groups - self.drawn[own]) + rate * cost, theirs - their_rate * cost)
                gain = max(mine, theirs) - after
                if gain > MIN_GAIN and (best is None or gain > best[0]):
                    best = (gain, other, count)
        if best is None:
            return False
        _, other, count = best
        taken = [self.queues[other].pop() for _ in range(count)]
        self.queues[own].extend(reversed(taken))
        return True

    def chunk(self, own: int, now: float) -> List[int]:
        """The configurations of worker `own`'s next task (none: it has nothing left to draw)."""
        run = self.queues[own]
        if not run and (own in self.lost or not self.take(own, now)):
            return []
        if run[0] in self.again:
            indices = [run.popleft()]
        else:
            rate = self.rate(own)
            indices = []
            if rate is None:
                while run and len(indices) < FIRST_CHUNK:
                    indices.append(run.popleft())
            else:
                target = min(CHUNK_SECONDS / rate, sum(self.cost[i] for i in run) / 3) if rate > 0 else float("inf")
                total = 0.0
                while run and run[0] not in self.again and (not indices or total + self.cost[run[0]] <= target):
                    total += self.cost[run[0]]
                    indices.append(run.popleft())
        for index in indices:
            group = self.group_of[index]
            if group not in self.drawn[own]:
                self.drawn[own].add(group)
                self.first.add((own, index))
        if not self.flight[own]:
            self.since[own] = now
        self.flight[own] += indices
        return indices

    def finished(self, worker: int, drawn: List[Tuple[int, float]], undrawn: List[int], now: float) -> None:
        """A task of `worker` came back: (index, seconds) of the configurations drawn, and those it did not draw."""
        for index, seconds in drawn:
            self.flight[worker].remove(index)
            if (worker, index) in self.first:
                self.entries.append((worker, seconds, self.cost[index]))
            else:
                self.seconds[worker] += seconds
                self.costs[worker] += self.cost[index]
        for index in undrawn:
            self.flight[worker].remove(index)
        if undrawn:
            self.again.add(undrawn[0])
            self.queues[worker].extendleft(reversed(undrawn))
        self.since[worker] = now

    def give_back(self, worker: int, indices: List[int]) -> None:
        """A lost worker's task: its configurations go back to the front of its run, which the others then take."""
        for index in indices:
            self.flight[worker].remove(index)
        self.queues[worker].extendleft(reversed(indices))


def _take_back_from_lost_workers(client: Any, workers: List[str], futures: Dict[Any, Tuple[int, List[int]]],
                                 schedule: _Schedule) -> None:
    """A worker that has left the cluster (killed, or restarted by its nanny under a new address) never draws the
    configurations given only to it: they go back to the front of its run, which the other workers then take."""
    alive = set(client.scheduler_info()["workers"])
    for worker, address in enumerate(workers):
        if worker in schedule.lost or address in alive:
            continue
        schedule.lost.add(worker)
        for future, (owner, indices) in list(futures.items()):
            if owner == worker:
                del futures[future]
                future.cancel()
                schedule.give_back(worker, indices)


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
    futures: Dict[Any, Tuple[int, List[int]]] = {}  # future -> (the worker it was given to, its configurations)
    try:
        done = set(folder.done)
        pending = [i for i in range(folder.configurations) if i not in done]
        if pending:
            measurer = _qdmr.StudyMeasurer(spec, threads=1, force=force, base_dir=base_dir)
            queues, group_of = _assign(measurer, pending, len(workers))
            schedule = _Schedule(queues, group_of, {index: measurer.estimated_cost(index) for index in pending})
            tag = f"{folder.spec_hash[5:13]}-{os.getpid()}-{time.time_ns()}"
            tasks = 0

            def submit(worker: int) -> bool:
                nonlocal tasks
                indices = schedule.chunk(worker, time.perf_counter())
                if not indices:
                    return False
                # Only on that worker: Dask's own work stealing would move a queued task to an idle worker whose
                # renderers hold another group's reference and heights, and compute them again there.
                future = client.submit(_measure, spec, base_dir, force, threads, folder.spec_hash, out, indices,
                                       key=f"qdmr-study-{tag}-{tasks}", pure=False, workers=[workers[worker]],
                                       allow_other_workers=False)
                tasks += 1
                futures[future] = (worker, indices)
                return True

            def fill() -> None:
                """Every worker left with its tasks in flight (a worker done may take from another's run)."""
                for worker in range(len(workers)):
                    while worker not in schedule.lost and sum(1 for w, _ in futures.values() if w == worker) < IN_FLIGHT:
                        if not submit(worker):
                            break

            fill()
            while futures:
                try:
                    finished = wait(list(futures), timeout=WATCH_SECONDS, return_when="FIRST_COMPLETED").done
                except TimeoutError:
                    finished = set()
                for future in finished:
                    worker, _ = futures.pop(future)
                    pid, rows, undrawn = future.result()
                    for index, row, built, _seconds in rows:
                        folder.append(row)
                        result["rendered"] += 1
                        result["asset_builds"] += built
                    pids.add(pid)
                    schedule.finished(worker, [(index, seconds) for index, _, _, seconds in rows], undrawn,
                                      time.perf_counter())
                if not finished:
                    _take_back_from_lost_workers(client, workers, futures, schedule)
                fill()
                if not futures and any(schedule.queues):
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
