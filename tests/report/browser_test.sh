#!/usr/bin/env bash
# The report as a reader sees it: a small real study (tests/report/small_study.json, every picture kept) through
# `qdmr study --report`, then the page opened in headless Chromium (browser_check.py): every image loads, no
# console error, no network request, the table sorts; the screenshot stays in WORK for a look. Then the command's
# bad inputs: exit 2 with one line naming the folder, and no report written.
#   browser_test.sh QDMR SOURCE_DIR WORK PYTHON
set -euo pipefail
qdmr="$1" source="$2" work="$3" python="$4"
rm -rf "$work"
mkdir -p "$work"
"$qdmr" study "$source/tests/report/small_study.json" -o "$work/results" --report --threads 2 >"$work/study.log" 2>&1 ||
  { cat "$work/study.log"; exit 1; }
test -f "$work/results-report/index.html"
"$python" "$source/tests/report/browser_check.py" "$work/results-report/index.html" --sort-check \
  --screenshot "$work/screenshot.png"

expect_refusal() {  # expected message fragment, then the command
  local fragment="$1"; shift
  set +e
  "$@" >"$work/out.txt" 2>"$work/err.txt"
  local code=$?
  set -e
  if [ "$code" -ne 2 ] || ! grep -qF -- "$fragment" "$work/err.txt" || [ "$(wc -l <"$work/err.txt")" -ne 1 ]; then
    echo "expected exit 2 and one line with '$fragment' from: $*; got exit $code:" >&2
    cat "$work/err.txt" >&2
    exit 1
  fi
}
expect_refusal "missing: not the results folder" "$qdmr" report "$work" -o "$work/other-report"
expect_refusal "is or holds the study's results" "$qdmr" report "$work/results" -o "$work/results"
expect_refusal "--worst: must be from 0 to 100" "$qdmr" report "$work/results" --worst 1000
test ! -e "$work/other-report"
echo "report: ok ($work/screenshot.png)"
