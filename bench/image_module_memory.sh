#!/bin/sh
# The memory the image library costs a qdmr process (the figure behind kImageModuleBytes, qdmr/plan/plan.hpp):
# the same small scene drawn by `qdmr bench` twice, once with a 4x4 PGM file albedo (which loads the image
# module) and once with a 4x4 procedural albedo (which does not), each process sampled from
# /proc/PID/smaps_rollup while it draws; prints both and the difference of private dirty memory (heap and the
# libraries' relocated data: what the process cannot give back) and of resident memory (which also counts the
# libraries' code, file pages the kernel can drop and reload; Private_Clean is left out because it counts those
# too whenever no other process maps the same library).
#
#   bench/image_module_memory.sh [-B BUILD_DIR]
set -eu

root=$(cd "$(dirname "$0")/.." && pwd)
build="$root/build/release"
[ "${1:-}" = "-B" ] && build=$2
qdmr="$build/qdmr"
[ -x "$qdmr" ] || { echo "image_module_memory: no $qdmr (build it first)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'P5\n4 4\n255\n' > "$tmp/albedo.pgm"
head -c 16 /dev/zero | tr '\0' 'd' >> "$tmp/albedo.pgm"

# Private dirty and resident kB of one `qdmr bench` of scenes/plane.json at 64x64 with ALBEDO as the albedo.
sample() {
  "$qdmr" bench "$root/scenes/plane.json" --frames 100000 --warmup 0 --threads 1 --set /output/width=64 \
    --set /output/height=64 --set "/materials/bricks/layers/0/albedo=$1" > /dev/null 2>&1 &
  pid=$!
  sleep 3  # past load, plan and prepare (well under a second), while it draws
  awk '/^Rss:/ {rss = $2} /^Private_Dirty:/ {private = $2} END {print private, rss}' "/proc/$pid/smaps_rollup"
  kill "$pid"
  wait "$pid" 2> /dev/null || true
}

set -- $(sample '{"procedural": "bricks", "size": 4}')
none_private=$1 none_rss=$2
set -- $(sample "{\"file\": \"$tmp/albedo.pgm\"}")
file_private=$1 file_rss=$2
echo "procedural albedo: private dirty $none_private kB, resident $none_rss kB"
echo "file albedo:       private dirty $file_private kB, resident $file_rss kB"
awk -v p=$((file_private - none_private)) -v r=$((file_rss - none_rss)) \
  'BEGIN {printf "image module: %.1f MiB private dirty, %.1f MiB resident\n", p / 1024, r / 1024}'
