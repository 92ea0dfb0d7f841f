#!/usr/bin/env bash
# Renders the 120 frames of scenes/water.json (5 s at 24 fps) through one qdmr process and, where ffmpeg is
# installed (Debian: apt-get install ffmpeg), joins them into an MP4.
#
#   examples/water/render_movie.sh [OUT_DIR] [-- extra qdmr render arguments, e.g. --width 960 --height 540]
#
# Environment: QDMR (the qdmr command; default: qdmr on PATH, else build/release/qdmr of this checkout).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${1:-water-frames}
[ $# -gt 0 ] && shift
[ "${1:-}" = "--" ] && shift
qdmr=${QDMR:-$(command -v qdmr || echo "$root/build/release/qdmr")}
mkdir -p "$out"
# One renderer for the whole sequence: after the first frame only the waves' heights, their max-quadtree and
# the normals are rebuilt (qdmr plan scenes/water.json lists them as dynamic).
"$qdmr" render "$root/scenes/water.json" --frames 0:119 -o "$out/water_%04d.png" "$@"
if command -v ffmpeg >/dev/null; then
  ffmpeg -loglevel error -y -framerate 24 -i "$out/water_%04d.png" -c:v libx264 -pix_fmt yuv420p -crf 18 \
    "$out/water.mp4"
  echo "$out/water.mp4"
else
  echo "ffmpeg is not installed: the frames are in $out/ (apt-get install ffmpeg to join them into an MP4)"
fi
