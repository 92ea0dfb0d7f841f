"""Golden-image checks in process: `qdmr check MANIFEST` (docs/checks.md)."""
from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

from . import _qdmr

__all__ = ["run"]


def run(manifest: Union[str, os.PathLike], *, update: bool = False, jobs: int = 1, threads: Optional[int] = None,
        diff_dir: Union[str, os.PathLike] = "qdmr-check-failures") -> List[Dict[str, Any]]:
    """Runs every check of a manifest, as `qdmr check` does, and returns one dict per check in manifest order:
    name, status ("PASS", "FAIL", "SKIP", "ERROR", "UPDATED"), passed, lines (failed metrics or the reason),
    hashes (output -> canonical hash), diff_folder (written for a failure, else None), prepare_ms, draw_ms,
    seconds. update rewrites the goldens of failing checks (as --update). Raises SceneError for a bad manifest,
    InputError when it cannot be read."""
    return _qdmr.run_checks(manifest, update=update, jobs=jobs, threads=threads, diff_dir=diff_dir)
