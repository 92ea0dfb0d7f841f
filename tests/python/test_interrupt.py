# Ctrl-C: SIGINT stops a draw at the next tile and a study at the next configuration, as KeyboardInterrupt, with no
# frame returned, the renderer still usable and the study's rows so far valid (resume finishes it). Each case runs
# in a python3 of its own, which sends itself SIGINT from a timer thread.
import json
import os
import subprocess
import sys
import textwrap

import qdmr
from conftest import PLANE


def run(script, tmp_path):
    env = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(os.path.abspath(qdmr.__file__)))}
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=240, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_draw_stops_at_the_next_tile(tmp_path):
    result = run(f"""
        import json, os, signal, threading, time
        import numpy, qdmr
        scene = qdmr.load_scene({PLANE!r}, {{"/output/width": 3840, "/output/height": 2160,
                                "/materials/bricks/technique/name": "qdm"}})
        renderer = qdmr.Renderer(threads=1)
        renderer.set_scene(scene)
        start = time.perf_counter()
        full = renderer.draw().color.copy()
        full_seconds = time.perf_counter() - start
        threading.Timer(0.1 * full_seconds, os.kill, (os.getpid(), signal.SIGINT)).start()
        start = time.perf_counter()
        try:
            renderer.draw()
            stopped = None
        except KeyboardInterrupt:
            stopped = time.perf_counter() - start
        again = renderer.draw().color  # the renderer draws on after an interrupted frame
        print(json.dumps({{"full": full_seconds, "stopped": stopped, "same": bool(numpy.array_equal(full, again))}}))
    """, tmp_path)
    assert result["stopped"] is not None, result
    # Interrupted at a tenth of the frame; stopped well before its end (a tile is 1/2040 of it).
    assert result["stopped"] < 0.6 * result["full"], result
    assert result["same"]


def test_a_study_stops_at_the_next_configuration_and_resumes(tmp_path):
    spec = {"scene": PLANE, "width": 64, "height": 36, "frames": 1, "warmup": 0,
            "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["pom", "qdm"]},
                     {"name": "elevation", "camera": "elevation", "values": [10, 20, 30, 40, 50, 60, 70, 80]}]}
    result = run(f"""
        import json, os, signal, threading, time
        import qdmr
        out = "s"
        def interrupt_after_the_first_row():
            while not (os.path.exists("s/rows.jsonl") and os.path.getsize("s/rows.jsonl") > 0):
                time.sleep(0.002)
            os.kill(os.getpid(), signal.SIGINT)
        threading.Thread(target=interrupt_after_the_first_row, daemon=True).start()
        try:
            qdmr.study.run({spec!r}, out, threads=1)
            kept = None
        except KeyboardInterrupt:
            kept = len(qdmr.study.load(out))
        finished = qdmr.study.run({spec!r}, out, threads=1)
        print(json.dumps({{"kept": kept, "finished": finished, "rows": len(qdmr.study.load(out))}}))
    """, tmp_path)
    assert result["kept"] is not None and 1 <= result["kept"] < 16, result
    assert result["finished"]["resumed"] == result["kept"]
    assert result["finished"]["rendered"] == 16 - result["kept"] and result["rows"] == 16
