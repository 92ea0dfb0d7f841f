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


def schedule_of(*runs):
    """A _Schedule of two workers' runs (group 0: configurations below 20, group 1 the others), every estimated cost 1."""
    from collections import deque
    from qdmr import _dask
    indices = [i for run in runs for i in run]
    return _dask._Schedule([deque(run) for run in runs], {i: 0 if i < 20 else 1 for i in indices},
                           {i: 1.0 for i in indices})


def test_tasks_shrink_to_single_configurations_at_the_end_of_a_run():
    from qdmr import _dask
    s = schedule_of(range(20), [])
    # Before any drawing time is known: FIRST_CHUNK configurations.
    assert s.chunk(0, 0.0) == list(range(_dask.FIRST_CHUNK)) == [0, 1, 2]
    # The group's first costs 0.9 s beyond its estimate (its reference and heights), the others 0.1 s a unit.
    s.finished(0, [(0, 1.0), (1, 0.1), (2, 0.1)], [], 0.3)
    assert s.rate(0) == pytest.approx(0.1) and s.entry_cost() == pytest.approx(0.9)
    # Then a third of the run left (17 configurations: 5), fewer and fewer, the last ones single.
    sizes = []
    while chunk := s.chunk(0, 0.3):
        sizes.append(len(chunk))
        s.finished(0, [(i, 0.1) for i in chunk], [], 0.3)
    assert sizes == [5, 4, 2, 2, 1, 1, 1, 1] and sum(sizes) == 17
    # CHUNK_SECONDS bounds a task of a long run: 2 s at 0.1 s a unit.
    s = schedule_of(range(20), range(20, 20 + 300))
    s.finished(1, [(i, 0.1) for i in s.chunk(1, 0.0)], [], 0.3)
    assert len(s.chunk(1, 0.3)) == int(_dask.CHUNK_SECONDS / 0.1)


def test_a_worker_takes_from_another_run_only_when_it_pays():
    # Worker 1 has drawn 3 of its 20 configurations: 0.1 s each, its group's first 0.9 s more.
    def started(s):
        assert s.chunk(1, 0.0) == [20, 21, 22]
        s.finished(1, [(20, 1.0), (21, 0.1), (22, 0.1)], [], 0.3)
        return s
    # 17 left (1.7 s): worker 0, done, takes the last 4 (0.9 s for the group's reference and heights, then 0.4 s:
    # both finish 1.3 s from now), and draws them in its owner's order.
    s = started(schedule_of([], range(20, 40)))
    assert s.chunk(0, 0.3) == [36] and list(s.queues[0]) == [37, 38, 39] and s.queues[1][-1] == 35
    # 8 left (0.8 s): computing the group's reference and heights again would finish later than leaving them.
    s = started(schedule_of([], range(20, 31)))
    assert s.chunk(0, 0.3) == [] and list(s.queues[1]) == list(range(23, 31))
    # Of a group worker 0 has drawn: half of them.
    s = started(schedule_of([], range(20, 31)))
    s.drawn[0].add(1)
    assert s.chunk(0, 0.3) == [27] and list(s.queues[1]) == list(range(23, 27))
    # What worker 1 is drawing now counts, less the time since it began: 8 left after 3 given 0.1 s ago.
    s = started(schedule_of([], range(20, 34)))
    assert s.chunk(1, 0.3) == [23, 24, 25]
    assert s.left(1, 0.4) == pytest.approx(0.2 + 0.8)
    # A lost worker's run, however short: the back half.
    s = started(schedule_of([], range(20, 25)))
    s.lost.add(1)
    assert s.chunk(0, 0.3) == [24] and list(s.queues[1]) == [23]


def test_a_configuration_that_fails_after_others_is_sent_again_alone():
    s = schedule_of(range(10), [])
    assert s.chunk(0, 0.0) == [0, 1, 2]
    s.finished(0, [(0, 1.0)], [1, 2], 0.5)  # 1 failed: 0's row came back, 1 and 2 were not drawn
    assert s.chunk(0, 0.5) == [1]
    assert s.flight[0] == [1]


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
