#!/usr/bin/env python3
"""What `qdmr check` costs beyond drawing (docs/performance.md, "qdmr check").

1. A manifest of 200 exact checks of small scenes (320x180: four shipped scenes x 50 camera angles), run in one
   process: its wall time against the sum of the checks' warm draw times, each measured by `qdmr bench` (median of
   5 frames after 2 warm-up frames). Target: <= 1.3x.
2. One one-off check of a 1080p scene (`qdmr check SCENE --hash H`) against `qdmr render` of it to PNG, alternated,
   median of -n runs. Target: the check costs no more than the render.

  python3 bench/check_overhead.py [-n 3] [-B build/release] [--checks 200]
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

SCENES = ["plane", "terrain", "pom_vs_qdm_depth_1.0", "surface_blend_4layers"]


def wall(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main():
    parser = bench_util.arguments(__doc__.split("\n")[0])
    parser.add_argument("--checks", type=int, default=200)
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        per_scene = args.checks // len(SCENES)
        checks = []
        for scene in SCENES:
            for k in range(per_scene):
                fov = 30.0 + 30.0 * k / max(1, per_scene - 1)
                checks.append({"name": f"{scene}_{k}", "scene": os.path.join(bench_util.ROOT, "scenes", scene + ".json"),
                               "set": {"/camera/fov_deg": fov}})
        manifest = os.path.join(tmp, "m.json")
        with open(manifest, "w") as f:
            json.dump({"bits_version": bench_util.bits_version(qdmr), "defaults": {"width": 320, "height": 180}, "checks": checks}, f)
        subprocess.run([qdmr, "check", manifest, "--update"], check=True, stdout=subprocess.DEVNULL)

        results = os.path.join(tmp, "r.json")
        runs = [wall([qdmr, "check", manifest, "--json", results]) for _ in range(args.n)]
        with open(results) as f:
            run = json.load(f)
        in_run_draw = sum(c["draw_ms"] for c in run["checks"]) / 1000.0
        in_run_prepare = sum(c["prepare_ms"] for c in run["checks"]) / 1000.0

        warm = 0.0
        for check in checks:
            out = os.path.join(tmp, "b.json")
            subprocess.run([qdmr, "bench", check["scene"], "--width", "320", "--height", "180", "--frames", "5",
                            "--warmup", "2", "--set", f"/camera/fov_deg={check['set']['/camera/fov_deg']}",
                            "--json", out], check=True, stdout=subprocess.DEVNULL)
            with open(out) as f:
                warm += json.load(f)["draw_ms"]["median"] / 1000.0

        # One-off check of a 1080p scene vs its render, alternated.
        scene = os.path.join(bench_util.ROOT, "scenes", "pom_vs_qdm_depth_1.0.json")
        printed = subprocess.run([qdmr, "check", scene, "--hash", "none", "--update"], check=True,
                                 capture_output=True, text=True).stdout
        digest = printed[printed.index("sha1:", printed.index("hash of ")):][:45]
        one_check, one_render = [], []
        for _ in range(args.n):
            one_render.append(wall([qdmr, "render", scene, "-o", os.path.join(tmp, "r.png")]))
            one_check.append(wall([qdmr, "check", scene, "--hash", digest]))

    load_after = os.getloadavg()
    median = statistics.median(runs)
    print(f"qdmr check, {len(checks)} checks at 320x180 ({', '.join(SCENES)}; 50 camera angles each), {args.n} runs")
    print(f"  wall: median {median:.2f} s (runs: {', '.join(f'{r:.2f}' for r in runs)})")
    print(f"  sum of warm draw times (qdmr bench, median of 5 frames each): {warm:.2f} s")
    print(f"  ratio wall / warm draws: {median / warm:.2f}  (target <= 1.3)")
    print(f"  inside the run: draws {in_run_draw:.2f} s, plan + prepare {in_run_prepare:.2f} s")
    print(f"one-off check of a 1080p scene ({os.path.basename(scene)}): median {statistics.median(one_check):.3f} s; "
          f"qdmr render to PNG: median {statistics.median(one_render):.3f} s")
    print(f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f}; {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
