"""Faults around a correct input (docs/testing.md, "Faults"): SIGKILL at spread-out moments then the same command
again, Ctrl-C, two processes on one folder or file, a full and a read-only file system, a bake cache past its
limit and a damaged entry. Run by CTest (faults.injection) with QDMR (the binary) and QDMR_SOURCE_DIR set.

The full-disk and read-only cases mount a small tmpfs: they need root (CI runs as root) and are skipped with the
reason elsewhere."""
import hashlib
import json
import os
import re
import select
import shutil
import signal
import subprocess
import tempfile
import time

import pytest

QDMR = os.environ["QDMR"]
SOURCE = os.environ["QDMR_SOURCE_DIR"]
PLANE = os.path.join(SOURCE, "scenes", "plane.json")
TEMPORARY = re.compile(r"^\..*\.tmp\d+-\d+|^\.report-")  # file/atomic_file.hpp's and the report's temporaries


def env(**extra):
    e = dict(os.environ)
    e.update(extra)
    return e


def run(args, timeout=120, **kw):
    return subprocess.run([QDMR, *args], capture_output=True, text=True, timeout=timeout, **kw)


def temporaries(folder):
    found = []
    for root, dirs, files in os.walk(folder):
        found += [os.path.join(root, n) for n in dirs + files if TEMPORARY.match(n)]
    return found


def tree(folder):
    """Every file under folder with its bytes' hash."""
    out = {}
    for root, _, files in os.walk(folder):
        for n in files:
            path = os.path.join(root, n)
            with open(path, "rb") as f:
                out[os.path.relpath(path, folder)] = hashlib.sha1(f.read()).hexdigest()
    return out


def deterministic_rows(folder):
    rows = []
    with open(os.path.join(folder, "rows.jsonl")) as f:
        for line in f:
            row = json.loads(line)
            row.pop("timing")
            rows.append(row)
    return sorted(rows, key=lambda r: r["index"])


def kill_after(args, seconds, sig=signal.SIGKILL, **kw):
    p = subprocess.Popen([QDMR, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, **kw)
    time.sleep(seconds)
    p.send_signal(sig)
    _, err = p.communicate(timeout=60)
    return p.returncode, err


def start_study(spec, out, file, limit=120):
    """A study into `out`, returned once `file` appeared there; a failure if the study ends without it, or if it
    has not appeared after `limit` seconds (a hang here would only show as the whole test's CTest timeout)."""
    p = subprocess.Popen([QDMR, "study", spec, "-o", out], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + limit
    path = os.path.join(out, file)
    while not os.path.exists(path):
        if p.poll() is not None and not os.path.exists(path):
            pytest.fail(f"the study ended (exit {p.returncode}) before {file} appeared: {p.communicate()[1]}")
        if time.monotonic() > end:
            p.kill()
            pytest.fail(f"{file} did not appear within {limit} s: {p.communicate()[1]}")
        time.sleep(0.002)
    return p


def moments(seconds):
    """Spread-out moments to kill a run that takes `seconds`: its first milliseconds, then through its length."""
    return [0.0, 0.003, 0.02] + [seconds * f for f in (0.15, 0.35, 0.55, 0.75, 0.95)]


@pytest.fixture(scope="module")
def work():
    folder = tempfile.mkdtemp(prefix="qdmr-faults-")
    os.environ["QDMR_CACHE_DIR"] = os.path.join(folder, "cache")  # no test touches the user's cache
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="module")
def study(work):
    """A small study (6 configurations at 48x27) and its uninterrupted run: (spec, rows, seconds)."""
    spec = os.path.join(work, "study.json")
    with open(spec, "w") as f:
        json.dump({"scene": PLANE, "width": 48, "height": 27, "frames": 3, "warmup": 0, "keep": ["image"],
                   "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["normal", "pom", "qdm"]},
                            {"name": "elevation", "camera": "elevation", "values": [60, 20]}],
                   "baseline": {"technique": "qdm"}}, f)
    start = time.monotonic()
    r = run(["study", spec, "-o", os.path.join(work, "study-full")])
    assert r.returncode == 0, r.stderr
    return spec, deterministic_rows(os.path.join(work, "study-full")), time.monotonic() - start


