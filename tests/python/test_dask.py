# Studies on a Dask cluster: a LocalCluster of 2 single-thread worker processes draws the configurations, one task
# each, with one persistent measurer per worker; the rows equal a one-process run's (deterministic columns bit for
# bit: JSON numbers of the same doubles), and an interrupted run resumes. The same through a scheduler and workers
# started as separate commands, as a batch job starts them. The `if __name__ == "__main__"` guard that LocalCluster needs is pytest's own module.
import os
import subprocess
import sys

import pytest

import qdmr
from conftest import PLANE

distributed = pytest.importorskip("distributed")

SPEC = {"scene": PLANE, "width": 64, "height": 36, "frames": 1, "warmup": 0,
        "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["pom", "relief", "qdm"]},
                 {"name": "elevation", "camera": "elevation", "values": [15, 45]}],
        "baseline": {"technique": "relief"}}


def deterministic(rows):
    return [(r["index"], r["config"], r["deterministic"]) for r in rows]


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def test_dask_rows_equal_one_process_rows(client, tmp_path):
    one = qdmr.study.run(SPEC, tmp_path / "one", threads=1)
    spread = qdmr.study.run(SPEC, tmp_path / "dask", client=client)
    assert spread["processes"] == 2  # both workers drew
    assert spread["total"] == one["total"] == 6 and spread["rendered"] == 6
    # Two asset sets (QDM's, and POM's and relief's): a worker keeps its renderers across tasks, so at most one
    # build per set and worker, not one per configuration.
    assert one["asset_builds"] == 2 and spread["asset_builds"] <= 4
    rows = qdmr.study.load(tmp_path / "dask")
    assert deterministic(rows) == deterministic(qdmr.study.load(tmp_path / "one"))
    for name in ("study.json", "results.json", "results.csv", "pareto.csv"):
        assert (tmp_path / "dask" / name).is_file()
    again = qdmr.study.run(SPEC, tmp_path / "dask", client=client)  # done: nothing to draw
    assert again["rendered"] == 0 and again["resumed"] == 6
    with pytest.raises(qdmr.SceneError, match="resume"):
        qdmr.study.run(SPEC, tmp_path / "dask", client=client, resume=False)


def test_an_interrupted_dask_run_resumes(client, tmp_path):
    out = tmp_path / "s"
    # As if a run had been stopped after its first two rows: the folder of a one-process run, cut to them.
    qdmr.study.run(SPEC, out, threads=1)
    rows = (out / "rows.jsonl").read_text().splitlines(keepends=True)
    (out / "rows.jsonl").write_text("".join(rows[:2]))
    resumed = qdmr.study.run(SPEC, out, client=client)
    assert resumed["resumed"] == 2 and resumed["rendered"] == 4
    assert [r["index"] for r in qdmr.study.load(out)] == list(range(6))


# Two height fields (stored plain and BC3-compressed) x two techniques: each field's exact reference and heights are
# computed once per process that draws any configuration of it.
FIELDS = {"scene": PLANE, "width": 64, "height": 36, "frames": 1, "warmup": 0, "metrics": ["time", "error"],
          "axes": [{"name": "compression", "path": "/materials/bricks/layers/0/height/compression",
                    "values": ["none", "bc3"]},
                   {"name": "technique", "path": "/materials/bricks/technique/name", "values": ["qdm", "pom"]},
                   {"name": "precision", "path": "/materials/bricks/sampling/precision", "values": ["exact", "hw8"]}],
          "baseline": {"compression": "none", "precision": "exact"}}


def test_configurations_are_grouped_by_the_reference_and_heights_they_share():
    from qdmr import _dask, _qdmr
    measurer = _qdmr.StudyMeasurer(FIELDS)
    everything = list(range(8))  # compression is the outer axis: 0-3 plain, 4-7 BC3
    groups = measurer.share_groups(everything)
    assert sorted(sorted(g) for g in groups) == [[0, 1, 2, 3], [4, 5, 6, 7]]
    for group in groups:  # each in the order that re-prepares least
        assert group == measurer.reuse_order(sorted(group))
    # Two workers: a field each (not a technique each, which would trace both references twice).
    runs, group_of = _dask._assign(measurer, everything, 2)
    assert sorted(sorted(run) for run in runs) == [[0, 1, 2, 3], [4, 5, 6, 7]]
    assert len({group_of[i] for i in runs[0]}) == 1
    # One worker: everything; three: a group is cut in two (each half computes its reference once).
    assert [sorted(run) for run in _dask._assign(measurer, everything, 1)[0]] == [everything]
    runs = sorted((sorted(run) for run in _dask._assign(measurer, everything, 3)[0]), key=len)
    assert all(runs) and runs[2] in ([0, 1, 2, 3], [4, 5, 6, 7])
    assert sorted(runs[0] + runs[1]) == sorted(set(everything) - set(runs[2]))
    with pytest.raises(qdmr.SceneError, match="does not exist"):
        measurer.share_groups([8])


