#!/usr/bin/env python3
"""A scene's first frame with an empty bake cache, stage by stage (issue #53: the terrain's prepare against its
draw). Each round renders the scene once per build, the builds alternating, each render with a new cache folder
(QDMR_CACHE_DIR) and one second apart; the table holds the median and range over the rounds of prepare, draw,
total (`time_ms`), the meshes, the textures (from the first one's start to the last one's end: they are built side
by side) and each kind of derived item (the same), and in how many rounds prepare <= draw.

  bench/cold_prepare.py [-n 8] [--scene scenes/terrain.json] [--threads 2] QDMR [QDMR ...]

Several binaries (e.g. a copy of build/release/qdmr taken before a change, then the new one) give one column each,
measured side by side. Wall times grow with anything else running: the load average is printed before and after.
"""
import argparse
import collections
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from bench_util import cpu_model

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def spans(steps, key):
    """Wall time from the first matching step's start to the last one's end (0 when none matches)."""
    chosen = [s for s in steps if key(s)]
    if not chosen:
        return 0.0
    return max(s["start_ms"] + s["ms"] for s in chosen) - min(s["start_ms"] for s in chosen)


def render(qdmr, scene, threads):
    with tempfile.TemporaryDirectory() as folder:
        env = dict(os.environ, QDMR_CACHE_DIR=folder)
        stats = os.path.join(folder, "s.json")
        subprocess.run([qdmr, "render", scene, "--threads", str(threads), "-o", os.path.join(folder, "t.png"),
                        "--stats", stats], check=True, capture_output=True, env=env)
        with open(stats) as f:
            s = json.load(f)
    t, steps = s["time_ms"], s["prepare"]["steps"]
    row = {"prepare": t["prepare"], "draw": t["draw"], "total": t["total"],
           "meshes": spans(steps, lambda x: x["item"].startswith("mesh")),
           "textures": spans(steps, lambda x: x["item"].startswith("texture"))}
    for kind in sorted({x["what"] for x in steps if x["item"].startswith("derived")}):
        row[kind] = spans(steps, lambda x, k=kind: x["item"].startswith("derived") and x["what"] == k)
    return row, s.get("isa", "?")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("qdmr", nargs="+", help="qdmr binaries, one column each")
    parser.add_argument("-n", "--rounds", type=int, default=8)
    parser.add_argument("--scene", default=os.path.join(ROOT, "scenes", "terrain.json"))
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    for q in args.qdmr:
        if not os.access(q, os.X_OK):
            sys.exit(f"cold_prepare.py: {q}: not an executable")
    print(f"load before: {' '.join(f'{v:.2f}' for v in os.getloadavg())}", flush=True)
    rows = {q: collections.defaultdict(list) for q in args.qdmr}
    isa = {}
    for r in range(args.rounds):
        order = args.qdmr if r % 2 == 0 else list(reversed(args.qdmr))
        for q in order:
            row, isa[q] = render(q, args.scene, args.threads)
            for k, v in row.items():
                rows[q][k].append(v)
            time.sleep(1)
        if sys.stderr.isatty():  # progress on a terminal only
            print(f"round {r + 1} of {args.rounds}", file=sys.stderr, flush=True)
    print(f"load after: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"{cpu_model()}, {args.threads} threads, {os.path.relpath(args.scene, ROOT)}, {args.rounds} rounds, cold bake cache")
    print("| ms | " + " | ".join(f"{os.path.basename(q)} ({isa[q]})" for q in args.qdmr) + " |")
    print("|---|" + "---|" * len(args.qdmr))
    keys = list(rows[args.qdmr[0]].keys())
    for k in keys:
        cells = []
        for q in args.qdmr:
            v = rows[q].get(k, [0.0])
            cells.append(f"{statistics.median(v):.0f} ({min(v):.0f}–{max(v):.0f})")
        print(f"| {k} | " + " | ".join(cells) + " |")
    met = [sum(1 for p, d in zip(rows[q]["prepare"], rows[q]["draw"]) if p <= d) for q in args.qdmr]
    print("| prepare <= draw | " + " | ".join(f"{m} of {args.rounds}" for m in met) + " |")


if __name__ == "__main__":
    main()
