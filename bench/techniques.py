#!/usr/bin/env python3
"""The talk's POM vs QDM table, rebuilt on this machine.

For each scene (depth scale 1.0, 1.5, 5.0 and the extreme grazing case) it first finds, at a small size, the
iteration settings that give an artifact-free image as judged by the exact reference (fewer than 0.1 % of the
covered pixels `missed`), doubling POM's max_steps and QDM's max_iterations from a low start. Then it times
normal mapping, POM and QDM side by side at full size (runs alternate within each round; medians of the
raster+shade stage from --stats) and prints a markdown table.

    bench/techniques.py [-n RUNS] [-B BUILD_DIR] [--width W --height H] [SCENE ...]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

from bench_util import ROOT, arguments, render

SCENES = ["pom_vs_qdm_depth_1.0", "pom_vs_qdm_depth_1.5", "pom_vs_qdm_depth_5.0", "extreme_grazing_2048"]
TALK_MS = {"pom_vs_qdm_depth_1.0": (5.0, 5.66), "pom_vs_qdm_depth_1.5": (6.66, 6.7),
           "pom_vs_qdm_depth_5.0": (18.87, 9.0), "extreme_grazing_2048": (73.0, 14.0)}
KNOB = {"pom": "max_steps", "qdm": "max_iterations"}


def materials(scene):
    with open(os.path.join(ROOT, "scenes", scene + ".json")) as f:
        return list(json.load(f)["materials"].keys())


def render_scene(qdmr, scene, sets, width, height, tmp, aov=None):
    extra = ["--aov", f"missed={os.path.join(tmp, 'missed.exr')}"] if aov else []
    return render(qdmr, os.path.join(ROOT, "scenes", scene + ".json"), sets, width, height, tmp, extra=extra)


def missed_fraction(stats, tmp, width, height):
    text = subprocess.run(["oiiotool", os.path.join(tmp, "missed.exr"), "--printstats"], check=True,
                          capture_output=True, text=True).stdout
    mean = float(next(line for line in text.splitlines() if "Stats Avg" in line).split()[2])
    return mean * width * height / max(1, stats["shading"]["pixels_shaded"])


def technique_sets(scene, technique, knob_value=None):
    sets = []
    for m in materials(scene):
        sets.append((f"/materials/{m}/technique/name", technique))
        if technique == "qdm":  # judged against the box surface it traverses
            sets.append((f"/materials/{m}/technique/refinement", "none"))
        if knob_value is not None:
            sets.append((f"/materials/{m}/technique/{KNOB[technique]}", knob_value))
    return sets


def tune(qdmr, scene, technique, tmp, start, limit):
    """Smallest doubling of the knob that leaves < 0.1 % of pixels missed (at 480x270)."""
    if technique == "pom":  # max_steps may not go below the scene's min_steps
        with open(os.path.join(ROOT, "scenes", scene + ".json")) as f:
            start = max([start] + [m["technique"].get("min_steps", 8) for m in json.load(f)["materials"].values()])
    value = start
    while True:
        stats = render_scene(qdmr, scene, technique_sets(scene, technique, value), 480, 270, tmp, aov=True)
        missed = missed_fraction(stats, tmp, 480, 270)
        if missed < 0.001 or value >= limit:
            return value, missed
        value *= 2


def main():
    parser = arguments(__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=SCENES)
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    print(f"| scene | POM: {KNOB['pom']} / missed | QDM: {KNOB['qdm']} / missed | normal ms | POM ms over normal "
          f"| QDM ms over normal | POM/QDM | talk POM/QDM | POM iter mean/p99 | QDM iter mean/p99 | lane use POM/QDM |")
    print("|" + "---|" * 11, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            settings = {t: tune(qdmr, scene, t, tmp, 16, 4096) for t in ("pom", "qdm")}
            times = {t: [] for t in ("normal", "pom", "qdm")}
            iters = {}
            for _ in range(args.n):
                for t in ("normal", "pom", "qdm"):
                    sets = technique_sets(scene, t, settings[t][0] if t in settings else None)
                    stats = render_scene(qdmr, scene, sets, args.width, args.height, tmp)
                    times[t].append(stats["time_ms"]["raster_shade"])
                    iters[t] = stats["iterations"]
            med = {t: statistics.median(v) for t, v in times.items()}
            pom = med["pom"] - med["normal"]
            qdm = med["qdm"] - med["normal"]
            talk = TALK_MS[scene][0] / TALK_MS[scene][1] if scene in TALK_MS else float("nan")
            print(f"| {scene} | {settings['pom'][0]} / {100 * settings['pom'][1]:.3f} % | {settings['qdm'][0]} / "
                  f"{100 * settings['qdm'][1]:.3f} % | {med['normal']:.1f} | {pom:.1f} | {qdm:.1f} | {pom / qdm:.2f}x "
                  f"| {talk:.2f}x | {iters['pom']['mean']:.1f} / {iters['pom']['p99']:.0f} | "
                  f"{iters['qdm']['mean']:.1f} / {iters['qdm']['p99']:.0f} | "
                  f"{iters['pom']['lane_utilisation']:.2f} / {iters['qdm']['lane_utilisation']:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
