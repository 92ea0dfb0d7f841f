#!/usr/bin/env python3
"""Issue #55's targets for glTF input: loading and planning a 1-million-triangle .glb against the same mesh as
qdmr's procedural grid (time: at most 1.5 x), and the peak memory of that plan against the mesh's own size as the
plan counts it (at most 1.3 x; the asset has no textures). The peak counted is what the asset adds to the command's
own: the peak of `qdmr plan` of the same .glb at resolution 1 (2 triangles) is taken off.

The .glb is written here: the grid of `{"type": "grid", "resolution": R}` (R = 708: 1,002,528 triangles) with
POSITION, NORMAL, TEXCOORD_0 and 32-bit indices, and no TANGENT (qdmr generates them, MikkTSpace's way), or with
TANGENT (--tangents: as exporters write them for normal-mapped assets). Each round runs `qdmr plan` and then a
16x16 `qdmr render` of the grid and of the .glb, one right after the other (the .glb first in every other round),
and takes the ratio .glb / grid of that round; the table holds the median of those ratios, the median wall times,
the CPU time and peak resident memory (wait4 of the child), the plan's mesh size, the CPU model and the load average after each
round. Run it on a quiet machine, and under `flock /tmp/qdmr-build.lock` where builds share the machine.

  bench/gltf_load.py [-n 11] [-B BUILD_DIR] [--resolution 708] [--tangents]
"""
import argparse
import json
import os
import re
import statistics
import struct
import subprocess
import sys
import tempfile
import time

from bench_util import cpu_model

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def grid_glb(path, resolution, tangents=False):
    """The procedural grid's vertices (size 2, in glTF's XZ plane facing +Y) as one .glb."""
    n = resolution + 1
    positions, normals, uvs, frame = bytearray(), bytearray(), bytearray(), bytearray()
    for j in range(n):
        for i in range(n):
            u, v = i / resolution, j / resolution
            positions += struct.pack("<3f", -1 + 2 * u, 0.0, 1 - 2 * v)
            normals += struct.pack("<3f", 0.0, 1.0, 0.0)
            uvs += struct.pack("<2f", u, 1 - v)
            frame += struct.pack("<4f", 1.0, 0.0, 0.0, 1.0)
    indices = bytearray()
    for j in range(resolution):
        for i in range(resolution):
            a = j * n + i
            indices += struct.pack("<6I", a, a + 1, a + n + 1, a, a + n + 1, a + n)
    blobs = [positions, normals, uvs, indices] + ([frame] if tangents else [])
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    count = n * n
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": dict({"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                                       **({"TANGENT": 4} if tangents else {})), "indices": 3}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
            {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": count, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": len(indices) // 4, "type": "SCALAR"}] +
            ([{"bufferView": 4, "componentType": 5126, "count": count, "type": "VEC4"}] if tangents else []),
        "bufferViews": views, "buffers": [{"byteLength": offset}]}
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    body = b"".join(blobs)
    glb = (struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(body)) + struct.pack("<II", len(js), 0x4E4F534A) + js +
           struct.pack("<II", len(body), 0x004E4942) + body)
    with open(path, "wb") as f:
        f.write(glb)


# The command runs under a small Python process of its own: a child's peak resident memory (ru_maxrss) counts the
# memory of the process it was forked from, and this one holds the asset it wrote.
TIMER = ("import os, subprocess, sys, time\n"
         "s = time.perf_counter(); c = subprocess.Popen(sys.argv[1:], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)\n"
         "_, status, usage = os.wait4(c.pid, 0); t = time.perf_counter() - s\n"
         "print(t, usage.ru_utime + usage.ru_stime, usage.ru_maxrss, os.waitstatus_to_exitcode(status))\n")


