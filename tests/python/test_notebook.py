# docs/notebooks/sampling_artifacts.ipynb runs from top to bottom (nbclient and ipykernel, Debian's python3 kernel
# with the build's qdmr on PYTHONPATH): a notebook that fails fails the build.
import os

import pytest

from conftest import SOURCE_DIR

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")


def test_the_notebook_runs(tmp_path):
    path = os.path.join(SOURCE_DIR, "docs", "notebooks", "sampling_artifacts.ipynb")
    notebook = nbformat.read(path, as_version=4)
    # Executed where it lives (its paths are relative to docs/notebooks); the executed copy is kept in tmp_path,
    # never written over the source.
    nbclient.NotebookClient(notebook, timeout=240, kernel_name="python3",
                            resources={"metadata": {"path": os.path.dirname(path)}}).execute()
    nbformat.write(notebook, str(tmp_path / "executed.ipynb"))
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    assert sum(1 for o in outputs if "image/png" in o.get("data", {})) == 2  # the error images and the front
    assert any("27 configurations" in o.get("text", "") for o in outputs)
