# Studies on a Dask cluster: a LocalCluster of 2 single-thread worker processes draws one shard each; the merged
# rows equal a one-process run's (deterministic columns bit for bit: JSON numbers of the same doubles), and an
# interrupted run resumes. The `if __name__ == "__main__"` guard that LocalCluster needs is pytest's own module.
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
    assert spread["shards"] == 2 and spread["processes"] == 2  # both workers drew
    assert spread["total"] == one["total"] == 6 and spread["rendered"] == 6
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
    # As if the first run had stopped after shard 1 of 2 finished: its folder is there, shard 2's is not.
    first = qdmr.study.run(SPEC, out / "shards" / "1-of-2", shard=(1, 2), threads=1)
    resumed = qdmr.study.run(SPEC, out, client=client)
    assert resumed["resumed"] == first["rendered"] and resumed["rendered"] == 6 - first["rendered"]
    assert [r["index"] for r in qdmr.study.load(out)] == list(range(6))
