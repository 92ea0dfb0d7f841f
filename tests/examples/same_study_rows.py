#!/usr/bin/env python3
"""Exit 0 when two results.json files hold the same rows in every deterministic column (index, axis values,
deterministic metrics), e.g. a merged distributed run and an unsharded one; else one line naming the first
difference and exit 1.
  same_study_rows.py A/results.json B/results.json
"""
import json
import sys


def main(a_path, b_path):
    with open(a_path) as f:
        a = json.load(f)
    with open(b_path) as f:
        b = json.load(f)
    if len(a["rows"]) != len(b["rows"]) or len(b["rows"]) != b["configurations"]:
        print(f"{a_path}: {len(a['rows'])} rows, {b_path}: {len(b['rows'])} of {b['configurations']}", file=sys.stderr)
        return 1
    for x, y in zip(a["rows"], b["rows"]):
        for key in ("index", "config", "deterministic"):
            if x[key] != y[key]:
                print(f"row {x['index']}: {key} differs: {x[key]} vs {y[key]}", file=sys.stderr)
                return 1
    print(f"{len(a['rows'])} rows equal in every deterministic column")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
