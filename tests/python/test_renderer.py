# The Renderer from Python: pixels equal to the command's EXR, arrays that outlive draws and renderers, the GIL
# released while drawing, plan and stats as the command prints them.
import gc
import json
import os
import platform
import shutil
import struct
import subprocess
import threading
import time

import numpy
import pytest

import qdmr
from conftest import PLANE, SMALL, run_cli

QDM = {"/materials/bricks/technique/name": "qdm", "/materials/bricks/technique/depth_scale": 0.1}


def bits(array):
    """The float32 values as their bit patterns: equality of these is equality bit for bit (NaN included)."""
    return numpy.ascontiguousarray(array, dtype=numpy.float32).view(numpy.uint32)


def test_pixels_equal_the_commands_exr_bit_for_bit(cli, tmp_path):
    color, depth, errors = tmp_path / "c.exr", tmp_path / "d.exr", tmp_path / "e.exr"
    sets = [a for p, v in QDM.items() for a in ("--set", f"{p}={v}")]
    run_cli(cli, "render", PLANE, "-o", str(color), "--width", "96", "--height", "54", "--threads", "2",
            "--aov", f"depth={depth}", "--aov", f"error_texels={errors}", *sets)
    scene = qdmr.load_scene(PLANE, {**SMALL, **QDM})
    renderer = qdmr.Renderer(threads=1, tile=16)  # another thread count and tile size: the same bits
    renderer.set_scene(scene, aovs=["depth", "error_texels"])
    frame = renderer.draw()
    assert frame.color.shape == (54, 96, 3) and frame.color.dtype == numpy.float32
    assert frame["depth"].shape == (54, 96)
    assert numpy.array_equal(bits(frame.color), bits(qdmr.read_image(color)))
    assert numpy.array_equal(bits(frame["depth"]), bits(qdmr.read_image(depth)))
    assert numpy.array_equal(bits(frame.aovs["error_texels"]), bits(qdmr.read_image(errors)))
    # qdmr's own writer: the same bytes as the command's file.
    qdmr.write_image(frame.color, tmp_path / "again.exr")
    assert (tmp_path / "again.exr").read_bytes() == color.read_bytes()
    qdmr.write_image(frame.color, tmp_path / "one.exr", threads=1)  # on the calling thread alone: the same bytes
    assert (tmp_path / "one.exr").read_bytes() == color.read_bytes()
    assert not [p for p in os.listdir(tmp_path) if ".tmp" in p]  # no temporary left behind


def test_plan_is_what_qdmr_plan_prints(cli):
    scene = qdmr.load_scene(PLANE, ["/output/width=96", "/output/height=54"])  # --set text works too
    renderer = qdmr.Renderer(threads=1)
    renderer.set_scene(scene, aovs=["depth"])
    printed = json.loads(run_cli(cli, "plan", PLANE, "--json", "--set", "/output/width=96", "--set",
                                 "/output/height=54", "--aov", "depth"))
    assert renderer.plan == printed
    assert qdmr.plan(scene, aovs=["depth"]) == printed


def test_stats_and_preparation_kept_across_scenes():
    renderer = qdmr.Renderer(threads=1)
    assert renderer.stats is None
    renderer.set_scene(qdmr.load_scene(PLANE, SMALL))
    first = renderer.draw().stats
    assert first["prepare"]["items_built"] > 0 and renderer.stats == first
    assert len(first["prepare"]["steps"]) == first["prepare"]["items_built"]
    renderer.set_scene(qdmr.load_scene(PLANE, {**SMALL, "/camera/fov_deg": 30}))  # a new camera builds nothing
    second = renderer.draw().stats
    assert second["prepare"] == {"items_built": 0, "items_reused": first["prepare"]["items_built"], "steps": []}


def test_arrays_outlive_the_next_draw_and_the_renderer():
    renderer = qdmr.Renderer(threads=2)
    renderer.set_scene(qdmr.load_scene(PLANE, SMALL), aovs=["depth"])
    frame = renderer.draw()
    color, depth = frame.color, frame["depth"]
    kept_color, kept_depth = color.copy(), depth.copy()
    del frame
    for fov in (30, 60, 40):  # other pixels drawn meanwhile, into recycled frames
        renderer.set_scene(qdmr.load_scene(PLANE, {**SMALL, "/camera/fov_deg": fov}), aovs=["depth"])
        other = renderer.draw().color
        assert not numpy.array_equal(other, kept_color)
    assert numpy.array_equal(bits(color), bits(kept_color))
    last = renderer.draw()
    del renderer
    gc.collect()
    assert numpy.array_equal(bits(color), bits(kept_color)) and numpy.array_equal(bits(depth), bits(kept_depth))
    assert last.color.sum() > 0 and last.width == 96
    assert not color.flags.writeable  # a view of the frame: read-only, so every array of it says the same


