#!/usr/bin/env python3
"""Issue #55's targets for glTF input: loading and planning a 1-million-triangle .glb against the same mesh as
qdmr's procedural grid (time: at most 1.5 x), and the peak memory of that plan against the mesh's own size as the
plan counts it (at most 1.3 x; the asset has no textures). The peak counted is what the asset adds to the command's
own: the peak of `qdmr plan` of the same .glb at resolution 1 (2 triangles) is taken off.

The .glb is written here: the grid of `{"type": "grid", "resolution": R}` (R = 708: 1,002,528 triangles) with
POSITION, NORMAL, TEXCOORD_0 and 32-bit indices, and no TANGENT (qdmr generates them, MikkTSpace's way), or with
TANGENT (--tangents: as exporters write them for normal-mapped assets). Each round runs
`qdmr plan` and a 16x16 `qdmr render` of both once; the table holds the median wall time, the peak resident memory (getrusage of the
child), the plan's mesh size, and the load average before and after (run it on a quiet machine, and under
`flock /tmp/qdmr-build.lock` where builds share the machine).

  bench/gltf_load.py [-n 5] [-B BUILD_DIR] [--resolution 708] [--tangents]
"""
import argparse
import json
import os
import re
import statistics
import struct
import subprocess
import tempfile

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


def measure(binary, target, rounds, command):
    script = ("import resource, subprocess, sys, time\n"
              "s = time.perf_counter(); o = subprocess.run(sys.argv[1:], check=True, capture_output=True, text=True).stdout\n"
              "t = time.perf_counter() - s\n"
              "print(t, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); print(o)\n")
    times, peaks = [], []
    for _ in range(rounds):
        out = subprocess.run(["python3", "-c", script, binary, *command(target)], check=True, capture_output=True,
                             text=True).stdout
        first = out.split("\n", 1)[0]
        t, kib = first.split()
        times.append(float(t))
        peaks.append(int(kib) / 1024)
    mesh = re.search(r"meshes ([0-9.]+) MiB", subprocess.run([binary, "plan", target], check=True, capture_output=True,
                                                             text=True).stdout)
    return statistics.median(times), max(peaks), float(mesh.group(1)) if mesh else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=5)
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
                    # 16x16 render holds both (and next to no drawing).
                    "render 16x16": lambda t: ["render", t, "-o", image, "--width", "16", "--height", "16"]}
        load = os.getloadavg()[0]
        rows = [(what, name, measure(binary, target, args.n, command)) for what, command in commands.items()
                for name, target in (("procedural grid", scene), (".glb", glb))]
        empty = measure(binary, tiny, args.n, commands["plan"])[1]
        load_after = os.getloadavg()[0]
    triangles = 2 * args.resolution ** 2
    print("| %d triangles%s, %d rounds | wall time (median) | peak RSS | plan's mesh size |" % (triangles, " (.glb with TANGENT)" if args.tangents else "", args.n))
    print("|---|---|---|---|")
    for what, name, (t, peak, mesh) in rows:
        print("| %s: %s | %.3f s | %.1f MiB | %.1f MiB |" % (what, name, t, peak, mesh))
    for what in commands:
        grid, gltf = [r[2] for r in rows if r[0] == what]
        print("| %s: .glb / grid | %.2f (target <= 1.5) | | |" % (what, gltf[0] / grid[0]))
    gltf = [r[2] for r in rows if r[0] == "plan" and r[1] == ".glb"][0]
    print("| plan: (.glb peak - %.1f MiB) / mesh | | %.2f (target <= 1.3) | |" % (empty, (gltf[1] - empty) / gltf[2]))
    print("load average: %.2f before, %.2f after" % (load, load_after))


if __name__ == "__main__":
    main()