# --- SIGKILL at any moment, then the same command ---------------------------------------------------------------

def test_study_killed_at_any_moment_resumes_to_the_rows_of_an_uninterrupted_run(work, study):
    spec, reference, seconds = study
    for i, moment in enumerate(moments(seconds)):
        out = os.path.join(work, f"study-cut-{i}")
        kill_after(["study", spec, "-o", out], moment)
        r = run(["study", spec, "-o", out, "--resume"])
        assert r.returncode == 0, f"killed after {moment:.3f} s: {r.stderr}"
        assert deterministic_rows(out) == reference, f"killed after {moment:.3f} s"
        with open(os.path.join(out, "results.json")) as f:
            assert len(json.load(f)["rows"]) == 6
        assert sorted(os.listdir(os.path.join(out, "images"))) == [f"{k}.png" for k in sorted(range(6), key=str)]
        assert temporaries(out) == [], f"killed after {moment:.3f} s"


def test_study_merge_killed_at_any_moment_ends_as_an_uninterrupted_merge(work, study):
    spec, reference, _ = study
    shards = [os.path.join(work, f"shard-{i}") for i in (1, 2)]
    for i, folder in enumerate(shards, 1):
        assert run(["study", spec, "-o", folder, "--shard", f"{i}/2"]).returncode == 0
    merge = lambda out: ["study", "merge", *shards, "-o", out]
    start = time.monotonic()
    assert run(merge(os.path.join(work, "merged-full"))).returncode == 0
    seconds = time.monotonic() - start
    without_lock = lambda folder: {k: v for k, v in tree(folder).items() if k != ".qdmr-lock"}  # it holds a PID
    full = without_lock(os.path.join(work, "merged-full"))
    for i, moment in enumerate(moments(seconds)):
        out = os.path.join(work, f"merged-cut-{i}")
        kill_after(merge(out), moment)
        r = run(merge(out))
        assert r.returncode == 0, f"killed after {moment:.3f} s: {r.stderr}"
        assert without_lock(out) == full, f"killed after {moment:.3f} s"
        assert deterministic_rows(out) == reference
        assert temporaries(out) == []


def check_manifest(folder):
    os.makedirs(folder, exist_ok=True)
    bits = int(re.search(r"bits version (\d+)", run(["--version"]).stdout).group(1))
    manifest = {"bits_version": bits, "defaults": {"width": 64, "height": 36},
                "checks": [{"name": "plane", "scene": PLANE, "hash": {"color": "sha1:" + "0" * 40}},
                           {"name": "steep", "scene": PLANE, "set": {"/camera/fov_deg": 30}, "outputs": ["color", "depth"],
                            "hash": {"color": "sha1:" + "0" * 40, "depth": "sha1:" + "0" * 40}},
                           {"name": "tol", "scene": PLANE, "mode": "tolerance", "tolerance": {"max_abs": 0.01}}]}
    with open(os.path.join(folder, "checks.json"), "w") as f:
        json.dump(manifest, f, indent=2)
    return os.path.join(folder, "checks.json")


def test_check_update_killed_at_any_moment_ends_as_an_uninterrupted_run(work):
    full = check_manifest(os.path.join(work, "check-full"))
    start = time.monotonic()
    r = run(["check", full, "--update"])
    seconds = time.monotonic() - start
    assert r.returncode == 0, r.stderr
    reference = tree(os.path.dirname(full))
    for i, moment in enumerate(moments(seconds)):
        manifest = check_manifest(os.path.join(work, f"check-cut-{i}"))
        kill_after(["check", manifest, "--update"], moment, cwd=work)
        r = run(["check", manifest, "--update"], cwd=work)
        assert r.returncode == 0, f"killed after {moment:.3f} s: {r.stderr}"
        assert tree(os.path.dirname(manifest)) == reference, f"killed after {moment:.3f} s"
        assert run(["check", manifest], cwd=work).returncode == 0


