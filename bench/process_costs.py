#!/usr/bin/env python3
"""The whole-process targets of issue #12 (docs/performance.md, "Targets"), measured side by side in one run:

  - `qdmr --help` and `qdmr plan` of a procedural scene, of one whose textures are PNG and JPEG files, of one
    with a TIFF, an OpenEXR, a PGM and a PFM texture (all read in process), and of one with a TIFF stored "min is
    white", a layout OpenImageIO converts (the plan reads its header with libtiff; a render reads its pixels
    through the image module): each at most 50 ms;
  - a whole `qdmr render` of the canonical scene (bench/llvmpipe/canonical.json, normal mapping, 1920x1080) to
    PNG: at most 2 x its warm frame + 50 ms, by wall time and by its stats' time_ms.total; its PNG written in at
    most 40 ms (time_ms.write); its frame (time_ms.draw, cold: the process's first) within 1.2 x the warm one;
  - the warm frame: `qdmr bench` of the same scene, the median draw after warm-up frames.

Every round runs each case once, in the same order; the table holds the median and the range over the rounds,
with the load average before and after (wall times grow with anything else running: run it on a quiet machine).

  bench/process_costs.py [-n 5] [-B BUILD_DIR] [--threads 2] [--json FILE]
"""
import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CANONICAL = os.path.join(ROOT, "bench", "llvmpipe", "canonical.json")
PLANE = os.path.join(ROOT, "scenes", "plane.json")
IMAGES = os.path.join(ROOT, "tests", "bad_inputs", "files", "images")
ALBEDO = "/materials/bricks/layers/0/albedo"
NORMAL_MAPPED = ["--set", "/materials/cobbles/technique/name=normal"]


def wall_ms(cmd):
    """Runs cmd (its output discarded); its wall time in ms. A failure stops the benchmark with its output."""
    start = time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = (time.perf_counter() - start) * 1000.0
    if done.returncode != 0:
        sys.exit(f"process_costs: {' '.join(cmd)} failed ({done.returncode}): {done.stderr.strip()}")
    return elapsed


def load():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-n", type=int, default=5, help="rounds (default 5)")
    parser.add_argument("-B", default=os.path.join(ROOT, "build", "release"), help="build folder holding qdmr")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--json", help="also write every round's numbers to this file")
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    if not os.access(qdmr, os.X_OK):
        sys.exit(f"process_costs: no {qdmr} (build the qdmr_cli target first)")
    threads = ["--threads", str(args.threads)]
    tmp_dir = tempfile.TemporaryDirectory()
    tmp = tmp_dir.name
    pgm = os.path.join(tmp, "grey.pgm")  # a 4x4 binary PGM, read in process
    with open(pgm, "wb") as f:
        f.write(b"P5\n4 4\n255\n" + bytes([100] * 16))
    pfm = os.path.join(tmp, "grey.pfm")  # a 4x4 PFM, read in process
    with open(pfm, "wb") as f:
        f.write(b"Pf\n4 4\n-1.0\n" + bytes(64))
    converted = os.path.join(tmp, "white.tif")  # a 4x4 min-is-white TIFF: its pixels are read through the image module
    with open(converted, "wb") as f:
        entries = [(256, 3, 4), (257, 3, 4), (258, 3, 8), (259, 3, 1), (262, 3, 0), (273, 4, 8 + 2 + 12 * 8 + 4),
                   (278, 3, 4), (279, 4, 16)]  # 4x4, 8 bits, uncompressed, min is white, one strip
        f.write(b"II*\0" + struct.pack("<IH", 8, len(entries)) +
                b"".join(struct.pack("<HHII", tag, kind, 1, value) for tag, kind, value in entries) +
                struct.pack("<I", 0) + bytes(range(0, 256, 16)))
    plans = {
        "plan, procedural textures": [qdmr, "plan", PLANE],
        "plan, PNG and JPEG textures": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={IMAGES}/noise.jpg", "--set",
                                        f"/materials/bricks/layers/0/normal={IMAGES}/good.png"],
        "plan, a TIFF texture": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={IMAGES}/noise.tif"],
        "plan, an OpenEXR texture": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={IMAGES}/noise.exr"],
        "plan, a PGM texture": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={pgm}"],
        "plan, a PFM texture": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={pfm}"],
        "plan, a converted TIFF texture": [qdmr, "plan", PLANE, "--set", f"{ALBEDO}={converted}"],
    }
    rounds = {name: [] for name in ["help", *plans, "render wall", "render total", "render draw", "render write",
                                    "warm frame"]}
    before = load()
    with tmp_dir:
        png, stats, bench = (os.path.join(tmp, name) for name in ("frame.png", "stats.json", "bench.json"))
        for r in range(args.n):
            rounds["help"].append(wall_ms([qdmr, "--help"]))
            for name, cmd in plans.items():
                rounds[name].append(wall_ms(cmd))
            rounds["render wall"].append(
                wall_ms([qdmr, "render", CANONICAL, *NORMAL_MAPPED, *threads, "-o", png, "--stats", stats]))
            with open(stats) as f:
                times = json.load(f)["time_ms"]
            rounds["render total"].append(times["total"])
            rounds["render draw"].append(times["draw"])
            rounds["render write"].append(times["write"])
            wall_ms([qdmr, "bench", CANONICAL, *NORMAL_MAPPED, *threads, "--frames", "8", "--warmup", "2", "--json",
                     bench])
            with open(bench) as f:
                draw = json.load(f)["draw_ms"]
            rounds["warm frame"].append(draw["median"] if isinstance(draw, dict) else draw)
            print(f"round {r + 1}/{args.n} done, load average {load()}", file=sys.stderr)
    after = load()

    med = {name: statistics.median(values) for name, values in rounds.items()}
    bound = 2.0 * med["warm frame"] + 50.0
    rows = [("`qdmr --help`", "help", "<= 50 ms", med["help"] <= 50.0)]
    rows += [(f"`qdmr {name}`", name, "<= 50 ms", med[name] <= 50.0) for name in plans]
    rows += [
        ("1080p PNG written (`time_ms.write`)", "render write", "<= 40 ms", med["render write"] <= 40.0),
        ("whole `qdmr render`, wall", "render wall", f"<= 2 x warm + 50 = {bound:.1f} ms", med["render wall"] <= bound),
        ("whole `qdmr render`, `time_ms.total`", "render total", f"<= {bound:.1f} ms", med["render total"] <= bound),
        ("its frame, cold (`time_ms.draw`)", "render draw", f"<= 1.2 x warm = {1.2 * med['warm frame']:.1f} ms",
         med["render draw"] <= 1.2 * med["warm frame"]),
        ("warm frame (`qdmr bench`, median draw)", "warm frame", "", None),
    ]
    version = subprocess.run([qdmr, "--version"], capture_output=True, text=True).stdout.strip()
    print(f"{version}; canonical scene normal-mapped at 1920x1080, {args.threads} threads; {args.n} rounds; "
          f"load average before {before}, after {after}")
    print()
    print("| measurement | target | median ms | range ms | met |")
    print("|---|---|---|---|---|")
    for label, key, target, met in rows:
        values = rounds[key]
        status = "" if met is None else ("yes" if met else "no")
        print(f"| {label} | {target} | {med[key]:.1f} | {min(values):.1f} - {max(values):.1f} | {status} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"version": version, "threads": args.threads, "load_before": before, "load_after": after,
                       "rounds_ms": rounds}, f, indent=1)


if __name__ == "__main__":
    main()
