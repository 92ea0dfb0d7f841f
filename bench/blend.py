#!/usr/bin/env python3
"""The talk's surface blend table, rebuilt on this machine.

scenes/surface_blend_4layers.json (four layers, per-vertex weights, full screen) rendered as normal mapping
(technique name=normal, the blend kept), relief mapping with alpha blend, POM with alpha blend and POM with
height blend (the scene as stored). Runs alternate inside each round; medians of the raster+shade stage from
--stats; "over normal" subtracts normal mapping's time, as the talk's table does ("technique time - normal
mapping time", per-vertex blend with 4 surfaces: relief 3 ms, POM 2.5 ms, POM with HB 1.25 ms).

With --tuned, like for like: every variant uses per-pixel weights (blend/weights/mode=pixel, so the exact
reference of the blend applies without the per-vertex floating), and each displaced variant first gets the smallest
doubling of its step knob (relief linear_steps, POM max_steps) that leaves fewer than 0.1 % of the covered pixels
`missed` against the exact reference of its own blended surface (at 480x270), as the talk set its iteration counts
"for non artifact rendering".

--cpu times CPU time instead of wall time (for a shared machine): the process's CPU time (all threads) at full
size minus the same at 64x36, on one thread, as bench/techniques.py --cpu.

    bench/blend.py [-n RUNS] [-B BUILD_DIR] [--width W --height H] [--tuned] [--cpu]
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


KNOB = {"relief": "linear_steps", "pom": "max_steps"}
THRESHOLD = 0.001  # fraction of covered pixels missed


def tune(qdmr, sets, tmp):
    """Smallest doubling (16 .. 4096) of the technique's step knob with < 0.1 % missed at 480x270."""
    technique = dict(sets)[f"{M}/technique/name"]
    value = 16
    while True:
        knob = [(f"{M}/technique/{KNOB[technique]}", value)]
        stats = render(qdmr, SCENE, sets + knob, 480, 270, tmp, extra=["--aov", f"missed={os.path.join(tmp, 'm.exr')}"])
        missed = stats["reference"]["missed_fraction"]
        print(f"# {sets}: {KNOB[technique]}={value}: {100 * missed:.3f} % missed", file=sys.stderr, flush=True)
        if missed < THRESHOLD or value >= 4096:
            return knob, f"{KNOB[technique]} {value} / {100 * missed:.3f} %"
        value *= 2


def main():
    parser = arguments(__doc__.splitlines()[0])
    parser.add_argument("--tuned", action="store_true", help="per-pixel weights, step counts tuned to 0.1 %% missed")
    parser.add_argument("--cpu", action="store_true", help="CPU time (full size minus 64x36) instead of wall time")
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    times = {label: [] for label, _, _ in VARIANTS}
    iters = {}
    variants = VARIANTS
    settings = {label: "scene's" for label, _, _ in VARIANTS}
    with tempfile.TemporaryDirectory() as tmp:
        if args.tuned:
            variants = []
            for label, sets, talk in VARIANTS:
                sets = sets + [(f"{M}/blend/weights/mode", "pixel")]
                if label != "normal mapping":
                    knob, settings[label] = tune(qdmr, sets, tmp)
                    sets = sets + knob
                else:
                    settings[label] = "–"
                variants.append((label, sets, talk))
        for _ in range(args.n):
            for label, sets, _ in variants:
                # --cpu renders on one thread: idle oneTBB workers spin, which would count as CPU time
                one = ["--threads", "1"] if args.cpu else []
                stats = render(qdmr, SCENE, sets, args.width, args.height, tmp, extra=one)
                if args.cpu:
                    small = render(qdmr, SCENE, sets, 64, 36, tmp, extra=one)
                    times[label].append(stats["cpu_ms"] - small["cpu_ms"])
                else:
                    times[label].append(stats["time_ms"]["raster_shade"])
                iters[label] = stats["iterations"]
    med = {label: statistics.median(v) for label, v in times.items()}
    base = med["normal mapping"]
    relief = med["relief, alpha blend"] - base
    low = {label: min(v) for label, v in times.items()}  # fastest runs: less exposed to other processes' load
    what = "CPU ms, full size minus 64x36" if args.cpu else "raster_shade ms"
    print(f"| variant | steps / missed | {what} (median of {args.n}) | min–max | ms over normal mapping "
          f"| ratio to relief | over normal, from minima | talk ms over normal | talk ratio to relief "
          f"| iterations mean / p99 | lane use |")
    print("|" + "---|" * 11)
    for label, _, talk in VARIANTS:
        over = med[label] - base
        it = iters[label]
        print(f"| {label} | {settings[label]} | {med[label]:.1f} | {min(times[label]):.1f}–{max(times[label]):.1f} | {over:.1f} | "
              f"{over / relief:.2f} | {low[label] - low['normal mapping']:.1f} | {talk:g} | {talk / 3.0:.2f} | {it['mean']:.1f} / {it['p99']:.0f} | "
              f"{it['lane_utilisation']:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