def test_report_killed_at_any_moment_ends_as_an_uninterrupted_run(work, study):
    results = os.path.join(work, "study-full")
    start = time.monotonic()
    r = run(["report", results, "-o", os.path.join(work, "report-full")])
    seconds = time.monotonic() - start
    assert r.returncode == 0, r.stderr
    reference = sorted(tree(os.path.join(work, "report-full")))
    for i, moment in enumerate(moments(seconds)[::2]):  # a report takes seconds: every other moment
        out = os.path.join(work, f"report-cut-{i}")
        kill_after(["report", results, "-o", out], moment)
        r = run(["report", results, "-o", out])
        assert r.returncode == 0, f"killed after {moment:.3f} s: {r.stderr}"
        assert sorted(tree(out)) == reference
        assert temporaries(work) == [], f"killed after {moment:.3f} s"


def height_map(path, size, terraces=0):
    """A size x size 16-bit PGM of smooth bumps (deterministic), cut into flat terraces if asked (their flat tops
    make a cone bake walk far: 1024² with 6 terraces takes about 2.4 s, the smooth map a tenth of that)."""
    import numpy as np
    y, x = np.mgrid[0:size, 0:size].astype(np.float64)
    v = 0.5 + 0.25 * np.sin(x * 0.11) * np.cos(y * 0.07) + 0.2 * np.sin((x + 2 * y) * 0.031)
    if terraces:
        v = np.floor(v * terraces) / terraces
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n65535\n" % (size, size) + (v * 65535).astype(">u2").tobytes())
    return path


def test_bake_and_render_killed_at_any_moment_end_as_an_uninterrupted_run(work):
    height = height_map(os.path.join(work, "h384.pgm"), 384)
    for name, args in [("cone.exr", ["bake", "cone", height, "--kind", "relaxed", "-o"]),
                       ("plane.png", ["render", PLANE, "--width", "640", "--height", "360", "--aov", "depth=" +
                                      os.path.join(work, "depth.exr"), "-o"])]:
        full = os.path.join(work, "full-" + name)
        start = time.monotonic()
        r = run(args + [full])
        seconds = time.monotonic() - start
        assert r.returncode == 0, r.stderr
        with open(full, "rb") as f:
            reference = f.read()
        out = os.path.join(work, name)
        for moment in moments(seconds):
            kill_after(args + [out], moment)
            r = run(args + [out])
            assert r.returncode == 0, f"killed after {moment:.3f} s: {r.stderr}"
            with open(out, "rb") as f:
                assert f.read() == reference, f"killed after {moment:.3f} s"
            assert temporaries(work) == [], f"killed after {moment:.3f} s"


# --- Ctrl-C ----------------------------------------------------------------------------------------------------

def test_ctrl_c_stops_a_study_at_the_next_configuration_and_a_bake_at_once(work, study):
    spec, reference, _ = study
    out = os.path.join(work, "study-int")
    p = start_study(spec, out, "rows.jsonl")
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    if p.returncode == 0:
        pytest.skip("the study finished before the signal")
    assert p.returncode == 130, err
    assert "interrupted; the results so far are valid, continue with --resume" in err
    assert run(["study", spec, "-o", out, "--resume"]).returncode == 0
    assert deterministic_rows(out) == reference

    # A relaxed bake of 2048² takes seconds: SIGTERM stops it within a fraction of one, writing nothing.
    height = height_map(os.path.join(work, "h2048.pgm"), 2048)
    out = os.path.join(work, "stopped.exr")
    p = subprocess.Popen([QDMR, "bake", "cone", height, "--kind", "relaxed", "-o", out], stderr=subprocess.PIPE, text=True)
    time.sleep(0.3)
    stopped = time.monotonic()
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    if p.returncode == 0:
        pytest.skip("the bake finished before the signal")
    assert p.returncode == 130, err
    assert time.monotonic() - stopped < 1.0  # rows are baked in blocks of two: milliseconds each
    assert err.strip().splitlines()[-1].startswith("qdmr: interrupted")
    assert not os.path.exists(out) and temporaries(work) == []

    # A render whose preparation bakes a 2048² cone map (no cache): SIGINT stops it before anything is written.
    out = os.path.join(work, "stopped.png")
    p = subprocess.Popen([QDMR, "render", cone_scene(work, 7, 2048), "--width", "96", "--height", "54", "-o", out],
                         stderr=subprocess.PIPE, text=True, env=env(QDMR_CACHE_DIR=os.path.join(work, "no-cache")))
    time.sleep(0.4)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    if p.returncode == 0:
        pytest.skip("the render finished before the signal")
    assert p.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("qdmr: interrupted")
    assert not os.path.exists(out) and temporaries(work) == []


