"""Markdown tables of medians from the files bench/run_scenes.sh writes.

Input: a folder of CASE__BUILD__tTHREADS__rROUND.json (qdmr --stats) and CASE__llvmpipe__tT__rR.lp.json
(bench/llvmpipe output). "frame" = geometry + binning + raster_shade of one run (prepare is a one-off).
"""
import json
import pathlib
import statistics
import sys
from collections import defaultdict

STAGES = ["prepare", "geometry", "binning", "raster_shade", "write"]
MB = 1024 * 1024


def load(folder):
    runs = defaultdict(list)  # (case, build, threads) -> [stats]
    lp = defaultdict(list)    # (case, threads) -> [ms]
    for f in sorted(pathlib.Path(folder).glob("*.json")):
        case, build, t, _ = f.name.split(".")[0].split("__")
        data = json.loads(f.read_text())
        if f.name.endswith(".lp.json"):
            lp[(case, int(t[1:]))].append(data["median_ms"])
        else:
            runs[(case, build, int(t[1:]))].append(data)
    return runs, lp


def frame_ms(s):
    t = s["time_ms"]
    return t["geometry"] + t["binning"] + t["raster_shade"]


def med(values):
    return statistics.median(values)


def table(header, rows):
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print()


def main(folder):
    runs, lp = load(folder)
    cases = list(dict.fromkeys(k[0] for k in runs))
    builds = sorted({k[1] for k in runs})
    threads = sorted({k[2] for k in runs})

    print("### Median ms per stage (frame = geometry + binning + raster_shade)\n")
    rows = []
    for c in cases:
        for b in builds:
            for t in threads:
                rs = runs.get((c, b, t))
                if not rs:
                    continue
                st = [med([r["time_ms"][s] for r in rs]) for s in STAGES]
                rows.append([c, b, str(t), str(rs[0]["triangles"]["in"]), str(rs[0]["shading"]["pixels_shaded"])]
                            + [f"{v:.1f}" for v in st[:4]] + [f"**{med([frame_ms(r) for r in rs]):.1f}**", f"{st[4]:.1f}",
                                                              f"{min(frame_ms(r) for r in rs):.1f}–{max(frame_ms(r) for r in rs):.1f}"])
    table(["case", "build", "threads", "triangles", "pixels shaded", "prepare", "geometry", "binning", "raster_shade",
           "frame", "write", "frame min–max"], rows)

    if len(threads) > 1:
        t0, t1 = threads[0], threads[-1]
        print(f"### Thread scaling, {t0} → {t1} threads (ratio of medians)\n")
        rows = []
        for c in cases:
            for b in builds:
                a, z = runs.get((c, b, t0)), runs.get((c, b, t1))
                if not a or not z:
                    continue
                ratio = lambda f: med([f(r) for r in a]) / max(med([f(r) for r in z]), 1e-9)
                rows.append([c, b, f"**{ratio(frame_ms):.2f}×**"]
                            + [f"{ratio(lambda r, s=s: r['time_ms'][s]):.2f}×" for s in ["geometry", "binning", "raster_shade", "prepare"]]
                            + [f"{100 * med([r['time_ms']['raster_shade'] / frame_ms(r) for r in z]):.0f} %"])
        table(["case", "build", "frame", "geometry", "binning", "raster_shade", "prepare",
               f"raster_shade share of frame at {t1} threads"], rows)

    if "qdmr-sse" in builds and "qdmr" in builds:
        print("### SIMD: SSE4.2 (4 lanes) vs AVX2 (8 lanes), median frame ms\n")
        rows = []
        for c in cases:
            for t in threads:
                s, a = runs.get((c, "qdmr-sse", t)), runs.get((c, "qdmr", t))
                if not s or not a:
                    continue
                fs, fa = med([frame_ms(r) for r in s]), med([frame_ms(r) for r in a])
                rs_s = med([r["time_ms"]["raster_shade"] for r in s])
                rs_a = med([r["time_ms"]["raster_shade"] for r in a])
                rows.append([c, str(t), f"{fs:.1f}", f"{fa:.1f}", f"**{fs / fa:.2f}×**", f"{rs_s / rs_a:.2f}×"])
        table(["case", "threads", "SSE4.2 frame", "AVX2 frame", "AVX2 gain (frame)", "AVX2 gain (raster_shade)"], rows)

    print("### Memory (largest thread count, first build)\n")
    rows = []
    for c in cases:
        rs = runs.get((c, builds[0], threads[-1]))
        if not rs:
            continue
        m = rs[0]["memory"]
        peak = med([r["memory"]["peak_rss_bytes"] for r in rs])
        fb, tex, mesh = m["framebuffer_bytes"], m["texture_bytes"], m["mesh_bytes"]
        rows.append([c, f"{peak / MB:.0f}", f"{fb / MB:.1f}", f"{tex / MB:.1f}", f"{mesh / MB:.1f}",
                     f"{(peak - fb - tex - mesh) / MB:.0f}", f"{100 * fb / peak:.0f} %"])
    table(["case", "peak RSS MiB", "framebuffer MiB", "textures MiB", "meshes MiB", "rest MiB", "framebuffer share"], rows)

    if "grid1m" in cases:
        print("### Throughput, grid1m (triangles in per second, from the medians)\n")
        rows = []
        for b in builds:
            for t in threads:
                rs = runs.get(("grid1m", b, t))
                if not rs:
                    continue
                n = rs[0]["triangles"]["in"]
                g, bn, r = (med([x["time_ms"][s] for x in rs]) for s in ["geometry", "binning", "raster_shade"])
                rows.append([b, str(t), f"{n / (g + bn + r) / 1e3:.2f}", f"{n / g / 1e3:.2f}", f"{n / bn / 1e3:.2f}",
                             f"{n / (g + bn) / 1e3:.2f}", f"{n / r / 1e3:.2f}"])
        table(["build", "threads", "frame Mtri/s", "geometry Mtri/s", "setup+binning Mtri/s", "geometry+setup+binning Mtri/s",
               "raster+shade Mtri/s"], rows)

    if lp:
        print("### Mesa llvmpipe vs qdmr (median frame ms; qdmr frame = geometry + binning + raster_shade)\n")
        rows = []
        for c in cases:
            for t in threads:
                if (c, t) not in lp or (c, "qdmr", t) not in runs:
                    continue
                q, l = med([frame_ms(r) for r in runs[(c, "qdmr", t)]]), med(lp[(c, t)])
                rows.append([c, str(t), f"{q:.1f}", f"{l:.1f}", f"**{q / l:.2f}**"])
        for c in cases:
            if len(threads) > 1 and (c, threads[0]) in lp and (c, threads[-1]) in lp:
                rows.append([c, f"{threads[0]}→{threads[-1]} scaling", "", "",
                             f"llvmpipe {med(lp[(c, threads[0])]) / med(lp[(c, threads[-1])]):.2f}×"])
        table(["case", "threads", "qdmr AVX2", "llvmpipe", "qdmr / llvmpipe"], rows)


if __name__ == "__main__":
    main(sys.argv[1])
