#!/usr/bin/env python3
"""Self-shadowing, ambient occlusion and QDMHB vs QDM on scenes/terrain.json, measured side by side.

Every variant changes one thing against the scene's own baseline (shadow off, AO off; the scene as stored
has qdm_soft shadows and baked AO): each shadow mode (hard, horizon, qdm_soft, defaults but the scene's
strength), each AO mode (frame with jitter, the same with coarse=false, baked), the scene as stored, and
QDM over one layer: a temporary copy of the scene with only layers[0] (rock) and no blend, shadow and AO off,
against the baseline (QDM over the 4-layer height blend = QDMHB, with its precomputed combined quadtree), and
QDMHB bounding cells on the fly (the product bound) or with per-vertex weights. Baked AO is baked once into a temporary
QDMR_CACHE_DIR by a warm-up render, so the timed runs read the cache. Runs alternate inside each round;
medians of the raster+shade stage from --stats; iterations are the intersection search's (not the
shadow's or AO's fetches), from the last run.

    bench/shadows_ao.py [-n RUNS] [-B BUILD_DIR] [--width W --height H]
"""
import json
import os
import statistics
import sys
import tempfile

from bench_util import ROOT, arguments, render

SCENE = os.path.join(ROOT, "scenes", "terrain.json")
M = "/materials/ground"
OFF = [(f"{M}/shadow/mode", "off"), (f"{M}/ao/mode", "off")]
VARIANTS = [  # (label, scene: None = terrain.json, "single" = the one-layer copy; --set pairs)
    ("baseline: QDMHB, shadow off, AO off", None, OFF),
    ("shadow hard", None, OFF + [(f"{M}/shadow/mode", "hard")]),
    ("shadow horizon", None, OFF + [(f"{M}/shadow/mode", "horizon")]),
    ("shadow qdm_soft", None, OFF + [(f"{M}/shadow/mode", "qdm_soft")]),
    ("AO frame (coarse, jitter)", None, OFF + [(f"{M}/ao/mode", "frame"), (f"{M}/ao/jitter", "true")]),
    ("AO frame (fine: coarse=false, jitter)", None,
     OFF + [(f"{M}/ao/mode", "frame"), (f"{M}/ao/jitter", "true"), (f"{M}/ao/coarse", "false")]),
    ("AO baked", None, OFF + [(f"{M}/ao/mode", "baked")]),
    ("as stored: qdm_soft + baked AO", None, []),
    ("QDMHB, product bound (blend/quadtree=product)", None, OFF + [(f"{M}/blend/quadtree", "product")]),
    ("QDMHB, per-vertex weights", None, OFF + [(f"{M}/blend/weights/mode", "vertex")]),
    ("QDM, one layer (rock), shadow off, AO off", "single", OFF),
]
TALK = {"shadow qdm_soft": "0.5 (QDM self-shadowing, full screen)"}


def single_layer_scene(tmp):
    with open(SCENE) as f:
        scene = json.load(f)
    ground = scene["materials"]["ground"]
    ground["layers"] = ground["layers"][:1]
    del ground["blend"]
    path = os.path.join(tmp, "terrain_one_layer.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    return path


def main():
    args = arguments(__doc__.splitlines()[0]).parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    times = {label: [] for label, _, _ in VARIANTS}
    iters = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, QDMR_CACHE_DIR=os.path.join(tmp, "cache"))
        scenes = {None: SCENE, "single": single_layer_scene(tmp)}
        render(qdmr, SCENE, OFF + [(f"{M}/ao/mode", "baked")], 320, 180, tmp, env=env)  # bakes the AO maps
        for _ in range(args.n):
            for label, scene, sets in VARIANTS:
                stats = render(qdmr, scenes[scene], sets, args.width, args.height, tmp, env=env)
                times[label].append(stats["time_ms"]["raster_shade"])
                iters[label] = stats["iterations"]
    med = {label: statistics.median(v) for label, v in times.items()}
    base = med[VARIANTS[0][0]]
    low = {label: min(v) for label, v in times.items()}  # fastest runs: less exposed to other processes' load
    print(f"| variant | raster_shade ms (median of {args.n}) | min–max | ms over baseline | over baseline, from minima | "
          f"iterations mean / p99 | lane use | talk ms |")
    print("|" + "---|" * 8)
    for label, _, _ in VARIANTS:
        it = iters[label]
        print(f"| {label} | {med[label]:.1f} | {min(times[label]):.1f}–{max(times[label]):.1f} | "
              f"{med[label] - base:+.1f} | {low[label] - low[VARIANTS[0][0]]:+.1f} | {it['mean']:.2f} / {it['p99']:.0f} | {it['lane_utilisation']:.2f} | "
              f"{TALK.get(label, '')} |", flush=True)
    qdmhb, qdm = iters[VARIANTS[0][0]]["mean"], iters[VARIANTS[-1][0]]["mean"]
    print(f"\nQDMHB (4 layers) vs QDM (layer 0 alone): mean iterations {qdmhb:.2f} vs {qdm:.2f} "
          f"({100 * (qdmhb / qdm - 1):+.1f} %), raster_shade {med[VARIANTS[0][0]]:.1f} vs {med[VARIANTS[-1][0]]:.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
