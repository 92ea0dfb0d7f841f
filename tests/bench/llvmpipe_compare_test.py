"""bench/llvmpipe_compare.py's plumbing, with stand-ins for qdmr and llvmpipe_bench that answer at once: both
precision pairs are timed, each with its own arithmetic on both sides (qdmr's sampling precision, llvmpipe's
GALLIVM_PERF), and the CPU model and qdmr's kernel ISA are printed beside the table. No renderer runs and nothing
is timed: the stand-ins' milliseconds are fixed, so the ratios in the table are exact."""
import json
import os
import re
import stat
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "bench", "llvmpipe_compare.py")

# qdmr bench: 10 ms with exact weights, 20 ms with hw8; it reports the kernel it was asked for.
FAKE_QDMR = r'''#!PYTHON
import json, sys
args = sys.argv[1:]
with open(LOG, "a") as f:
    f.write(json.dumps({"who": "qdmr", "args": args}) + "\n")
precision = [a.split("=", 1)[1] for a in args if "/sampling/precision=" in a]
isa = args[args.index("--isa") + 1]
ms = {"exact": 10.0, "hw8": 20.0}[precision[0]]
with open(args[args.index("--json") + 1], "w") as f:
    json.dump({"draw_ms": {"median": ms}, "isa": "avx2" if isa == "avx2" else "avx512", "threads": 2,
               "pixels_shaded": 1234}, f)
'''
# llvmpipe_bench: 30 ms with float filtering (GALLIVM_PERF=no_aos_sampling), 50 ms with its 8-bit default.
FAKE_LLVMPIPE = r'''#!PYTHON
import json, os, sys
with open(LOG, "a") as f:
    f.write(json.dumps({"who": "llvmpipe", "args": sys.argv[1:], "perf": os.environ.get("GALLIVM_PERF")}) + "\n")
ms = 30.0 if os.environ.get("GALLIVM_PERF") == "no_aos_sampling" else 50.0
print(json.dumps({"median_ms": ms, "renderer": "llvmpipe (stand-in)", "pixels_covered": 1200}))
'''


def write_tool(path, text, log):
    with open(path, "w") as f:
        f.write(text.replace("#!PYTHON", "#!" + sys.executable).replace("LOG", repr(log), 1))
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)


@pytest.fixture
def build(tmp_path):
    log = str(tmp_path / "calls.jsonl")
    os.makedirs(tmp_path / "bench" / "llvmpipe")
    write_tool(str(tmp_path / "qdmr"), FAKE_QDMR, log)
    write_tool(str(tmp_path / "bench" / "llvmpipe" / "llvmpipe_bench"), FAKE_LLVMPIPE, log)
    return tmp_path, log


def run(build_dir, *extra):
    env = dict(os.environ, GALLIVM_PERF="nopt")  # the caller's setting must not reach either pair
    return subprocess.run([sys.executable, SCRIPT, "-B", str(build_dir), "--timing-only", "--rounds", "1",
                           "--frames", "1", "--warmup", "0", "--width", "64", "--height", "36"] + list(extra),
                          check=True, stdout=subprocess.PIPE, text=True, env=env).stdout


def cpu_fields():
    """The first processor's /proc/cpuinfo fields."""
    fields = {}
    with open("/proc/cpuinfo") as f:
        for line in f:
            if not line.strip():
                break
            key, _, value = line.partition(":")
            fields[key.strip()] = value.strip()
    return fields


def table_rows(out):
    return [line.split("|")[1:-1] for line in out.splitlines() if re.match(r"\| (exact|hw8) ", line)]


def test_both_pairs_each_like_for_like(build):
    build_dir, log = build
    out = run(build_dir, "--isa", "avx2")
    rows = table_rows(out)
    cases = 8  # normal, POM, relief and QDM at two depths, and the grid
    assert len(rows) == 2 * cases
    for row in rows:
        pair, lp, q, ratio = row[0].strip(), float(row[3]), float(row[4]), row[5].strip()
        expected = {"exact / float": (30.0, 10.0), "hw8 / 8-bit": (50.0, 20.0)}[pair]
        assert (lp, q) == expected
        assert ratio == f"**{expected[0] / expected[1]:.2f}x**"
    calls = [json.loads(line) for line in open(log)]
    llvmpipe = [c for c in calls if c["who"] == "llvmpipe"]
    qdmr = [c for c in calls if c["who"] == "qdmr"]
    assert sorted(c["perf"] or "" for c in llvmpipe) == sorted(["no_aos_sampling"] * cases + [""] * cases)
    precisions = [a.rsplit("=", 1)[1] for c in qdmr for a in c["args"] if "/sampling/precision=" in a]
    assert sorted(precisions) == sorted(["exact"] * cases + ["hw8"] * cases)
    assert all(c["args"][c["args"].index("--isa") + 1] == "avx2" for c in qdmr)


def test_machine_and_kernel_beside_the_table(build):
    build_dir, _ = build
    out = run(build_dir, "--isa", "avx2", "--pairs", "hw8")
    # The model name alone does not tell the class apart (a VM may say only "AMD EPYC"): family and model, and
    # whether the CPU has AVX-512, are printed beside it.
    fields = cpu_fields()
    cpu_line = next(line for line in out.splitlines() if line.startswith("CPU: "))
    assert cpu_line.startswith(f"CPU: {fields['model name']} (family {fields['cpu family']} model {fields['model']} ")
    assert ("no AVX-512" in cpu_line) == ("avx512f" not in fields["flags"].split())
    assert "; qdmr: avx2 kernel" in cpu_line
    assert len(table_rows(out)) == 8 and all(r[0].strip() == "hw8 / 8-bit" for r in table_rows(out))
    assert "qdmr: avx512 kernel" in run(build_dir, "--pairs", "exact")
