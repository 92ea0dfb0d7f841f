#!/usr/bin/env python3
"""What qdmr costs from Python (docs/performance.md, "qdmr from Python"), against the command doing the same:

  - draw: `Renderer.draw()` timed around the call (the frame's arrays included) against `qdmr bench`'s median warm
    draw of the same scene, size, threads and ISA, at 480x270 and 1920x1080 (target <= 1.05x);
  - study: `qdmr.study.run` in process against `qdmr study` (a process), wall time of the 100-configuration study
    of bench/study_overhead.py (target <= 1.1x);
  - dask: a shipped study (studies/filtering.json: 54 configurations) on a Dask LocalCluster of 2 single-thread
    worker processes against one process with 1 thread, wall time (target <= 0.6x); the cluster's start is timed
    apart.

Each case's two sides run in turns, the order flipped every round; each prints the median of the per-round ratios.
Run it on a quiet machine (the load average is printed), with Debian's python3 and the build's package:
  PYTHONPATH=build/release/python /usr/bin/python3 bench/python_costs.py [-n 3] [-B build/release] [--only draw]
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

import qdmr  # noqa: E402

PLANE = os.path.join(bench_util.ROOT, "scenes", "plane.json")
STUDY_100 = {
    "scene": PLANE, "width": 480, "height": 270, "frames": 3, "warmup": 1, "metrics": ["time", "iterations"],
    "axes": [
        {"name": "technique", "path": "/materials/bricks/technique/name", "values": ["normal", "pom", "relief", "qdm", "csm"]},
        {"name": "elevation", "camera": "elevation", "range": {"from": 10, "to": 80, "steps": 10}},
        {"name": "depth", "path": "/materials/bricks/technique/depth_scale", "values": [0.02, 0.05]},
    ],
}


def load():
    return f"{os.getloadavg()[0]:.2f}"


def in_turns(k, first, second):
    """Round k's two measurements, the order flipped every round: on these VMs the second process of a round runs
    measurably slower (a 1080p draw: 1.029 with Python first, 1.083 with the command first, 100 rounds)."""
    if k % 2 == 0:
        first()
        second()
    else:
        second()
        first()


def draw_costs(args, cli, width, height, frames=30, warmup=3):
    """Median ms of draw() from Python and of `qdmr bench`'s draws, the same scene and settings."""
    python, command = [], []
    isa = qdmr.Renderer(threads=1).isa

    def from_python():
        renderer = qdmr.Renderer(threads=args.threads)
        renderer.set_scene(qdmr.load_scene(PLANE, {"/output/width": width, "/output/height": height}))
        times = []
        for k in range(warmup + frames):
            start = time.perf_counter()
            frame = renderer.draw()
            frame.color  # the array a caller gets
            if k >= warmup:
                times.append((time.perf_counter() - start) * 1000.0)
        python.append(statistics.median(times))

    def from_command():
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "b.json")
            subprocess.run([cli, "bench", PLANE, "--frames", str(frames), "--warmup", str(warmup), "--threads",
                            str(args.threads), "--isa", isa, "--width", str(width), "--height", str(height),
                            "--json", out, "--image", os.path.join(tmp, "b.png")],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            with open(out) as f:
                command.append(json.load(f)["draw_ms"]["median"])

    for k in range(args.n):
        in_turns(k, from_python, from_command)
    return python, command


def study_costs(args, cli):
    python, command = [], []
    with tempfile.TemporaryDirectory() as tmp:
        spec = os.path.join(tmp, "s.json")
        with open(spec, "w") as f:
            json.dump(STUDY_100, f)
        for k in range(args.n):
            def from_command():
                start = time.perf_counter()
                subprocess.run([cli, "study", spec, "-o", os.path.join(tmp, f"c{k}"), "--threads", str(args.threads)],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                command.append(time.perf_counter() - start)

            def from_python():
                start = time.perf_counter()
                qdmr.study.run(spec, os.path.join(tmp, f"p{k}"), threads=args.threads)
                python.append(time.perf_counter() - start)

            in_turns(k, from_python, from_command)
    return python, command


def dask_costs(args):
    from distributed import Client, LocalCluster
    spec = os.path.join(bench_util.ROOT, "studies", "filtering.json")
    one, spread, starts = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.n):
            def in_one_process():
                start = time.perf_counter()
                qdmr.study.run(spec, os.path.join(tmp, f"one{k}"), threads=1)
                one.append(time.perf_counter() - start)

            def on_the_cluster():
                start = time.perf_counter()
                cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
                with cluster, Client(cluster) as client:
                    client.run(lambda: __import__("qdmr").__version__)  # every worker started and qdmr imported
                    starts.append(time.perf_counter() - start)
                    start = time.perf_counter()
                    qdmr.study.run(spec, os.path.join(tmp, f"dask{k}"), client=client)
                    spread.append(time.perf_counter() - start)

            in_turns(k, on_the_cluster, in_one_process)
    return one, spread, starts


def print_pair(case, python_name, python, command_name, command, unit, digits, target):
    """One line: the median (and range) of each side's times, and the median of the per-round ratios."""
    def side(name, times):
        return (f"{name} {statistics.median(times):.{digits}f} {unit} "
                f"({min(times):.{digits}f} - {max(times):.{digits}f})")
    ratios = [p / c for p, c in zip(python, command)]
    print(f"{case}: {side(python_name, python)}, {side(command_name, command)}: ratio {statistics.median(ratios):.3f} "
          f"(target <= {target:g}); load {load()}")


def main():
    parser = bench_util.arguments(__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2, help="threads of the draw and study cases (default 2)")
    parser.add_argument("--only", choices=["draw", "study", "dask"], help="one case only")
    args = parser.parse_args()
    cli = os.path.join(args.B, "qdmr")
    print(f"qdmr {qdmr.__version__} ({qdmr.__file__}), {os.cpu_count()} cores, load average {load()}")
    if args.only in (None, "draw"):
        for width, height in ((480, 270), (1920, 1080)):
            python, command = draw_costs(args, cli, width, height)
            print_pair(f"draw {width}x{height}, {args.threads} threads", "Python draw()", python, "qdmr bench", command,
                       "ms", 3, 1.05)
    if args.only in (None, "study"):
        python, command = study_costs(args, cli)
        print_pair(f"study, 100 configurations, {args.threads} threads", "qdmr.study.run", python, "qdmr study", command,
                   "s", 2, 1.1)
    if args.only in (None, "dask"):
        one, spread, starts = dask_costs(args)
        ratios = [s / o for s, o in zip(spread, one)]
        print(f"dask, studies/filtering.json: one process (1 thread) {statistics.median(one):.2f} s "
              f"({min(one):.2f} - {max(one):.2f}), LocalCluster 2 x 1 thread {statistics.median(spread):.2f} s "
              f"({min(spread):.2f} - {max(spread):.2f}): ratio {statistics.median(ratios):.3f} (target <= 0.6); "
              f"the cluster's start {statistics.median(starts):.2f} s apart, with it "
              f"{statistics.median([(s + t) / o for s, t, o in zip(spread, starts, one)]):.3f}; load {load()}")


if __name__ == "__main__":  # LocalCluster's worker processes import this module again
    main()
