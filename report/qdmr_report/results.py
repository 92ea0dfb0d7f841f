"""A study's results folder, read and checked before anything of the report is drawn.

The rows come from rows.jsonl (appended by `qdmr study` as each configuration finishes: the primary record) and
what they belong to from study.json; results.json and pareto.csv are derived from them and must agree.
"""
import csv
import json
import math
import os


class BadResults(Exception):
    """An input the report cannot be made from: the message names the file and what is wrong with it."""


DETERMINISTIC = "deterministic"
TIMING = "timing"


class Study:
    """The rows of a study and what they belong to."""

    def __init__(self, folder, header, rows, fronts, complete):
        self.folder = folder
        self.header = header            # study.json, plus results.json's "run" when there is one
        self.rows = rows                # by index: {"index", "config", "deterministic", "timing"}
        self.fronts = fronts            # front name ("all", "technique=qdm") -> set of row indices
        self.complete = complete        # every configuration has a row

    @property
    def axes(self):
        return list(self.header.get("axes", []))

    @property
    def group_axis(self):
        return self.header.get("group_by") or ""

    def axis_spec(self, name):
        for axis in self.header.get("spec", {}).get("axes", []):
            if axis.get("name") == name:
                return axis
        return {}

    def value(self, row, column):
        """A column of a row: an axis value, a deterministic or a timing column; None when absent."""
        if column in row["config"]:
            return row["config"][column]
        for group in (DETERMINISTIC, TIMING):
            if column in row.get(group, {}):
                return row[group][column]
        return None

    def columns(self, group):
        names = []
        for row in self.rows:
            for name in row.get(group, {}):
                if name not in names:
                    names.append(name)
        return names

    def number(self, row, column):
        v = self.value(row, column)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            return None
        return float(v)

    def group_of(self, row):
        if not self.group_axis:
            return "all"
        return format_value(row["config"].get(self.group_axis))

    def groups(self):
        seen = []
        for row in self.rows:
            g = self.group_of(row)
            if g not in seen:
                seen.append(g)
        return seen

    def label(self, row):
        return ", ".join(f"{a}={format_value(row['config'].get(a))}" for a in self.axes
                         if row["config"].get(a) is not None)

    def kept(self, index, suffix):
        """The path of a kept file of a configuration (suffix ".png", ".error_texels.exr", ...) or None."""
        path = os.path.join(self.folder, "images", f"{index}{suffix}")
        return path if os.path.isfile(path) else None


def format_value(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, dict)):
        return json.dumps(v, separators=(",", ":"))
    return str(v)


def _read_json(path, what):
    if not os.path.isfile(path):
        raise BadResults(f"{path}: missing: not the results folder of `qdmr study` ({what})")
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise BadResults(f"{path}: unreadable ({e})") from None


def _check_row(path, line_number, row, configurations):
    where = f"{path}: line {line_number}"
    if not isinstance(row, dict) or not isinstance(row.get("index"), int) or isinstance(row.get("index"), bool):
        raise BadResults(f"{where}: not a row of `qdmr study` (no integer \"index\")")
    if not 0 <= row["index"] < configurations:
        raise BadResults(f"{where}: configuration {row['index']} does not exist (the study has {configurations})")
    for key in ("config", DETERMINISTIC, TIMING):
        if not isinstance(row.get(key), dict):
            raise BadResults(f"{where}: row {row['index']} has no \"{key}\" object")
    for group in (DETERMINISTIC, TIMING):
        for name, v in row[group].items():
            if isinstance(v, float) and not math.isfinite(v):
                raise BadResults(f"{where}: row {row['index']}: {group}.{name} is {v}")


def _read_rows(path, configurations):
    rows = {}
    with open(path, "rb") as f:
        data = f.read()
    lines = data.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    elif lines:
        raise BadResults(f"{path}: line {len(lines)} is half-written (the study was killed while writing it): "
                         "finish the study with `qdmr study SPEC -o FOLDER --resume`")
    for n, line in enumerate(lines, 1):
        try:
            row = json.loads(line.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError):
            raise BadResults(f"{path}: line {n} is not a whole row (half-written or damaged): finish the study with "
                             "`qdmr study SPEC -o FOLDER --resume`") from None
        _check_row(path, n, row, configurations)
        if row["index"] in rows:
            raise BadResults(f"{path}: line {n}: configuration {row['index']} has two rows")
        rows[row["index"]] = row
    return [rows[i] for i in sorted(rows)]


def _read_fronts(path, known):
    fronts = {}
    if not os.path.isfile(path):
        raise BadResults(f"{path}: missing (`qdmr study` writes it with the rows)")
    with open(path, newline="", encoding="utf-8") as f:
        for n, record in enumerate(csv.DictReader(f), 2):
            try:
                index = int(record["index"])
            except (KeyError, TypeError, ValueError):
                raise BadResults(f"{path}: line {n}: no configuration index") from None
            if index not in known:
                raise BadResults(f"{path}: line {n}: configuration {index} has no row in rows.jsonl "
                                 "(the files are of different runs)")
            fronts.setdefault(record.get("front", "all"), set()).add(index)
    return fronts


def load_study(folder, partial=False):
    """Reads and checks a results folder; raises BadResults naming the file and the problem."""
    if not os.path.isdir(folder):
        raise BadResults(f"{folder}: not a folder (give the -o folder of `qdmr study`)")
    header = _read_json(os.path.join(folder, "study.json"), "study.json is written when a study starts")
    for key in ("spec_hash", "configurations", "shard", "axes"):
        if key not in header:
            raise BadResults(f"{os.path.join(folder, 'study.json')}: no \"{key}\": not written by `qdmr study`")
    configurations = header["configurations"]
    if not isinstance(configurations, int) or configurations < 0:
        raise BadResults(f"{os.path.join(folder, 'study.json')}: /configurations: expected a count")
    shard = header["shard"]
    if shard != [1, 1]:
        if not partial:
            raise BadResults(f"{os.path.join(folder, 'study.json')}: this folder is shard {shard[0]} of {shard[1]}: "
                             "merge the shards first (`qdmr study merge SHARD... -o FOLDER`), or report this shard "
                             "alone with --partial")
    results = _read_json(os.path.join(folder, "results.json"), "results.json is written as rows finish")
    if results.get("spec_hash") != header["spec_hash"]:
        raise BadResults(f"{os.path.join(folder, 'results.json')}: belongs to another spec "
                         f"({results.get('spec_hash')}, study.json says {header['spec_hash']})")
    rows_path = os.path.join(folder, "rows.jsonl")
    if not os.path.isfile(rows_path):
        raise BadResults(f"{rows_path}: missing: not the results folder of `qdmr study`")
    rows = _read_rows(rows_path, configurations)
    if not rows:
        raise BadResults(f"{rows_path}: empty: the study has not finished a single configuration")
    complete = len(rows) == configurations
    if not complete and not partial and shard == [1, 1]:
        raise BadResults(f"{rows_path}: {len(rows)} of {configurations} configurations: finish the study with "
                         "`qdmr study SPEC -o FOLDER --resume`, or report what is there with --partial")
    derived = results.get("rows", [])
    if len(derived) > len(rows):
        raise BadResults(f"{os.path.join(folder, 'results.json')}: {len(derived)} rows, rows.jsonl has {len(rows)} "
                         "(the files are of different runs)")
    if "run" in results:
        header = dict(header, run=results["run"])
    fronts = _read_fronts(os.path.join(folder, "pareto.csv"), {r["index"] for r in rows})
    return Study(folder, header, rows, fronts, complete)
