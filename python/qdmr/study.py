"""Studies from Python: `qdmr study` in process, or spread over a Dask cluster (docs/studies.md, docs/python.md)."""
from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Tuple, Union

from . import _qdmr

__all__ = ["run", "load", "to_frame"]

Spec = Union[str, os.PathLike, Dict[str, Any]]


def run(spec: Spec, out: Union[str, os.PathLike], *, resume: bool = True, threads: Optional[int] = None,
        jobs: int = 1, force: bool = False, shard: Optional[Tuple[int, int]] = None, client: Any = None,
        base_dir: Optional[Union[str, os.PathLike]] = None) -> Dict[str, Any]:
    """Runs a study spec (a file, or a dict whose relative paths resolve against base_dir, default the current
    folder) into the folder `out`, with the same rows.jsonl, results.json, results.csv and pareto.csv as
    `qdmr study SPEC -o OUT`. resume continues an interrupted run of the same spec (an `out` holding another
    spec's results is refused). threads: per configuration (None: every core / jobs); jobs: configurations at
    once; shard=(I, N): the I-th of N shards only, balanced by estimated cost (`qdmr study --shard I/N`, merged
    by `qdmr study merge`).

    client: a dask.distributed Client. The configurations are then drawn a few per task on its workers: every
    worker process keeps one set of persistent renderers across its tasks and draws whole groups of configurations
    that share the exact reference and the heights it is traced on, taking from the others' runs when its own is
    done and the times measured so far say that pays, and from workers that have left; the rows come back to this process, which writes OUT as a
    one-process run does (the same files; resume works across both). The
    folder must be on a file system the workers share with the caller (kept images are written there). threads
    then defaults to the worker's thread count.

    Returns {"total", "rendered", "resumed", "asset_builds", "seconds"} (with a client also
    "processes": the worker processes that drew configurations). Ctrl-C stops after the configurations being drawn, with the
    rows so far kept (resume continues), and raises KeyboardInterrupt. Raises SceneError for a bad spec before
    anything renders."""
    if client is not None:
        if shard is not None:
            raise ValueError("study.run(): shard and client: the client spreads the configurations itself")
        from . import _dask
        return _dask.run(spec, out, client, resume=resume, threads=threads, force=force, base_dir=base_dir)
    return _qdmr.run_study(spec, out, resume=resume, threads=threads, jobs=jobs, shard=shard, force=force,
                           base_dir=base_dir)


def load(folder: Union[str, os.PathLike], *, as_frame: bool = False) -> Any:
    """The rows of a results folder, in index order: a list of dicts ("index", "config", "deterministic",
    "timing"; docs/studies.md has the columns), or with as_frame a pandas DataFrame of them (to_frame)."""
    rows = sorted(_qdmr.study_rows(folder), key=lambda row: row["index"])
    return to_frame(rows) if as_frame else rows


def to_frame(rows: List[Dict[str, Any]]) -> Any:
    """Rows as a pandas DataFrame, one column per value: "index", "config.<axis>", "deterministic.<metric>",
    "timing.<metric>" (pandas.json_normalize). Needs pandas (Debian: python3-pandas)."""
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - pandas is a scripts/setup package
        raise ImportError("qdmr.study.to_frame needs pandas (apt-get install python3-pandas)") from e
    return pandas.json_normalize(rows).set_index("index", drop=False)
