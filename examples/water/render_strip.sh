#!/usr/bin/env bash
# The strip of frames in docs/techniques.md ("Dynamic surfaces"): frames 0, 30, 60 and 90 of scenes/water.json
# (0, 1.25, 2.5 and 3.75 s) rendered through one qdmr process at 1920x1080, each scaled to 320x180 and set side by
# side with oiiotool (Debian: openimageio-tools, in scripts/setup).
#
#   examples/water/render_strip.sh [OUT.png] [-- extra qdmr render arguments, e.g. --width 480 --height 270]
#
# Default OUT: docs/images/water/strip.png of this checkout. Environment: QDMR (the qdmr command; default: qdmr on
# PATH, else build/release/qdmr of this checkout).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${1:-$root/docs/images/water/strip.png}
[ $# -gt 0 ] && shift
[ "${1:-}" = "--" ] && shift
qdmr=${QDMR:-$(command -v qdmr || echo "$root/build/release/qdmr")}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
frames=(0 30 60 90)
"$qdmr" render "$root/scenes/water.json" --frames 0:90:30 -o "$tmp/water_%04d.png" "$@" >/dev/null
args=()
for f in "${frames[@]}"; do args+=("$tmp/$(printf 'water_%04d.png' "$f")" --resize 320x180); done
mkdir -p "$(dirname "$out")"
oiiotool "${args[@]}" --mosaic:pad=4 "${#frames[@]}x1" -o "$out"
echo "$out"
