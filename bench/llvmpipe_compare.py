#!/usr/bin/env python3
"""qdmr vs Mesa llvmpipe on the same work: bench/llvmpipe/canonical.json with normal mapping, POM, relief and
QDM at depth scales 0.1 and 0.3, and the 1 M-triangle grid (issue #12's table).

1. The texel check (small frame, default 480x270): each technique and depth rendered by qdmr (`qdmr render
   --aov hit_uv --aov depth --aov iterations`) and by llvmpipe_bench (`--hit-uv`); for the pixels both cover,
   the fraction whose hit UVs agree within --tolerance UV in both coordinates (target >= 99 %), and the loop
   iterations per pixel on each side (mean, and the fraction of pixels with the same count).
2. The timing (default 1920x1080, 2 threads each): in every round each case runs once in each renderer,
   renderers alternating (the order flips every round); qdmr: `qdmr bench --frames N --warmup K`, its
   draw_ms median; llvmpipe: `llvmpipe_bench --runs N`, its median after the warm-up frame. The grid case
   (timed only) is scenes/plane.json's normal-mapped plane as a 710x710 grid (1,008,200 triangles) in both:
   `qdmr bench scenes/plane.json --set /objects/0/mesh=...` and `llvmpipe_bench --mesh grid`. The table gives
   the median over rounds, llvmpipe / qdmr, and the issue's goal (>= 2x normal, POM, relief and the grid;
   >= 4x QDM). Filtering is compared like for like, in two pairs (--pairs): `exact`, qdmr's float filter weights
   against llvmpipe with GALLIVM_PERF=no_aos_sampling (its float filtering path), and `hw8`, qdmr's 8-bit
   fixed-point weights (precision=hw8) against llvmpipe's default (8-bit fixed-point filtering of 8-bit textures).
   Each pair is a column group of its own; the rounds alternate renderers and pairs.
The CPU model, qdmr's kernel ISA and the load average (before and after) are printed with the table.

    bench/llvmpipe_compare.py [-B BUILD_DIR] [--qdmr QDMR] [--rounds 5] [--frames 5] [--warmup 2]
                              [--threads 2] [--isa auto] [--pairs exact,hw8] [--check-only | --timing-only]
                              [--keep DIR]

Needs: qdmr and llvmpipe_bench built (cmake --build build/release --target qdmr_cli llvmpipe_bench), and a
python3 with numpy and OpenImageIO's module (Debian's python3-openimageio: run it with the system python3).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

try:
    import numpy
    import OpenImageIO  # noqa: F401 (bench_util.read_exr reads the AOVs with it: missing, say so before any render)
except ImportError:
    sys.exit("llvmpipe_compare.py needs numpy and OpenImageIO's Python module (Debian: python3-openimageio, "
             "for the system python3)")

from bench_util import cpu_model, read_exr  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "bench", "llvmpipe", "canonical.json")
MATERIAL = "/materials/cobbles"
CASES = [("normal", 0.1)] + [(t, d) for t in ("pom", "relief", "qdm") for d in (0.1, 0.3)]
TIMED_CASES = CASES + [("grid", None)]
GOALS = {"normal": 2.0, "pom": 2.0, "relief": 2.0, "qdm": 4.0, "grid": 2.0}  # llvmpipe / qdmr, issue #12
GRID_SCENE = os.path.join(ROOT, "scenes", "plane.json")
GRID_MESH = '/objects/0/mesh={"type":"grid","size":[4,4],"resolution":710,"uv_scale":[2,2]}'  # as llvmpipe_bench's
LLVMPIPE_ENV = {"LIBGL_ALWAYS_SOFTWARE": "1", "GALLIUM_DRIVER": "llvmpipe"}
# The precision pairs: qdmr's sampling/precision, and what llvmpipe's environment adds for the same arithmetic.
PAIRS = {"exact": ("exact", {"GALLIVM_PERF": "no_aos_sampling"}), "hw8": ("hw8", {})}


def arguments():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("-B", default=os.path.join(ROOT, "build", "release"), help="build folder of llvmpipe_bench")
    p.add_argument("--qdmr", help="the qdmr binary (default: BUILD_DIR/qdmr)")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--frames", type=int, default=5, help="timed frames per run, both renderers")
    p.add_argument("--warmup", type=int, default=2, help="qdmr bench's untimed frames (llvmpipe: always one)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--isa", default="auto", help="qdmr's kernel (qdmr bench --isa): auto, avx512, avx2, sse4.2")
    p.add_argument("--pairs", default="exact,hw8",
                   help="precision pairs to time, comma-separated: exact (qdmr exact vs llvmpipe float filtering), "
                        "hw8 (qdmr hw8 vs llvmpipe's default 8-bit filtering)")
    p.add_argument("--width", type=int, default=1920)
    p.add_argument("--height", type=int, default=1080)
    p.add_argument("--check-width", type=int, default=480)
    p.add_argument("--check-height", type=int, default=270)
    p.add_argument("--tolerance", type=float, default=1e-3, help="hit UV agreement, UV units")
    p.add_argument("--check-only", action="store_true")
    p.add_argument("--timing-only", action="store_true")
    p.add_argument("--keep", help="keep the images and JSON files (timing.json: every round) in this folder")
    return p.parse_args()


def technique_sets(technique, depth):
    return ["--set", f"{MATERIAL}/technique/name={technique}", "--set", f"{MATERIAL}/technique/depth_scale={depth}"]


def run_json(cmd, env=None, json_file=None):
    """Runs cmd; returns the JSON it printed (its last line), or the JSON file it wrote."""
    out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True, env=env).stdout
    if json_file:
        with open(json_file) as f:
            return json.load(f)
    return json.loads(out.strip().splitlines()[-1])


def llvmpipe_env(threads, pair=None):
    env = dict(os.environ)
    env.pop("GALLIVM_PERF", None)  # the pair decides
    env.update(LLVMPIPE_ENV)
    env["LP_NUM_THREADS"] = str(threads)
    if pair:
        env.update(PAIRS[pair][1])
    return env


def read_pfm(path):
    """A PFM file as a float array (height, width, channels), top row first (PFM stores rows bottom to top)."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        width, height = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        channels = {b"PF": 3, b"Pf": 1}[kind]
        data = numpy.frombuffer(f.read(width * height * channels * 4), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(height, width, channels)[::-1]


def check_case(qdmr, llvmpipe, technique, depth, args, tmp):
    """The texel check of one case: both renderers at the check size, hit UVs and iterations compared."""
    w, h = args.check_width, args.check_height
    base = os.path.join(tmp, f"check_{technique}_{depth}")
    subprocess.run([qdmr, "render", SCENE, "-o", base + "_qdmr.exr", "--width", str(w), "--height", str(h),
                    "--threads", str(args.threads), "--aov", f"hit_uv={base}_uv.exr",
                    "--aov", f"depth={base}_depth.exr", "--aov", f"iterations={base}_it.exr",
                    "--stats", base + "_stats.json"] + technique_sets(technique, depth),
                   check=True, stdout=subprocess.DEVNULL)
    lp = run_json([llvmpipe, "--technique", technique, "--depth", str(depth), "--width", str(w), "--height", str(h),
                   "--hit-uv", base + "_llvmpipe.pfm"], env=llvmpipe_env(args.threads))
    with open(base + "_stats.json") as f:
        stats = json.load(f)
    q_uv, q_it = read_exr(base + "_uv.exr"), read_exr(base + "_it.exr")[..., 0]
    q_covered = read_exr(base + "_depth.exr")[..., 0] > 0.0  # uncovered pixels are 0 in every AOV
    lp_pixels = read_pfm(base + "_llvmpipe.pfm")
    if lp_pixels.shape[:2] != (h, w):
        raise RuntimeError(f"llvmpipe_bench wrote {lp_pixels.shape[1]}x{lp_pixels.shape[0]}, expected {w}x{h}")
    l_uv, l_it = lp_pixels[..., :2], lp_pixels[..., 2]
    l_covered = l_it >= 0.0  # -1 where no triangle covers the pixel
    both = q_covered & l_covered
    n = max(int(both.sum()), 1)
    error = numpy.abs(q_uv[both] - l_uv[both]).max(axis=1)
    return {"technique": technique, "depth": depth, "qdmr_pixels": stats["shading"]["pixels_shaded"],
            "llvmpipe_pixels": lp["pixels_covered"], "both": int(both.sum()),
            "qdmr_only": int((q_covered & ~l_covered).sum()), "llvmpipe_only": int((l_covered & ~q_covered).sum()),
            "agree": float((error <= args.tolerance).sum()) / n, "worst_uv": float(error.max(initial=0.0)),
            "qdmr_iterations": float(q_it[both].mean()), "llvmpipe_iterations": float(l_it[both].mean()),
            "same_iterations": float((q_it[both] == l_it[both]).sum()) / n, "knobs": lp.get("knobs", {})}


def check_knobs(knobs):
    """llvmpipe_bench compiles canonical.json's knobs into its shaders: stop if the two have drifted apart."""
    with open(SCENE) as f:
        material = json.load(f)["materials"]["cobbles"]
    technique = dict(material["technique"], height_side=material["layers"][0]["height"]["size"],
                     math=material["sampling"]["math"])
    drift = {k: (technique.get(k), v) for k, v in knobs.items() if k in technique and technique[k] != v}
    if drift:
        raise RuntimeError(f"canonical.json and llvmpipe_bench disagree (scene, bench): {drift}")


def texel_check(qdmr, llvmpipe, args, tmp):
    print(f"## Texel check: {args.check_width}x{args.check_height}, hit UVs within {args.tolerance:g} UV\n")
    print("| technique | depth | pixels qdmr / llvmpipe / both | hit UV agree | worst UV error "
          "| iterations mean qdmr / llvmpipe | same iteration count |")
    print("|---|---|---|---|---|---|---|")
    results = []
    for technique, depth in CASES:
        r = check_case(qdmr, llvmpipe, technique, depth, args, tmp)
        check_knobs(r["knobs"])
        results.append(r)
        depth_text = "-" if technique == "normal" else f"{depth:g}"
        print(f"| {technique} | {depth_text} | {r['qdmr_pixels']} / {r['llvmpipe_pixels']} / {r['both']} "
              f"| **{100 * r['agree']:.3f} %** | {r['worst_uv']:.2e} "
              f"| {r['qdmr_iterations']:.2f} / {r['llvmpipe_iterations']:.2f} | {100 * r['same_iterations']:.2f} % |",
              flush=True)
    failed = [r for r in results if r["agree"] < 0.99]
    print("\nAll cases >= 99 %." if not failed else f"\nBelow 99 %: {[(r['technique'], r['depth']) for r in failed]}")
    return not failed


def time_qdmr(qdmr, technique, depth, pair, args, tmp):
    out = os.path.join(tmp, "qdmr_bench.json")
    if technique == "grid":
        scene = [GRID_SCENE, "--set", GRID_MESH, "--set", f"/materials/bricks/sampling/precision={PAIRS[pair][0]}"]
    else:
        scene = [SCENE] + technique_sets(technique, depth) + ["--set", f"{MATERIAL}/sampling/precision={PAIRS[pair][0]}"]
    result = run_json([qdmr, "bench"] + scene + ["--frames", str(args.frames), "--warmup", str(args.warmup),
                      "--threads", str(args.threads), "--width", str(args.width), "--height", str(args.height),
                      "--isa", args.isa, "--json", out], json_file=out)
    return result["draw_ms"]["median"], result


def time_llvmpipe(llvmpipe, technique, depth, pair, args):
    case = ["--mesh", "grid"] if technique == "grid" else ["--technique", technique, "--depth", str(depth)]
    result = run_json([llvmpipe] + case + ["--width", str(args.width), "--height", str(args.height),
                                           "--runs", str(args.frames)], env=llvmpipe_env(args.threads, pair))
    return result["median_ms"], result


def measure_rounds(qdmr, llvmpipe, pairs, args, tmp):
    """{(pair, case): {"qdmr": [ms per round], "llvmpipe": [...]}} and the last JSON of each renderer. Within a
    round each case runs in both renderers back to back, pair after pair; which goes first flips every round."""
    times = {(pair, case): {"qdmr": [], "llvmpipe": []} for pair in pairs for case in TIMED_CASES}
    info = {}
    for r in range(args.rounds):
        for case in TIMED_CASES:
            for pair in pairs if r % 2 == 0 else pairs[::-1]:
                for who in ("llvmpipe", "qdmr") if r % 2 == 0 else ("qdmr", "llvmpipe"):
                    if who == "qdmr":
                        ms, info[who] = time_qdmr(qdmr, *case, pair, args, tmp)
                    else:
                        ms, info[who] = time_llvmpipe(llvmpipe, *case, pair, args)
                    times[(pair, case)][who].append(ms)
        print(f"round {r + 1}/{args.rounds} done, load average {os.getloadavg()[0]:.2f}", file=sys.stderr, flush=True)
    return times, info


def per_round(values):
    return " ".join(f"{v:.1f}" for v in values)


def timing(qdmr, llvmpipe, args, tmp):
    pairs = [p.strip() for p in args.pairs.split(",") if p.strip()]
    unknown = [p for p in pairs if p not in PAIRS]
    if not pairs or unknown:
        sys.exit(f"llvmpipe_compare.py: --pairs: unknown pair(s) {unknown}; choose from {', '.join(PAIRS)}")
    print(f"\n## Timing: {args.width}x{args.height}, {args.threads} threads each, {args.rounds} rounds; "
          f"qdmr bench {args.frames} frames after {args.warmup}, llvmpipe {args.frames} after 1\n")
    times, info = measure_rounds(qdmr, llvmpipe, pairs, args, tmp)
    with open(os.path.join(tmp, "timing.json"), "w") as f:  # every round's times, kept with --keep
        json.dump([{"pair": p, "technique": c[0], "depth": c[1], **times[(p, c)]} for p in pairs for c in TIMED_CASES],
                  f, indent=1)
    print(f"CPU: {cpu_model()}; qdmr: {info['qdmr']['isa']} kernel, {info['qdmr']['threads']} threads, "
          f"{info['qdmr']['pixels_shaded']} pixels shaded; llvmpipe: {info['llvmpipe']['renderer']}, "
          f"{info['llvmpipe']['pixels_covered']} pixels covered (last case)\n")
    print("| pair | technique | depth | llvmpipe ms | qdmr ms | llvmpipe / qdmr | goal | met "
          "| llvmpipe ms per round | qdmr ms per round |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for pair in pairs:
        label = {"exact": "exact / float", "hw8": "hw8 / 8-bit"}[pair]
        for technique, depth in TIMED_CASES:
            t = times[(pair, (technique, depth))]
            lp, q = statistics.median(t["llvmpipe"]), statistics.median(t["qdmr"])
            ratio, goal = lp / q, GOALS[technique]
            depth_text = "-" if depth is None or technique == "normal" else f"{depth:g}"
            print(f"| {label} | {technique} | {depth_text} | {lp:.1f} | {q:.1f} | **{ratio:.2f}x** | >= {goal:g}x "
                  f"| {'yes' if ratio >= goal else 'no'} | {per_round(t['llvmpipe'])} | {per_round(t['qdmr'])} |")


def load_line(when):
    one, five, fifteen = os.getloadavg()
    return f"load average {when}: {one:.2f} {five:.2f} {fifteen:.2f} ({os.cpu_count()} CPUs)"


def main():
    args = arguments()
    qdmr = args.qdmr or os.path.join(args.B, "qdmr")
    llvmpipe = os.path.join(args.B, "bench", "llvmpipe", "llvmpipe_bench")
    for path in (qdmr, llvmpipe):
        if not os.access(path, os.X_OK):
            sys.exit(f"llvmpipe_compare.py: {path} is not built")
    if args.keep:
        os.makedirs(args.keep, exist_ok=True)
    tmp_holder = None if args.keep else tempfile.TemporaryDirectory(prefix="llvmpipe-compare-")
    tmp = args.keep or tmp_holder.name
    print(load_line("before"), flush=True)
    ok = True
    if not args.timing_only:
        ok = texel_check(qdmr, llvmpipe, args, tmp)
    if not args.check_only:
        timing(qdmr, llvmpipe, args, tmp)
    print("\n" + load_line("after"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