def test_a_long_bake_shows_its_progress_on_a_terminal_only(work):
    """A bake over a second shows its line on a terminal (stderr a pseudo-terminal here), and nothing in a log."""
    import pty
    height = height_map(os.path.join(work, "terraces.pgm"), 1024, terraces=6)
    args = [QDMR, "bake", "cone", height, "--kind", "relaxed", "-o", os.path.join(work, "progress.exr")]
    master, slave = pty.openpty()
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    shown = b""
    end = time.monotonic() + 120
    while True:
        if not select.select([master], [], [], max(0.0, end - time.monotonic()))[0]:
            p.kill()
            pytest.fail(f"the bake did not end within 120 s; it showed {shown!r}")
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the terminal's other end closed: the bake ended
            break
        if not chunk:
            break
        shown += chunk
    os.close(master)
    assert p.wait(timeout=120) == 0
    done = re.search(rb"relaxed cone map 1024x1024: done in ([0-9.]+) s", shown)
    if not done:
        pytest.skip(f"no progress line: the bake took less than a second ({shown!r})")
    assert re.search(rb"\rrelaxed cone map 1024x1024 +[0-9]+% \([0-9]+ s\)", shown), shown
    logged = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert logged.returncode == 0 and logged.stderr == "", logged.stderr


# --- two processes, one folder or file -------------------------------------------------------------------------

def test_a_second_study_on_a_folder_in_use_is_refused(work, study):
    spec, reference, _ = study
    out = os.path.join(work, "study-twice")
    first = start_study(spec, out, "study.json")
    second = run(["study", spec, "-o", out, "--resume"])
    _, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    if second.returncode == 0:
        pytest.skip("the first study finished before the second started")
    assert second.returncode == 2
    assert f"{out}: is in use by another qdmr study (process {first.pid})" in second.stderr
    assert deterministic_rows(out) == reference


