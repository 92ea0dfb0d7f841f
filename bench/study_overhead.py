#!/usr/bin/env python3
"""What `qdmr study` costs beyond drawing (docs/performance.md, "qdmr study").

A 100-configuration study of the canonical plane at 480x270 (technique x 10 elevations x 2 depth scales, plus
POM step counts), metrics time and iterations only (no reference frame), 3 timed frames after 1 warm-up each:
its wall time against the sum of its warm draw times (each row's median draw time x the 4 frames it drew).
Target: <= 1.2x.

  python3 bench/study_overhead.py [-n 3] [-B build/release]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_util  # noqa: E402


def main():
    args = bench_util.arguments(__doc__.split("\n")[0]).parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    spec = {
        "scene": os.path.join(bench_util.ROOT, "scenes", "plane.json"), "width": 480, "height": 270,
        "frames": 3, "warmup": 1, "metrics": ["time", "iterations"],
        "axes": [
            {"name": "technique", "path": "/materials/bricks/technique/name", "values": ["normal", "pom", "relief", "qdm", "csm"]},
            {"name": "elevation", "camera": "elevation", "range": {"from": 10, "to": 80, "steps": 10}},
            {"name": "depth", "path": "/materials/bricks/technique/depth_scale", "values": [0.02, 0.05]},
        ],
    }
    load_before = os.getloadavg()
    walls, ratios = [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.json")
        with open(path, "w") as f:
            json.dump(spec, f)
        for k in range(args.n):
            out = os.path.join(tmp, f"r{k}")
            start = time.perf_counter()
            subprocess.run([qdmr, "study", path, "-o", out], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall = time.perf_counter() - start
            with open(os.path.join(out, "results.json")) as f:
                rows = json.load(f)["rows"]
            draws = sum(r["timing"]["draw_ms_median"] * (spec["frames"] + spec["warmup"]) for r in rows) / 1000.0
            prepares = sum(r["timing"]["prepare_ms"] for r in rows) / 1000.0
            walls.append(wall)
            ratios.append(wall / draws)
            print(f"run {k + 1}: {len(rows)} configurations, wall {wall:.2f} s, warm draws {draws:.2f} s, ratio "
                  f"{wall / draws:.2f}; of the rest {prepares:.2f} s preparing (once per technique), so without it "
                  f"{(wall - prepares) / draws:.2f}")
    load_after = os.getloadavg()
    print(f"median ratio wall / warm draws: {statistics.median(ratios):.2f} (target <= 1.2); "
          f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f}; {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
