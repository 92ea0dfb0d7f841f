# Studies on a Dask cluster: a LocalCluster of 2 single-thread worker processes draws the configurations, one task
# each, with one persistent measurer per worker; the rows equal a one-process run's (deterministic columns bit for
# bit: JSON numbers of the same doubles), and an interrupted run resumes. The `if __name__ == "__main__"` guard that LocalCluster needs is pytest's own module.
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
