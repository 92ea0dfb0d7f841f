# Shared fixtures of the Python module's tests (tests/CMakeLists.txt runs them with Debian's python3 -m pytest,
# PYTHONPATH=build/<preset>/python, QDMR_CLI = the qdmr command, QDMR_SOURCE_DIR = the repository).
import os
import subprocess

import pytest

SOURCE_DIR = os.environ.get("QDMR_SOURCE_DIR", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
PLANE = os.path.join(SOURCE_DIR, "scenes", "plane.json")
# The canonical plane displaced (QDM, the exact reference traced for error_texels), small enough for a test.
SMALL = {"/output/width": 96, "/output/height": 54}


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("QDMR_CLI")
    if not path:
        pytest.skip("QDMR_CLI is not set (run the tests through CTest)")
    return path


def run_cli(cli, *args, cwd=None):
    # Not the ASan runtime preloaded for a sanitized module (tests/CMakeLists.txt): a sanitized qdmr has its own.
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    done = subprocess.run([cli, *args], capture_output=True, text=True, cwd=cwd, env=env)
    assert done.returncode == 0, done.stderr
    return done.stdout
