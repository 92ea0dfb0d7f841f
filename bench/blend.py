#!/usr/bin/env python3
"""The talk's surface blend table, rebuilt on this machine.

scenes/surface_blend_4layers.json (four layers, per-vertex weights, full screen) rendered as normal mapping
(technique name=normal, the blend kept), relief mapping with alpha blend, POM with alpha blend and POM with
height blend (the scene as stored). Runs alternate inside each round; medians of the raster+shade stage from
--stats; "over normal" subtracts normal mapping's time, as the talk's table does ("technique time - normal
mapping time", per-vertex blend with 4 surfaces: relief 3 ms, POM 2.5 ms, POM with HB 1.25 ms).

    bench/blend.py [-n RUNS] [-B BUILD_DIR] [--width W --height H]
"""
import os
import statistics
import sys
import tempfile

from bench_util import ROOT, arguments, render

SCENE = os.path.join(ROOT, "scenes", "surface_blend_4layers.json")
M = "/materials/blend"
VARIANTS = [  # (label, --set pairs, the talk's ms over normal mapping)
    ("normal mapping", [(f"{M}/technique/name", "normal")], 0.0),
    ("relief, alpha blend", [(f"{M}/technique/name", "relief"), (f"{M}/blend/operator", "alpha")], 3.0),
    ("POM, alpha blend", [(f"{M}/technique/name", "pom"), (f"{M}/blend/operator", "alpha")], 2.5),
    ("POM, height blend", [(f"{M}/technique/name", "pom"), (f"{M}/blend/operator", "height")], 1.25),
]


def main():
    args = arguments(__doc__.splitlines()[0]).parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    times = {label: [] for label, _, _ in VARIANTS}
    iters = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.n):
            for label, sets, _ in VARIANTS:
                stats = render(qdmr, SCENE, sets, args.width, args.height, tmp)
                times[label].append(stats["time_ms"]["raster_shade"])
                iters[label] = stats["iterations"]
    med = {label: statistics.median(v) for label, v in times.items()}
    base = med["normal mapping"]
    relief = med["relief, alpha blend"] - base
    low = {label: min(v) for label, v in times.items()}  # fastest runs: less exposed to other processes' load
    print(f"| variant | raster_shade ms (median of {args.n}) | min–max | ms over normal mapping | ratio to relief "
          f"| over normal, from minima | talk ms over normal | talk ratio to relief | iterations mean / p99 | lane use |")
    print("|" + "---|" * 10)
    for label, _, talk in VARIANTS:
        over = med[label] - base
        it = iters[label]
        print(f"| {label} | {med[label]:.1f} | {min(times[label]):.1f}–{max(times[label]):.1f} | {over:.1f} | "
              f"{over / relief:.2f} | {low[label] - low['normal mapping']:.1f} | {talk:g} | {talk / 3.0:.2f} | {it['mean']:.1f} / {it['p99']:.0f} | "
              f"{it['lane_utilisation']:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