def test_concurrent_renders_to_one_path(work):
    out = os.path.join(work, "race.png")
    args = ["render", PLANE, "--width", "320", "--height", "180", "-o", out]
    r = run(args[:-1] + [os.path.join(work, "race-reference.png")])
    assert r.returncode == 0, r.stderr
    racers = [subprocess.Popen([QDMR, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE) for _ in range(3)]
    assert [p.wait(timeout=120) for p in racers] == [0, 0, 0]
    with open(out, "rb") as a, open(os.path.join(work, "race-reference.png"), "rb") as b:
        assert a.read() == b.read()
    assert temporaries(work) == []


# --- the bake cache --------------------------------------------------------------------------------------------

def cone_scene(work, cells, size=256):
    """The plane with relaxed cone stepping over size² procedural bricks of `cells` rows (256²: a 256 KiB map)."""
    scene = json.load(open(PLANE))
    layer = scene["materials"]["bricks"]["layers"][0]
    layer["height"].update(size=size, cells=cells)
    layer["albedo"]["size"] = size
    scene["materials"]["bricks"]["technique"] = {"name": "rcsm", "depth_scale": 0.05}
    path = os.path.join(work, f"cone-{cells}-{size}.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    return path


def test_the_bake_cache_stays_within_its_limit_and_rebuilds_a_damaged_entry(work):
    cache = os.path.join(work, "bounded-cache")
    limited = env(QDMR_CACHE_DIR=cache, QDMR_CACHE_MAX_MIB="1")
    entries, images = [], {}
    for cells in (3, 4, 5, 6):  # four cone maps of 256 KiB and a 40-byte header: three fit in 1 MiB
        out = os.path.join(work, f"cone-{cells}.png")
        before = set(os.listdir(cache)) if os.path.isdir(cache) else set()
        stats = os.path.join(work, f"cone-{cells}.stats.json")
        r = run(["render", cone_scene(work, cells), "--width", "96", "--height", "54", "-o", out, "--stats", stats], env=limited)
        assert r.returncode == 0, r.stderr
        images[cells] = open(out, "rb").read()
        steps = json.load(open(stats))["prepare"]["steps"]  # a line per preparation step, the bake among them
        assert any(s["what"] == "cone_map" and s["ms"] > 0 for s in steps), steps
        added = sorted(set(os.listdir(cache)) - before)
        assert len(added) == 1 and added[0].startswith("cone-relaxed-"), added
        entries.append(added[0])
        assert sum(os.path.getsize(os.path.join(cache, e)) for e in os.listdir(cache)) <= 1 << 20
    assert len(os.listdir(cache)) == 3
    assert entries[0] not in os.listdir(cache)  # the least recently used went
    shown = run(["cache"], env=limited)
    assert shown.returncode == 0 and cache in shown.stdout and "3 entries" in shown.stdout, shown.stdout
    assert "limit: 1.0 MiB" in shown.stdout

    # A damaged entry (one bit of the payload flipped) is baked again, never used: the same image, the same entry.
    entry = os.path.join(cache, entries[-1])
    good = open(entry, "rb").read()
    with open(entry, "r+b") as f:
        f.seek(len(good) // 2)
        f.write(bytes([good[len(good) // 2] ^ 1]))
    out = os.path.join(work, "cone-again.png")
    assert run(["render", cone_scene(work, 6), "--width", "96", "--height", "54", "-o", out], env=limited).returncode == 0
    assert open(out, "rb").read() == images[6]
    assert open(entry, "rb").read() == good

    cleared = run(["cache", "clear"], env=limited)
    assert cleared.returncode == 0 and "removed 3 entries" in cleared.stdout, cleared.stdout
    assert os.listdir(cache) == []
    bad = run(["cache"], env=env(QDMR_CACHE_DIR=cache, QDMR_CACHE_MAX_MIB="lots"))
    assert bad.returncode == 2 and "QDMR_CACHE_MAX_MIB: must be a whole number of MiB" in bad.stderr, bad.stderr


# --- full and read-only file systems ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def mounts(work):
    """A 4 MiB tmpfs filled to the last byte, and a read-only tmpfs; skipped where they cannot be mounted."""
    full, readonly = os.path.join(work, "full"), os.path.join(work, "readonly")
    os.makedirs(full)
    os.makedirs(readonly)
    mounted = []
    try:
        for folder in (full, readonly):
            r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", folder], capture_output=True, text=True,
                               timeout=60)
            if r.returncode != 0:
                pytest.skip(f"cannot mount a tmpfs ({r.stderr.strip() or 'mount failed'}): needs root")
            mounted.append(folder)
        for folder in (full, readonly):  # what the writers must leave alone: an earlier output in each
            shutil.copy(PLANE, os.path.join(folder, "earlier.png"))
            os.makedirs(os.path.join(folder, "study"))
        filler = os.open(os.path.join(full, "filler"), os.O_WRONLY | os.O_CREAT)
        for size in (65536, 4096, 1):  # to the last byte
            try:
                while True:
                    os.write(filler, b"\0" * size)
            except OSError:
                pass
        os.close(filler)
        r = subprocess.run(["mount", "-o", "remount,ro", readonly], capture_output=True, text=True, timeout=60)
        if r.returncode != 0:
            pytest.skip(f"cannot remount read-only: {r.stderr.strip()}")
        yield {"full": (full, "No space left on device"), "readonly": (readonly, "Read-only file system")}
    finally:
        for folder in mounted:
            subprocess.run(["umount", folder], timeout=60)


def writers(work, folder):
    """Every writer, each aimed at `folder`: (name, arguments, the path its message names)."""
    height = height_map(os.path.join(work, "h64.pgm"), 64) if not os.path.exists(os.path.join(work, "h64.pgm")) else os.path.join(work, "h64.pgm")
    small = ["--width", "64", "--height", "36"]
    manifest = check_manifest(os.path.join(work, "check-for-" + os.path.basename(folder)))
    study_spec = os.path.join(work, "study.json")
    f = lambda name: os.path.join(folder, name)
    return [
        ("png", ["render", PLANE, *small, "-o", f("a.png")], f("a.png")),
        ("exr", ["render", PLANE, *small, "-o", f("a.exr")], f("a.exr")),
        ("tif", ["render", PLANE, *small, "-o", f("a.tif")], f("a.tif")),
        ("aov", ["render", PLANE, *small, "-o", os.path.join(work, "ok.png"), "--aov", "depth=" + f("d.exr")], f("d.exr")),
        ("stats", ["render", PLANE, *small, "-o", os.path.join(work, "ok.png"), "--stats", f("s.json")], f("s.json")),
        ("overwrite", ["render", PLANE, *small, "-o", f("earlier.png")], f("earlier.png")),
        ("bench json", ["bench", PLANE, *small, "--frames", "1", "--json", f("b.json")], f("b.json")),
        ("bake", ["bake", "cone", height, "-o", f("c.exr")], f("c.exr")),
        ("study new folder", ["study", study_spec, "-o", f("new-study")], f("new-study")),
        ("study folder", ["study", study_spec, "-o", f("study")], f("study")),
        ("merge", ["study", "merge", os.path.join(work, "study-full"), "-o", f("merged")], f("merged")),
        ("report", ["report", os.path.join(work, "study-full"), "-o", f("report")], f("")),
        ("junit", ["check", manifest, "--junit", f("j.xml")], f("j.xml")),
        ("check json", ["check", manifest, "--json", f("c.json")], f("c.json")),
        ("check report", ["check", manifest, "--report", f("check-report")], f("check-report")),
        ("heatmap", ["diff", os.path.join(work, "race-reference.png"), os.path.join(work, "race-reference.png"),
                     "--heatmap", f("h.png")], f("h.png")),
    ]


@pytest.mark.parametrize("kind", ["full", "readonly"])
def test_every_writer_on_a_full_or_read_only_file_system(work, study, mounts, kind):
    folder, reason = mounts[kind]
    if not os.path.exists(os.path.join(work, "race-reference.png")):
        assert run(["render", PLANE, "--width", "320", "--height", "180", "-o", os.path.join(work, "race-reference.png")]).returncode == 0
    before = tree(folder)
    for name, args, path in writers(work, folder):
        r = run(args, cwd=work)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2, f"{name}: exit {r.returncode}: {r.stderr}"
        assert lines, name
        assert lines[-1].startswith("qdmr: error: ") or lines[-1].startswith("qdmr report: "), f"{name}: {r.stderr}"
        assert path in lines[-1] and reason in lines[-1], f"{name}: {lines[-1]}"
        assert "filesystem error" not in r.stderr and "Traceback" not in r.stderr, f"{name}: {r.stderr}"
        assert tree(folder) == before, f"{name}: the file system changed"


@pytest.mark.parametrize("kind", ["full", "readonly"])
def test_a_bake_cache_that_cannot_be_written_is_reported_and_the_render_succeeds(work, mounts, kind):
    """The cache is an optimisation: the render succeeds (exit 0, its image written), and one warning line names
    the entry and the OS reason; nothing on the mount changes."""
    folder, reason = mounts[kind]
    before = tree(folder)
    out = os.path.join(work, f"cached-on-{kind}.png")
    r = run(["render", cone_scene(work, 6), "--width", "64", "--height", "36", "-o", out], env=env(QDMR_CACHE_DIR=folder))
    assert r.returncode == 0, r.stderr
    assert os.path.isfile(out)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("qdmr: warning: " + os.path.join(folder, "cone-relaxed-")), lines[0]
    assert ".bin: cannot write bake cache: " in lines[0] and reason in lines[0], lines[0]
    assert lines[0].endswith(" (the map is baked again next time)"), lines[0]
    assert tree(folder) == before and not temporaries(folder)
