#!/bin/sh
# The CI examples (examples/ci/github-actions.yml, gitlab-ci.yml) run as they are written: qdmr installed with
# cmake --install into a prefix, then, from the checkout, examples/ci/run-checks.sh with that qdmr on PATH.
# A passing manifest must exit 0 and leave JUnit XML and the report; a manifest with a changed image must exit 1
# and leave them too, with the diff folder (the artefacts the examples keep "always").
#   ci_example_test.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -eu
src=$1 build=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
fail() { echo "ci_example_test: $*" >&2; exit 1; }

for example in github-actions.yml gitlab-ci.yml; do
  grep -q 'examples/ci/run-checks.sh' "$src/examples/ci/$example" || fail "$example does not call examples/ci/run-checks.sh"
  grep -q 'cmake --install build/release' "$src/examples/ci/$example" || fail "$example does not install with cmake --install"
  grep -q 'qdmr-check/junit.xml' "$src/examples/ci/$example" || fail "$example does not publish qdmr-check/junit.xml"
done

cmake --install "$build" --prefix "$work/prefix" >/dev/null
PATH="$work/prefix/bin:$PATH"
export PATH
command -v qdmr | grep -q "^$work/prefix/bin/qdmr$" || fail "the installed qdmr is not the one on PATH"
# The installed qdmr finds its report generator (share/qdmr/qdmr_report): the generator itself answers a bad folder.
set +e
qdmr report "$work/no-such-results" -o "$work/no-report" 2>"$work/report.err"
code=$?
set -e
[ "$code" -eq 2 ] && grep -q "no-such-results: not a folder" "$work/report.err" ||
  fail "the installed qdmr report did not run its generator (exit $code): $(cat "$work/report.err")"
test -f "$work/prefix/share/qdmr/qdmr_report/__main__.py" || fail "the report generator is not installed"

cd "$src"
QDMR_CHECK_OUT="$work/pass" examples/ci/run-checks.sh || fail "examples/ci/checks.json failed (exit $?)"
grep -q '<testsuites name="qdmr check" tests="3" failures="0" errors="0"' "$work/pass/junit.xml" || fail "JUnit XML of the passing run"
test -f "$work/pass/report/index.html" || fail "no report of the passing run"

# The same manifest with one hash changed, beside the original so its relative paths still resolve.
broken="$work/checks.json"
python3 - "$src/examples/ci/checks.json" "$broken" "$src/examples/ci" <<'PY'
import json, os, sys
manifest = json.load(open(sys.argv[1]))
manifest["golden_dir"] = os.path.join(sys.argv[3], "goldens")
for check in manifest["checks"]:
    check["scene"] = os.path.normpath(os.path.join(sys.argv[3], check["scene"]))
    if "golden" in check:
        check["golden"] = {k: os.path.join(sys.argv[3], v) for k, v in check["golden"].items()}
manifest["checks"][1]["hash"]["color"] = "sha1:" + "0" * 40
json.dump(manifest, open(sys.argv[2], "w"), indent=2)
PY
status=0
QDMR_CHECK_OUT="$work/fail" examples/ci/run-checks.sh "$broken" > "$work/fail.log" || status=$?
[ "$status" -eq 1 ] || fail "a changed image must exit 1, got $status: $(cat "$work/fail.log")"
grep -q '<failure message="color: hash sha1:' "$work/fail/junit.xml" || fail "JUnit XML of the failing run has no failure"
test -f "$work/fail/report/cobbles_pom/color.rendered.png" || fail "no diff folder in the report"
grep -q 'cobbles_pom/color.rendered.png' "$work/fail/report/index.html" || fail "the report does not show the failure"
echo "ci_example_test: both examples' commands work (pass: exit 0, changed image: exit 1, artefacts written)"
