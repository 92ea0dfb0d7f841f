#!/usr/bin/env python3
"""The report generator on hand-made results folders: what the page holds, and every bad input refused.

  report_test.py REPORT_PACKAGE_DIR      (the folder holding qdmr_report/)
"""
import hashlib
import io
import json
import os
import sys
import tempfile
import unittest
from contextlib import redirect_stderr, redirect_stdout

sys.path.insert(0, sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "../../report"))

import numpy  # noqa: E402
import OpenImageIO as oiio  # noqa: E402

from qdmr_report.__main__ import main  # noqa: E402

SPEC_HASH = "sha1:0123456789abcdef0123456789abcdef01234567"


def write_image(path, pixels):
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2],
                          oiio.UINT8 if path.endswith(".png") else oiio.FLOAT)
    out = oiio.ImageOutput.create(path)
    assert out.open(path, spec), oiio.geterror()
    assert out.write_image(pixels.astype(numpy.float32)), out.geterror()
    out.close()


def make_results(folder, rows=None, configurations=None, shard=(1, 1), images=True, cache=False):
    """A results folder as `qdmr study` writes it: 3 techniques x 4 elevations (x 2 layouts with cache)."""
    os.makedirs(folder, exist_ok=True)
    axes = ["technique", "elevation"] + (["layout"] if cache else [])
    spec = {"scene": "x.json", "comment": "hand-made", "axes": [
        {"name": "technique", "path": "/materials/m/technique/name", "values": ["pom", "relief", "qdm"]},
        {"name": "elevation", "camera": "elevation", "range": {"from": 1, "to": 90, "steps": 4, "scale": "log"}}]}
    if cache:
        spec["axes"].append({"name": "layout", "path": "/materials/m/sampling/layout", "values": ["linear", "morton"]})
    made = []
    index = 0
    for t, technique in enumerate(["pom", "relief", "qdm"]):
        for e, elevation in enumerate([1.0, 4.48, 20.1, 90.0]):
            for layout in (["linear", "morton"] if cache else [None]):
                config = {"technique": technique, "elevation": elevation}
                det = {"hash": f"sha1:{index:040x}", "nonfinite": 0, "iterations_mean": 10.0 + t + e,
                       "iterations_max": 40 + index, "error_p99": 0.1 * (t + 1) * (4 - e) + 0.01 * index,
                       "missed_fraction": 0.01 * (3 - t) * (4 - e)}
                if layout:
                    config["layout"] = layout
                    det["cache_miss_ratio"] = 0.3 if layout == "linear" else 0.2
                made.append({"index": index, "config": config, "deterministic": det,
                             "timing": {"draw_ms_median": 1.0 + 2 * t + 0.5 * e + 0.01 * index}})
                index += 1
    rows = made if rows is None else rows
    header = {"spec_hash": SPEC_HASH, "spec": spec, "spec_file": "studies/hand.json", "qdmr_version": "0.test",
              "bits_version": 1, "configurations": configurations or len(made), "shard": list(shard), "axes": axes,
              "group_by": "technique", "machine": {"cpu": "test", "isa": "avx2", "threads": 2, "cores": 2}}
    with open(os.path.join(folder, "study.json"), "w") as f:
        json.dump(header, f)
    with open(os.path.join(folder, "rows.jsonl"), "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    with open(os.path.join(folder, "results.json"), "w") as f:
        json.dump(dict(header, rows=rows, run={"wall_seconds": 12.5, "shards": 1}), f)
    with open(os.path.join(folder, "pareto.csv"), "w") as f:
        f.write("front,index\n")
        for r in rows[:2]:
            f.write(f"all,{r['index']}\n")
        for r in rows:
            if r["config"]["elevation"] == 90.0:
                f.write(f"technique={r['config']['technique']},{r['index']}\n")
    if images:
        os.makedirs(os.path.join(folder, "images"), exist_ok=True)
        rng = numpy.random.default_rng(7)
        for r in rows[:4]:
            i = r["index"]
            image = rng.random((24, 32, 3))
            reference = image.copy()
            reference[4:12, 8:20] = 0.0  # the artifact the crop must find
            error = numpy.zeros((24, 32, 1))
            error[4:12, 8:20] = 3.0
            write_image(os.path.join(folder, "images", f"{i}.png"), image)
            write_image(os.path.join(folder, "images", f"{i}.reference.png"), reference)
            write_image(os.path.join(folder, "images", f"{i}.error_texels.exr"), error)
            write_image(os.path.join(folder, "images", f"{i}.iterations.exr"), error * 10)
    return rows


def checksums(folder):
    sums = {}
    for root, _, files in os.walk(folder):
        for name in files:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                sums[os.path.relpath(path, folder)] = hashlib.sha1(f.read()).hexdigest()
    return sums


def run(*args):
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


class Report(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.results = os.path.join(self.tmp.name, "results")
        self.report = os.path.join(self.tmp.name, "report")

    def tearDown(self):
        self.tmp.cleanup()

    def test_page_holds_every_part(self):
        rows = make_results(self.results, cache=True)
        before = checksums(self.results)
        code, out, err = run(self.results, "-o", self.report, "--crop", "16")
        self.assertEqual(code, 0, err)
        self.assertEqual(out.strip(), os.path.join(self.report, "index.html"))
        with open(os.path.join(self.report, "index.html")) as f:
            page = f.read()
        # Pareto charts per technique and overall, the elevation line chart, the cache bars, two colour keys.
        self.assertEqual(page.count("<svg"), 4 + 1 + 1 + 2)
        for index in range(len(rows)):
            self.assertTrue(f"<tr id=row{index}" in page, f"<tr id=row{index}")
        for index in range(4):  # the configurations that kept pictures have sections; the charts link them
            self.assertTrue(f"id=c{index}" in page, f"id=c{index}")
            self.assertTrue(f"#c{index}" in page, f"#c{index}")
        self.assertIn("#row5", page)  # without pictures a point links to the table row
        self.assertTrue("0.test" in page, "0.test")
        self.assertTrue("12.5 s wall" in page, "12.5 s wall")
        self.assertTrue("cache_miss_ratio" in page, "cache_miss_ratio")
        # Nothing from the network: the only URLs are the XML namespaces of the inline SVG.
        urls = set(u.split('"')[0] for u in page.replace("'", '"').split("http")[1:])
        self.assertLessEqual(urls, {"://www.w3.org/2000/svg", "://www.w3.org/1999/xlink"})
        for name in page.split("src='images/")[1:]:
            self.assertTrue(os.path.isfile(os.path.join(self.report, "images", name.split("'")[0])), name)
        # The worst crop is placed on the artifact (rows 4..11, columns 8..19): the windows holding all of it start
        # at x 4..8, y 0..4; ties go to the top-most, then left-most.
        self.assertTrue("crop at (4, 0), 16 x 16" in page, "crop at (4, 0), 16 x 16")
        self.assertEqual(checksums(self.results), before)  # the results are never written

    def test_budget_table(self):
        # missed = 0.01 (3 - t)(4 - e): under 2.5 % only relief at elevation 90 and QDM at 20.1 and 90; pom, the time
        # base, is fastest at elevation 1 (1.00 ms with linear, 1.01 ms with morton).
        make_results(self.results, cache=True)
        for name in ("study.json", "results.json"):
            with open(os.path.join(self.results, name)) as f:
                content = json.load(f)
            content["spec"]["budget"] = {"missed_fraction": 0.025, "per": ["layout"],
                                         "relative_to": {"technique": "pom"}}
            with open(os.path.join(self.results, name), "w") as f:
                json.dump(content, f)
        code, _, err = run(self.results, "-o", self.report)
        self.assertEqual(code, 0, err)
        with open(os.path.join(self.report, "index.html")) as f:
            page = f.read()
        budget = page[page.index("<section id=budget>"):page.index("</section>", page.index("<section id=budget>"))]
        # relief, linear: row 14 (elevation 90), 4.64 ms over 1.00; QDM, linear: row 20 (elevation 20.1), 6.20 ms.
        self.assertIn("<b>4.64x</b>", budget)
        self.assertIn("<b>6.20x</b>", budget)
        self.assertIn("elevation=20.1", budget)
        self.assertIn("#row20", budget)
        self.assertNotIn("<td>pom</td>", budget)  # the time base is not a row of its own
        # Morton: same rows one index later, over pom's 1.01 ms.
        self.assertIn(f"<b>{4.65 / 1.01:.2f}x</b>", budget)

    def test_a_second_report_replaces_the_first(self):
        make_results(self.results)
        self.assertEqual(run(self.results, "-o", self.report)[0], 0)
        with open(os.path.join(self.report, "stale.txt"), "w") as f:
            f.write("from before")
        self.assertEqual(run(self.results, "-o", self.report)[0], 0)
        self.assertFalse(os.path.exists(os.path.join(self.report, "stale.txt")))
        self.assertEqual([n for n in os.listdir(self.tmp.name) if n.startswith(".report")], [])

    def refused(self, fragment, *args):
        code, out, err = run(*args)
        self.assertEqual(code, 2, err)
        self.assertIn(fragment, err)
        self.assertEqual(len(err.strip().splitlines()), 1, err)  # one line
        self.assertEqual([n for n in os.listdir(self.tmp.name) if n.startswith(".report")], [])  # nothing half

    def test_bad_inputs(self):
        self.refused("results: not a folder", self.results, "-o", self.report)
        os.makedirs(self.results)
        self.refused("study.json: missing", self.results, "-o", self.report)
        make_results(self.results, rows=[])
        self.refused("rows.jsonl: empty", self.results, "-o", self.report)
        rows = make_results(self.results)
        with open(os.path.join(self.results, "rows.jsonl"), "a") as f:
            f.write('{"index": 3, "config"')
        self.refused("rows.jsonl: line 13 is half-written", self.results, "-o", self.report)
        make_results(self.results, rows=rows[:5], configurations=12)
        self.refused("rows.jsonl: 5 of 12 configurations", self.results, "-o", self.report)
        self.assertEqual(run(self.results, "-o", self.report, "--partial")[0], 0)
        make_results(self.results, rows=rows[:5], configurations=12, shard=(2, 4))
        self.refused("this folder is shard 2 of 4: merge the shards first", self.results, "-o", self.report)
        make_results(self.results)
        with open(os.path.join(self.results, "results.json")) as f:
            other = json.load(f)
        other["spec_hash"] = "sha1:" + "f" * 40
        with open(os.path.join(self.results, "results.json"), "w") as f:
            json.dump(other, f)
        self.refused("results.json: belongs to another spec", self.results, "-o", self.report)
        make_results(self.results)
        with open(os.path.join(self.results, "rows.jsonl"), "a") as f:
            f.write(json.dumps(dict(rows[0], index=99)) + "\n")
        self.refused("line 13: configuration 99 does not exist", self.results, "-o", self.report)

    def test_never_writes_over_the_results_or_other_files(self):
        make_results(self.results)
        before = checksums(self.results)
        self.refused("is or holds the study's results", self.results, "-o", self.results)
        self.refused("is or holds the study's results", self.results, "-o", self.tmp.name)
        self.refused("inside the study's images", self.results, "-o", os.path.join(self.results, "images", "r"))
        other = os.path.join(self.tmp.name, "other")
        os.makedirs(other)
        with open(os.path.join(other, "notes.txt"), "w") as f:
            f.write("mine")
        self.refused("not a qdmr report", self.results, "-o", other)
        self.refused("--crop: must be from 8 to 1024", self.results, "-o", self.report, "--crop", "2")
        self.assertEqual(checksums(self.results), before)
        self.assertEqual(os.listdir(other), ["notes.txt"])


if __name__ == "__main__":
    unittest.main(verbosity=1)
