#!/bin/sh
# The check step of the CI examples (github-actions.yml, gitlab-ci.yml): every check of the manifest in one qdmr
# process, JUnit XML for the CI's test report and an HTML page of the results and failures (with their diff
# folders), both kept as artefacts.
#   examples/ci/run-checks.sh [MANIFEST]      (default examples/ci/checks.json; output in $QDMR_CHECK_OUT)
# Exit status: qdmr check's: 0 all pass, 1 an image changed, 2 a check could not run.
set -u
manifest=${1:-examples/ci/checks.json}
out=${QDMR_CHECK_OUT:-qdmr-check}
mkdir -p "$out"
exec qdmr check "$manifest" --junit "$out/junit.xml" --report "$out/report" --jobs "${QDMR_CHECK_JOBS:-1}"
