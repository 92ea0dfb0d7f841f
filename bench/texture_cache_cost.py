#!/usr/bin/env python3
"""What the emulated texture cache costs (docs/performance.md, "Texture cache").

Warm frames (`qdmr bench`, median of its frames) of two scenes at 1920x1080, 2 threads:
  - off: this build with the cache off, against a build without the cache code (--base BUILD, e.g. a build of
    the commit before it): the hooks must cost nothing measurable;
  - on: this build with the cache on (default settings), against off: what recording and replaying cost.
Runs alternate within each round (base, off, on), so load changes hit all three alike; the ratios are medians
over the rounds.

  python3 bench/texture_cache_cost.py [-n 5] [-B build/release] [--base OTHER_BUILD]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_util  # noqa: E402

# The 4-layer blend is left out: with the cache on, its ~300 texel reads per pixel take minutes per 1080p run.
SCENES = ["plane", "pom_vs_qdm_depth_1.5"]


def bench(qdmr, scene, width, height, tmp, sets=()):
    out = os.path.join(tmp, "bench.json")
    cmd = [qdmr, "bench", os.path.join(bench_util.ROOT, "scenes", scene + ".json"), "--frames", "5", "--warmup", "2",
           "--threads", "2", "--width", str(width), "--height", str(height), "--json", out]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)["draw_ms"]["median"]


def main():
    parser = bench_util.arguments(__doc__.split("\n")[0])
    parser.add_argument("--base", help="a build folder without the cache code, to time the hooks against")
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    base = os.path.join(args.base, "qdmr") if args.base else None
    load_before = os.getloadavg()
    print(f"| scene | {'base ms | ' if base else ''}off ms | on ms | {'off / base | ' if base else ''}on / off |")
    print(f"|---|{'---|' if base else ''}---|---|{'---|' if base else ''}---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in SCENES:
            times = {"base": [], "off": [], "on": []}
            for _ in range(args.n):
                if base:
                    times["base"].append(bench(base, scene, args.width, args.height, tmp))
                times["off"].append(bench(qdmr, scene, args.width, args.height, tmp))
                times["on"].append(bench(qdmr, scene, args.width, args.height, tmp, ["/texture_cache/enabled=true"]))
            med = {k: statistics.median(v) for k, v in times.items() if v}
            on_off = statistics.median(on / off for on, off in zip(times["on"], times["off"]))
            cells = [scene]
            if base:
                cells.append(f"{med['base']:.1f}")
            cells += [f"{med['off']:.1f}", f"{med['on']:.1f}"]
            if base:
                off_base = statistics.median(o / b for o, b in zip(times["off"], times["base"]))
                cells.append(f"{off_base:.3f}")
            cells.append(f"{on_off:.2f}")
            print("| " + " | ".join(cells) + " |", flush=True)
    load_after = os.getloadavg()
    print(f"{args.n} rounds; load average before {load_before[0]:.2f}, after {load_after[0]:.2f}; {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