def test_read_image_owns_its_pixels(tmp_path):
    image = numpy.random.default_rng(7).random((5, 7, 4), dtype=numpy.float32)
    qdmr.write_image(image, tmp_path / "x.exr")
    back = qdmr.read_image(tmp_path / "x.exr")
    assert numpy.array_equal(bits(back), bits(image))  # row 0 at the top both ways
    qdmr.write_image(image[:, :, 0], tmp_path / "g.exr")
    gray = qdmr.read_image(tmp_path / "g.exr")
    assert gray.shape == (5, 7) and numpy.array_equal(gray, image[:, :, 0])
    # PNG: 8-bit sRGB codes of a colour image, read back normalised.
    qdmr.write_image(image[:, :, :3], tmp_path / "x.png")
    png = qdmr.read_image(tmp_path / "x.png")
    assert png.shape == (5, 7, 3) and numpy.array_equal(png * 255, numpy.round(png * 255))


def test_two_threads_render_at_once():
    # While one thread is inside draw() the other runs Python: the GIL is released. A held GIL would let the
    # other thread run only before the draw starts (one switch interval, 5 ms), not across the draw.
    scene = qdmr.load_scene(PLANE, {"/output/width": 1280, "/output/height": 720, **QDM})
    a, b = qdmr.Renderer(threads=1), qdmr.Renderer(threads=1)
    a.set_scene(scene)
    b.set_scene(scene)
    expected = bits(a.draw().color).copy()
    intervals, ticks, results = {}, [], {}
    stop = threading.Event()

    def draw(name, renderer):
        start = time.perf_counter()
        results[name] = bits(renderer.draw().color)
        intervals[name] = (start, time.perf_counter())

    def spin():
        while not stop.is_set():
            ticks.append(time.perf_counter())

    spinner = threading.Thread(target=spin)
    spinner.start()
    threads = [threading.Thread(target=draw, args=(n, r)) for n, r in (("a", a), ("b", b))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    stop.set()
    spinner.join()
    for name in "ab":
        start, end = intervals[name]
        inside = [t for t in ticks if start < t < end]
        # Ticks across at least half of each draw (draws take about 100 ms here).
        assert inside and inside[-1] - inside[0] > 0.5 * (end - start), (name, end - start)
        assert numpy.array_equal(results[name], expected)
    (a_start, a_end), (b_start, b_end) = intervals["a"], intervals["b"]
    assert max(a_start, b_start) < min(a_end, b_end)  # the two draws overlapped


def grid_glb(path, resolution):
    """A flat grid of resolution^2 quads as one .glb without TANGENT: its load derives MikkTSpace tangents."""
    n = resolution + 1
    u, v = numpy.meshgrid(numpy.arange(n, dtype=numpy.float32) / resolution,
                          numpy.arange(n, dtype=numpy.float32) / resolution)
    positions = numpy.stack([2 * u - 1, numpy.zeros_like(u), 1 - 2 * v], -1).astype("<f4").tobytes()
    normals = numpy.tile(numpy.array([0, 1, 0], "<f4"), n * n).tobytes()
    uvs = numpy.stack([u, 1 - v], -1).astype("<f4").tobytes()
    a = (numpy.arange(resolution)[:, None] * n + numpy.arange(resolution)[None, :]).ravel().astype(numpy.uint32)
    indices = numpy.stack([a, a + 1, a + n + 1, a, a + n + 1, a + n], -1).astype("<u4").tobytes()
    blobs, views, offset = [positions, normals, uvs, indices], [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
           "accessors": [
               {"bufferView": 0, "componentType": 5126, "count": n * n, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
               {"bufferView": 1, "componentType": 5126, "count": n * n, "type": "VEC3"},
               {"bufferView": 2, "componentType": 5126, "count": n * n, "type": "VEC2"},
               {"bufferView": 3, "componentType": 5125, "count": len(indices) // 4, "type": "SCALAR"}],
           "bufferViews": views, "buffers": [{"byteLength": offset}]}
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    body = b"".join(blobs)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 28 + len(js) + len(body)) + struct.pack("<II", len(js), 0x4E4F534A) + js +
                struct.pack("<II", len(body), 0x004E4942) + body)


def test_load_scene_threads_bound_the_load(tmp_path):
    # 320k triangles without tangents: MikkTSpace's parts take tens of ms, split over the cores unless bounded.
    path = str(tmp_path / "grid.glb")
    grid_glb(path, 400)
    small = {"/output/width": 32, "/output/height": 18}

    def load(threads):
        # The call releases the GIL: the calling thread's CPU time is the load's own thread's; the process's minus
        # it is every other thread's (time.thread_time / time.process_time: the scheduler's exact run times).
        thread0, process0 = time.thread_time(), time.process_time()
        scene = qdmr.load_scene(path, small, threads=threads)
        caller = time.thread_time() - thread0
        return scene, caller, (time.process_time() - process0) - caller

    one, caller, others = load(1)
    assert caller > 0.005, "too little work to tell"
    # As tests/write/write_threads_test.cpp allows: 1 ms (a wake-up or two of idle workers) plus 5 % of the caller's.
    assert others <= 0.001 + 0.05 * caller, f"others {others} s against the caller's {caller} s"
    if (os.cpu_count() or 1) >= 2:
        every, _, others_every = load(None)
        assert others_every > 0.001 + 0.05 * caller, "the measure sees the other threads when they work"
    else:
        every = qdmr.load_scene(path, small)
    renderer = qdmr.Renderer(threads=1)
    pixels = []
    for scene in (one, every):
        renderer.set_scene(scene)
        pixels.append(renderer.draw().color.copy())
    assert numpy.array_equal(pixels[0], pixels[1])  # the same scene for any count


@pytest.mark.parametrize("threads, error", [(0, ValueError), (100000, ValueError), ("many", TypeError), (1.5, TypeError)])
def test_load_scene_refuses_bad_threads(threads, error):
    with pytest.raises(error, match="threads"):
        qdmr.load_scene(PLANE, threads=threads)


@pytest.mark.skipif(platform.machine() != "x86_64" or shutil.which("readelf") is None,
                    reason="reads an x86-64 ELF module's relocations with binutils' readelf")
def test_the_module_reaches_the_librarys_code_as_the_command_does_and_needs_no_static_tls():
    """A draw in the module runs the command's instructions (docs/performance.md, "qdmr from Python"): calls to the
    library's own functions are bound at link time, not made through the PLT. And `import qdmr` never depends on
    glibc's small static TLS reserve for modules loaded late (an initial-exec thread-local would put the module's
    thread-locals there: "cannot allocate memory in static TLS block" after other such modules): the texture-cache
    recorder, asked per texel fetch, is reached through a process-wide count instead (texture/fetch_recorder.hpp)."""
    module = qdmr._qdmr.__file__
    relocations = subprocess.run(["readelf", "-rW", module], check=True, capture_output=True, text=True).stdout
    symbols = subprocess.run(["readelf", "--dyn-syms", "-W", module], check=True, capture_output=True,
                             text=True).stdout
    dynamic = subprocess.run(["readelf", "-dW", module], check=True, capture_output=True, text=True).stdout
    # Num: Value Size Type Bind Vis Ndx Name: a function the module defines has a section index, not UND.
    defined = {f[7].split("@")[0] for f in (line.split() for line in symbols.splitlines())
               if len(f) >= 8 and f[3] == "FUNC" and f[6] != "UND"}
    slots = {f[4].split("@")[0] for f in (line.split() for line in relocations.splitlines())
             if len(f) >= 5 and f[2] == "R_X86_64_JUMP_SLOT"}
    assert defined, "no function symbols read"
    assert not slots & defined, sorted(slots & defined)[:5]
    # Initial-exec thread-locals are TPOFF relocations. The sanitizer build's coverage instrumentation adds its own
    # (`__sancov_lowest_stack`, -fsanitize=fuzzer-no-link): allowed there, nothing of the project's.
    # Offset Info Type Sym.Value Sym.Name + Addend; a local thread-local has no name (its offset is the addend).
    initial_exec = [f[4] if len(f) > 5 else "(local) " + f[-1]
                    for f in (line.split() for line in relocations.splitlines())
                    if len(f) >= 3 and f[2].startswith("R_X86_64_TPOFF")]
    ours = [name for name in initial_exec if not name.startswith("__sancov_")]
    assert not ours, ours
    if not initial_exec:
        flags = [line for line in dynamic.splitlines() if "(FLAGS)" in line]
        assert not any("STATIC_TLS" in line for line in flags), flags
