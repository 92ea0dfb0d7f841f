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
