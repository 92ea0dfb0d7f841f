"""scripts/check-include-cycles on small made-up trees: it passes a tree that matches its diagram and fails, naming
the file or the diagram line, on each kind of mismatch. (layout.include_cycles runs it on the real tree.)"""
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "check-include-cycles"


def make_tree(root, files, diagram):
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    (root / "docs").mkdir(exist_ok=True)
    (root / "docs" / "architecture.md").write_text("# A\n\n```folders\n" + diagram + "```\n")


def check(root):
    run = subprocess.run([sys.executable, str(SCRIPT), str(root)], capture_output=True, text=True)
    return run.returncode, run.stdout + run.stderr


GOOD_FILES = {
    "src/core/a.hpp": "#pragma once\n#include <vector>\n",
    "src/scene/b.cpp": '#include "core/a.hpp"\n#include "scene/b.hpp"\n',
    "include/qdmr/scene/b.hpp": '#include "qdmr/core/x.hpp"\n',
    "src/draw/c.cpp": '#include "qdmr/scene/b.hpp"\n#include "xsimd/xsimd.hpp"\n',
}
GOOD_DIAGRAM = "core ->   # comment\nscene -> core\ndraw -> scene\n"


def test_a_tree_that_matches_its_diagram_passes(tmp_path):
    make_tree(tmp_path, GOOD_FILES, GOOD_DIAGRAM)
    code, out = check(tmp_path)
    assert code == 0, out
    assert "matches architecture.md" in out


def test_an_include_the_diagram_does_not_allow_fails(tmp_path):
    files = dict(GOOD_FILES, **{"src/draw/d.cpp": '#include "core/a.hpp"\n'})
    make_tree(tmp_path, files, GOOD_DIAGRAM)
    code, out = check(tmp_path)
    assert code == 1
    assert "src/draw/d.cpp:1: draw -> core: the diagram does not allow it" in out


def test_a_stale_edge_fails(tmp_path):
    make_tree(tmp_path, GOOD_FILES, "core ->\nscene -> core\ndraw -> core scene\n")
    code, out = check(tmp_path)
    assert code == 1
    assert "draw -> core is stale" in out


def test_a_folder_missing_from_the_diagram_or_listed_below_its_user_fails(tmp_path):
    make_tree(tmp_path, GOOD_FILES, "core ->\ndraw -> scene\nscene -> core\n")
    code, out = check(tmp_path)
    assert code == 1
    assert "draw -> scene: scene is listed below draw" in out
    make_tree(tmp_path, GOOD_FILES, "core ->\nscene -> core\n")
    code, out = check(tmp_path)
    assert code == 1
    assert "src/draw/ is not in the diagram" in out


def test_a_cycle_fails_even_without_a_diagram(tmp_path):
    files = dict(GOOD_FILES, **{"src/core/e.cpp": '#include "draw/c.hpp"\n'})
    make_tree(tmp_path, files, GOOD_DIAGRAM)
    run = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path), "--no-diagram"], capture_output=True, text=True)
    assert run.returncode == 1
    assert "include cycle between folders: core, draw, scene" in run.stdout


def test_a_malformed_diagram_line_is_refused(tmp_path):
    make_tree(tmp_path, GOOD_FILES, GOOD_DIAGRAM + "draw => core\n")
    code, out = check(tmp_path)
    assert code == 1
    assert "not `folder -> folders...`" in out


def test_a_wall_fails_on_a_chain_of_includes_through_another_folder(tmp_path):
    # e.cpp reaches scene only through mid's header: the folder edges allow it, the wall does not.
    files = dict(GOOD_FILES, **{"src/mid/x.hpp": '#include "qdmr/scene/b.hpp"\n',
                                "src/draw/e.cpp": '\n#include "mid/x.hpp"\n'})
    diagram = "core ->\nscene -> core\nmid -> scene\ndraw -> mid scene\ndraw !> scene\n"
    make_tree(tmp_path, files, diagram)
    code, out = check(tmp_path)
    assert code == 1
    assert "src/draw/e.cpp:2 -> src/mid/x.hpp:1 -> include/qdmr/scene/b.hpp: draw reaches scene" in out
    # Without the chain, only the direct includes: c.cpp includes scene itself.
    files["src/mid/x.hpp"] = '#include "core/a.hpp"\n'
    make_tree(tmp_path, files, "core ->\nscene -> core\nmid -> core\ndraw -> mid scene\ndraw !> scene\n")
    code, out = check(tmp_path)
    assert code == 1
    assert "src/draw/c.cpp:1 -> include/qdmr/scene/b.hpp: draw reaches scene" in out
    assert "e.cpp" not in out


def test_a_wall_that_holds_passes(tmp_path):
    files = dict(GOOD_FILES, **{"src/core/x.hpp": "#pragma once\n", "src/draw/e.cpp": '#include "core/x.hpp"\n'})
    make_tree(tmp_path, files, "core ->\nscene -> core\ndraw -> core scene\ncore !> scene draw\n")
    code, out = check(tmp_path)
    assert code == 0, out
    assert "its walls (core !> scene draw)" in out