def test_a_worker_takes_from_another_run_only_when_it_pays():
    from collections import deque
    from qdmr import _dask
    group_of = {i: 0 if i < 20 else 1 for i in range(40)}
    # Its own run first, in order.
    queues = [deque([0, 1]), deque([20, 21, 22])]
    assert _dask._next(queues, 0, group_of, set(), set()) == 0
    # Done, and the other run is short and of a group it has not drawn: nothing (it would compute that group's
    # reference again for two configurations).
    queues = [deque(), deque([20, 21, 22])]
    assert _dask._next(queues, 0, group_of, {0}, set()) is None and list(queues[1]) == [20, 21, 22]
    # Of a group it has drawn: the back half, in order.
    queues = [deque(), deque([20, 21, 22, 23])]
    assert _dask._next(queues, 0, group_of, {0, 1}, set()) == 22
    assert list(queues[0]) == [23] and list(queues[1]) == [20, 21]
    # A long run of another group: its back half.
    queues = [deque(), deque(range(20, 20 + _dask.MIN_STEAL))]
    assert _dask._next(queues, 0, group_of, {0}, set()) == 20 + _dask.MIN_STEAL // 2
    assert len(queues[1]) == _dask.MIN_STEAL // 2
    # A lost worker's run, however short.
    queues = [deque(), deque([20])]
    assert _dask._next(queues, 0, group_of, {0}, {1}) == 20


def test_a_lost_worker_s_configurations_are_drawn_by_the_others(tmp_path):
    # A worker killed in the middle of the run (its nanny starts another under a new address): the configurations
    # given to it go to the worker left, and the rows are those of a one-process run.
    import signal
    import threading
    import time
    spec = dict(FIELDS, width=320, height=180, frames=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        killed = {}

        def kill_one_after_the_first_row():
            rows = tmp_path / "dask" / "rows.jsonl"
            while not (rows.is_file() and rows.read_text().count("\n") >= 1):
                time.sleep(0.005)
            killed["rows"] = rows.read_text().count("\n")
            os.kill(pids[sorted(pids)[1]], signal.SIGKILL)

        killer = threading.Thread(target=kill_one_after_the_first_row)
        killer.start()
        spread = qdmr.study.run(spec, tmp_path / "dask", client=client)
        killer.join()
    assert killed["rows"] < 8  # killed while configurations were left
    assert spread["rendered"] == 8
    qdmr.study.run(spec, tmp_path / "one", threads=1)
    assert deterministic(qdmr.study.load(tmp_path / "dask")) == deterministic(qdmr.study.load(tmp_path / "one"))


def test_any_client_scheduler_and_workers_started_as_commands(tmp_path):
    # The shape of a cluster job (dask-jobqueue's Slurm script, a Kubernetes pod): a scheduler process writes its
    # address to a shared file, worker processes started apart (each under its nanny) connect through it, and the
    # caller's Client does too. qdmr.study.run only sees the Client.
    scheduler_file = tmp_path / "scheduler.json"
    command = [sys.executable, "-m"]
    started = [subprocess.Popen(command + ["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                                           "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(2):
            started.append(subprocess.Popen(
                command + ["distributed.cli.dask_worker", "--scheduler-file", str(scheduler_file), "--nthreads", "1",
                           "--no-dashboard", "--death-timeout", "60"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=os.environ.copy()))
        with distributed.Client(scheduler_file=str(scheduler_file), timeout="60s") as client:
            client.wait_for_workers(2, timeout=60)
            spread = qdmr.study.run(SPEC, tmp_path / "dask", client=client)
        assert spread["processes"] == 2 and spread["rendered"] == 6
        one = qdmr.study.run(SPEC, tmp_path / "one", threads=1)
        assert deterministic(qdmr.study.load(tmp_path / "dask")) == deterministic(qdmr.study.load(tmp_path / "one"))
        assert one["total"] == 6
    finally:
        for process in reversed(started):  # the workers first, then the scheduler
            process.terminate()
        for process in started:
            process.wait(timeout=60)


def test_the_cluster_snippets_call_only_the_documented_api():
    # docs/python.md's dask-jobqueue and dask-kubernetes snippets cannot run here (neither package is in Debian):
    # what can be checked is that they are Python and call qdmr.study.run as it is, with a client.
    import ast
    import inspect
    from conftest import SOURCE_DIR
    text = open(os.path.join(SOURCE_DIR, "docs", "python.md")).read()
    blocks = [b.split("\n", 1)[1] for b in text.split("```")[1::2] if b.startswith("python\n")]
    snippets = [b for b in blocks if "dask_jobqueue" in b or "dask_kubernetes" in b]
    assert snippets
    run = inspect.signature(qdmr.study.run)
    calls = [node for tree in map(ast.parse, snippets) for node in ast.walk(tree)
             if isinstance(node, ast.Call) and ast.unparse(node.func) == "qdmr.study.run"]
    assert calls
    for call in calls:
        run.bind(*[None] * len(call.args), **{k.arg: None for k in call.keywords})  # TypeError when they differ
        assert "client" in {k.arg for k in call.keywords}