def run(binary, args):
    """Wall time, CPU time (user + system, all threads) and peak resident memory (MiB) of one command."""
    out = subprocess.run([sys.executable, "-c", TIMER, binary, *args], check=True, capture_output=True, text=True).stdout
    seconds, cpu, kib, code = out.split()
    if int(code) != 0:
        raise SystemExit("gltf_load: %s %s exited with %s" % (binary, " ".join(args), code))
    return float(seconds), float(cpu), int(kib) / 1024


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=11, help="rounds (default 11)")
    ap.add_argument("-B", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--resolution", type=int, default=708)
    ap.add_argument("--tangents", action="store_true", help="write TANGENT into the .glb")
    args = ap.parse_args()
    binary = os.path.join(args.B, "qdmr")
    with tempfile.TemporaryDirectory() as tmp:
        glb = os.path.join(tmp, "grid.glb")
        grid_glb(glb, args.resolution, args.tangents)
        tiny = os.path.join(tmp, "tiny.glb")
        grid_glb(tiny, 1, args.tangents)
        scene = os.path.join(tmp, "grid.json")
        with open(scene, "w") as f:
            json.dump({"materials": {"m": {"layers": [{"albedo": {"constant": 0.5}}]}},
                       "objects": [{"mesh": {"type": "grid", "size": 2, "resolution": args.resolution}, "material": "m"}]}, f)
        image = os.path.join(tmp, "x.png")
        commands = {"plan": lambda t: ["plan", t],
                    # The grid's mesh is built when the frame is prepared, a .glb's when the scene is loaded: a
                    # 16x16 render holds both (and next to no drawing). The target is this row.
                    "render 16x16": lambda t: ["render", t, "-o", image, "--width", "16", "--height", "16"]}
        targets = (("procedural grid", scene), (".glb", glb))
        times = {(what, name): [] for what in commands for name, _ in targets}
        cpus = {key: [] for key in times}
        peaks = {key: [] for key in times}
        ratios = {what: [] for what in commands}
        cpu_ratios = {what: [] for what in commands}
        empty = []
        loads = [os.getloadavg()[0]]
        # Round by round, the grid and the .glb one after the other (which goes first alternates), so a change of
        # the machine's load moves both sides of each round's ratio alike.
        for r in range(args.n):
            for what, command in commands.items():
                for name, target in (targets if r % 2 == 0 else targets[::-1]):
                    t, cpu, peak = run(binary, command(target))
                    times[(what, name)].append(t)
                    cpus[(what, name)].append(cpu)
                    peaks[(what, name)].append(peak)
                ratios[what].append(times[(what, ".glb")][-1] / times[(what, "procedural grid")][-1])
                cpu_ratios[what].append(cpus[(what, ".glb")][-1] / cpus[(what, "procedural grid")][-1])
            empty.append(run(binary, commands["plan"](tiny))[2])
            loads.append(os.getloadavg()[0])
        plan = subprocess.run([binary, "plan", glb], check=True, capture_output=True, text=True).stdout
        found = re.search(r"meshes ([0-9.]+) MiB", plan)
        mesh = float(found.group(1)) if found else float("nan")
    triangles = 2 * args.resolution ** 2
    print("%s, %d cores; load average (1 min) %.2f before, %.2f-%.2f during, %.2f after"
          % (cpu_model(), os.cpu_count(), loads[0], min(loads[1:]), max(loads[1:]), loads[-1]))
    print("| %d triangles%s, %d alternating rounds | wall time (median) | CPU time (median) | peak RSS (max) |"
          % (triangles, " (.glb with TANGENT)" if args.tangents else "", args.n))
    print("|---|---|---|---|")
    for (what, name), ts in times.items():
        print("| %s: %s | %.3f s | %.3f s | %.1f MiB |" % (what, name, statistics.median(ts),
                                                         statistics.median(cpus[(what, name)]), max(peaks[(what, name)])))
    for what, rs in ratios.items():
        note = ("target <= 1.5" if what != "plan" else
                "not the target: the grid's plan builds no mesh, the .glb's loads it")
        cs = cpu_ratios[what]
        print("| %s: .glb / grid, median of the rounds' ratios (min-max; %s) | %.2f (%.2f-%.2f) | %.2f (%.2f-%.2f) | |"
              % (what, note, statistics.median(rs), min(rs), max(rs), statistics.median(cs), min(cs), max(cs)))
    gltf_peak = max(peaks[("plan", ".glb")])
    print("| plan: (.glb peak - %.1f MiB, the command's own) / the plan's mesh size %.1f MiB | | | %.2f (target <= 1.3) |"
          % (max(empty), mesh, (gltf_peak - max(empty)) / mesh))


if __name__ == "__main__":
    main()
