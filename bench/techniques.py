#!/usr/bin/env python3
"""The talk's POM vs QDM table, rebuilt on this machine, like for like.

For each scene (depth scale 1.0, 1.5, 5.0 and the extreme grazing case) it first finds, at a small size, the
iteration settings that give an artifact-free image as judged by the exact reference (fewer than 0.1 % of the
covered pixels `missed`, i.e. more than one texel from the reference hit), doubling the knob from a low start:

  pom      POM's max_steps, judged against the bilinear surface (what its filtered fetches see)
  qdm_bp   QDM with refinement bilinear_patch (exact on the bilinear surface), max_iterations, against the
           bilinear surface: the same surface and threshold as POM (the like-for-like pairing)
  qdm_lin  QDM with linear refinement (the talk's QDM and the shipped scenes' setting), against the bilinear surface
  qdm_box  QDM with refinement none, against the box surface it traverses (the pairing of the earlier table)

Then it times normal mapping and the four side by side at full size (runs alternate within each round; medians of
the raster+shade stage from --stats) and prints two markdown tables: the settings found, and the times over
normal mapping with the POM/QDM ratios of each pairing next to the talk's.

    bench/techniques.py [-n RUNS] [-B BUILD_DIR] [--width W --height H] [--variants pom,qdm_bp,...]
                        [--settings FILE] [SCENE ...]

--cpu times CPU time instead of wall time, for a shared machine: each variant's process CPU time (all threads)
at full size minus the same at 64x36 (prepare and start-up, which do not depend on the size), so the difference
is the frame's geometry, raster+shade and image write, and "over normal" leaves raster+shade's difference. The
renders run on one thread (--threads 1): idle oneTBB workers spin, and spinning would count as CPU time.

--settings FILE keeps the tuned settings in a JSON file: the ones found there are reused (only the timing runs
again), new ones are added to it.
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
# variant: (technique name, QDM refinement or None, the knob tuned)
VARIANTS = {"pom": ("pom", None, "max_steps"),
            "qdm_bp": ("qdm", "bilinear_patch", "max_iterations"),
            "qdm_lin": ("qdm", "linear", "max_iterations"),
            "qdm_box": ("qdm", "none", "max_iterations")}
THRESHOLD = 0.001  # fraction of covered pixels missed
TUNE_W, TUNE_H = 480, 270


def materials(scene):
    with open(os.path.join(ROOT, "scenes", scene + ".json")) as f:
        return list(json.load(f)["materials"].keys())


def render_scene(qdmr, scene, sets, width, height, tmp, aov=None, one_thread=False):
    extra = ["--aov", f"missed={os.path.join(tmp, 'missed.exr')}"] if aov else []
    if one_thread:
        extra += ["--threads", "1"]
    return render(qdmr, os.path.join(ROOT, "scenes", scene + ".json"), sets, width, height, tmp, extra=extra)


def missed_fraction(stats, tmp, width, height):
    text = subprocess.run(["oiiotool", os.path.join(tmp, "missed.exr"), "--printstats"], check=True,
                          capture_output=True, text=True).stdout
    mean = float(next(line for line in text.splitlines() if "Stats Avg" in line).split()[2])
    return mean * width * height / max(1, stats["shading"]["pixels_shaded"])


def variant_sets(scene, variant, knob_value=None):
    if variant == "normal":
        return [(f"/materials/{m}/technique/name", "normal") for m in materials(scene)]
    name, refinement, knob = VARIANTS[variant]
    sets = []
    for m in materials(scene):
        sets.append((f"/materials/{m}/technique/name", name))
        if refinement:
            sets.append((f"/materials/{m}/technique/refinement", refinement))
        if knob_value is not None:
            sets.append((f"/materials/{m}/technique/{knob}", knob_value))
    return sets


def tune(qdmr, scene, variant, tmp, start, limit):
    """Smallest doubling of the knob that leaves < 0.1 % of pixels missed (at 480x270), and that fraction."""
    if VARIANTS[variant][0] == "pom":  # max_steps may not go below the scene's min_steps
        with open(os.path.join(ROOT, "scenes", scene + ".json")) as f:
            start = max([start] + [m["technique"].get("min_steps", 8) for m in json.load(f)["materials"].values()])
    value = start
    while True:
        stats = render_scene(qdmr, scene, variant_sets(scene, variant, value), TUNE_W, TUNE_H, tmp, aov=True)
        missed = missed_fraction(stats, tmp, TUNE_W, TUNE_H)
        print(f"# {scene} {variant} {VARIANTS[variant][2]}={value}: {100 * missed:.3f} % missed", file=sys.stderr,
              flush=True)
        if missed < THRESHOLD or value >= limit:
            return value, missed
        value *= 2


def main():
    parser = arguments(__doc__.splitlines()[0])
    parser.add_argument("--variants", default="pom,qdm_bp,qdm_lin,qdm_box",
                        help="comma-separated subset of " + ", ".join(VARIANTS))
    parser.add_argument("--settings", help="JSON file of tuned settings, read and updated")
    parser.add_argument("--cpu", action="store_true", help="CPU time (full size minus 64x36) instead of wall time")
    parser.add_argument("scenes", nargs="*", default=SCENES)
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    variants = args.variants.split(",")
    rows = []
    saved = {}
    if args.settings and os.path.exists(args.settings):
        with open(args.settings) as f:
            saved = json.load(f)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            known = saved.setdefault(scene, {})
            settings = {v: tuple(known[v]) if v in known else tune(qdmr, scene, v, tmp, 16, 4096) for v in variants}
            if args.settings:
                known.update(settings)
                with open(args.settings, "w") as f:
                    json.dump(saved, f, indent=1)
            times = {v: [] for v in ["normal"] + variants}
            iters = {}
            for _ in range(args.n):
                for v in times:
                    sets = variant_sets(scene, v, settings[v][0] if v in settings else None)
                    # --cpu renders on one thread: idle oneTBB workers spin, which would count as CPU time
                    stats = render_scene(qdmr, scene, sets, args.width, args.height, tmp, one_thread=args.cpu)
                    if args.cpu:
                        small = render_scene(qdmr, scene, sets, 64, 36, tmp, one_thread=True)
                        times[v].append(stats["cpu_ms"] - small["cpu_ms"])
                    else:
                        times[v].append(stats["time_ms"]["raster_shade"])
                    iters[v] = dict(stats["iterations"], pixels=stats["shading"]["pixels_shaded"])
            rows.append((scene, settings, {v: statistics.median(t) for v, t in times.items()}, iters,
                         {v: min(t) for v, t in times.items()}))
            print(f"# {scene} done", file=sys.stderr, flush=True)

    print("Settings found at %dx%d (knob / missed fraction) and iterations at full size (mean / p99, lane use):\n"
          % (TUNE_W, TUNE_H))
    print("| scene | " + " | ".join(f"{v}: {VARIANTS[v][2]} / missed | {v} iter mean / p99 / lane use"
                                     for v in variants) + " |")
    print("|" + "---|" * (1 + 2 * len(variants)))
    for scene, settings, med, iters, low in rows:
        cells = []
        for v in variants:
            it = iters[v]
            cells.append(f"{settings[v][0]} / {100 * settings[v][1]:.3f} %")
            cells.append(f"{it['mean']:.1f} / {it['p99']:.0f} / {it['lane_utilisation']:.2f}")
        print(f"| {scene} | " + " | ".join(cells) + " |")

    what = "CPU ms (all threads, full size minus 64x36)" if args.cpu else "raster_shade ms"
    print("\n%s over normal mapping (medians of %d) and POM / QDM ratios:\n" % (what, args.n))
    qdms = [v for v in variants if v != "pom"]
    header = "| scene | normal ms | " + " | ".join(f"{v} ms over normal" for v in variants)
    if "pom" in variants:
        header += " | " + " | ".join(f"POM/{v}" for v in qdms) + " | " + " | ".join(f"POM/{v} from minima" for v in qdms)
    print(header + " | talk POM/QDM |")
    print("|" + "---|" * (3 + len(variants) + (2 * len(qdms) if "pom" in variants else 0)))
    for scene, settings, med, iters, low in rows:
        over = {v: med[v] - med["normal"] for v in variants}
        cells = [f"{med['normal']:.1f}"] + [f"{over[v]:.1f}" for v in variants]
        if "pom" in variants:
            cells += [f"{over['pom'] / over[v]:.2f}x" if over[v] > 0 else "–" for v in qdms]
        if "pom" in variants:  # the fastest runs: less exposed to other processes' load
            low_over = {v: low[v] - low["normal"] for v in variants}
            cells += [f"{low_over['pom'] / low_over[v]:.2f}x" if low_over[v] > 0 else "–" for v in qdms]
        talk = TALK_MS[scene][0] / TALK_MS[scene][1] if scene in TALK_MS else float("nan")
        print(f"| {scene} | " + " | ".join(cells) + f" | {talk:.2f}x |")

    print("\nCost per iteration: ns of %s over normal mapping per pixel-iteration:\n" % what)
    print("| scene | pixels shaded | " + " | ".join(f"{v} ns / iteration" for v in variants) + " |")
    print("|" + "---|" * (2 + len(variants)))
    for scene, settings, med, iters, low in rows:
        cells = [str(iters[variants[0]]["pixels"])]
        for v in variants:
            work = iters[v]["pixels"] * iters[v]["mean"]
            cells.append(f"{(med[v] - med['normal']) * 1e6 / work:.1f}" if work > 0 else "–")
        print(f"| {scene} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
