# Studies and checks in process: the same rows as `qdmr study`, resume, load as dicts and as a DataFrame; check.run's
# results as `qdmr check` reports them.
import json
import os

import pytest

import qdmr
from conftest import PLANE, run_cli

# Two techniques at two elevations on the canonical plane, small: a few seconds.
SPEC = {"scene": PLANE, "width": 64, "height": 36, "frames": 1, "warmup": 0,
        "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["pom", "qdm"]},
                 {"name": "elevation", "camera": "elevation", "values": [20, 60]}],
        "baseline": {"technique": "pom"}}


def deterministic(rows):
    return [(r["index"], r["config"], r["deterministic"]) for r in sorted(rows, key=lambda r: r["index"])]


def test_same_rows_and_files_as_the_command(cli, tmp_path):
    spec_file = tmp_path / "spec.json"
    spec_file.write_text(json.dumps(SPEC))
    run_cli(cli, "study", str(spec_file), "-o", str(tmp_path / "cli"), "--threads", "2")
    run = qdmr.study.run(spec_file, tmp_path / "py", threads=1)
    assert run["total"] == 4 and run["rendered"] == 4 and run["resumed"] == 0
    for name in ("study.json", "rows.jsonl", "results.json", "results.csv", "pareto.csv"):
        assert (tmp_path / "py" / name).is_file(), name
    rows = qdmr.study.load(tmp_path / "py")
    assert [r["index"] for r in rows] == [0, 1, 2, 3]
    assert deterministic(rows) == deterministic(qdmr.study.load(tmp_path / "cli"))
    results = json.loads((tmp_path / "py" / "results.json").read_text())
    assert results["spec_hash"] == json.loads((tmp_path / "cli" / "study.json").read_text())["spec_hash"]
    # A dict spec: the same rows (its paths resolve against base_dir).
    from_dict = qdmr.study.run({**SPEC, "scene": os.path.relpath(PLANE, tmp_path)}, tmp_path / "dict",
                               base_dir=tmp_path, threads=1)
    assert from_dict["rendered"] == 4
    assert deterministic(qdmr.study.load(tmp_path / "dict")) == deterministic(rows)


def test_resume_and_refusal(tmp_path):
    out = tmp_path / "s"
    qdmr.study.run(SPEC, out, threads=1)
    again = qdmr.study.run(SPEC, out, threads=1)  # resume=True by default: nothing left to draw
    assert again["rendered"] == 0 and again["resumed"] == 4
    with pytest.raises(qdmr.SceneError, match="--resume"):
        qdmr.study.run(SPEC, out, resume=False)
    with pytest.raises(qdmr.SceneError, match="another spec"):
        qdmr.study.run({**SPEC, "width": 48}, out)


def test_rows_as_a_dataframe(tmp_path):
    pandas = pytest.importorskip("pandas")
    qdmr.study.run(SPEC, tmp_path / "s", threads=1)
    frame = qdmr.study.load(tmp_path / "s", as_frame=True)
    assert isinstance(frame, pandas.DataFrame) and len(frame) == 4
    assert list(frame["config.technique"]) == ["pom", "pom", "qdm", "qdm"]
    assert "deterministic.error_p99" in frame.columns and "timing.draw_ms_median" in frame.columns


def test_checks_in_process(cli, tmp_path):
    manifest = tmp_path / "checks.json"
    check = {"name": "plane", "scene": PLANE, "width": 48, "height": 27, "outputs": ["color", "depth"]}
    manifest.write_text(json.dumps({"bits_version": qdmr.bits_version, "checks": [check]}))
    first = qdmr.check.run(manifest, update=True, diff_dir=tmp_path / "diffs")  # writes the hashes
    assert [r["status"] for r in first] == ["UPDATED"]
    results = qdmr.check.run(manifest, diff_dir=tmp_path / "diffs")
    assert results[0]["name"] == "plane" and results[0]["status"] == "PASS" and results[0]["passed"]
    assert results[0]["hashes"] == json.loads(manifest.read_text())["checks"][0]["hash"]
    # A wrong hash fails, with a diff folder, as `qdmr check` does.
    document = json.loads(manifest.read_text())
    document["checks"][0]["hash"]["color"] = "sha1:" + "0" * 40
    manifest.write_text(json.dumps(document))
    failed = qdmr.check.run(manifest, diff_dir=tmp_path / "diffs")
    assert failed[0]["status"] == "FAIL" and not failed[0]["passed"] and failed[0]["lines"]
