#!/bin/sh
# Renders each benchmark case RUNS times per thread count (and per build with --sse), alternating the
# variants inside every round so that ratios are measured side by side, then prints markdown tables of
# medians taken from the --stats JSON files (bench/summarize.py).
#
#   bench/run_scenes.sh [-n RUNS] [-t "1 2"] [-B BUILD_DIR] [--sse] [--llvmpipe] [CASE ...]
#
# CASE: plane terrain objects real_rocks grid1m (default: all; real_rocks only when ../shared/data exists).
# grid1m is scenes/plane.json with its plane replaced by a 710x710 grid: 1,008,200 small triangles.
# --sse also runs the SSE4.2 kernel of the same binary (qdmr --isa sse4.2, labelled qdmr-sse); --llvmpipe also runs BUILD_DIR/bench/llvmpipe/llvmpipe_bench on
# plane and grid1m with LP_NUM_THREADS set to each thread count. For clean timings run it on an otherwise
# idle machine (nothing compiling).
set -eu

root=$(cd "$(dirname "$0")/.." && pwd)
runs=5
threads="1 2"
build="$root/build/release"
sse=0
llvmpipe=0
while [ $# -gt 0 ]; do
  case "$1" in
    -n) runs=$2; shift 2 ;;
    -t) threads=$2; shift 2 ;;
    -B) build=$2; shift 2 ;;
    --sse) sse=1; shift ;;
    --llvmpipe) llvmpipe=1; shift ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    -*) echo "run_scenes.sh: unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
cases=${*:-"plane terrain objects real_rocks grid1m"}
if [ $# -eq 0 ] && [ ! -d "$root/../shared/data" ]; then cases="plane terrain objects grid1m"; fi

binaries="qdmr"
if [ $sse -eq 1 ]; then binaries="qdmr qdmr-sse"; fi
[ -x "$build/qdmr" ] || { echo "run_scenes.sh: $build/qdmr is not built" >&2; exit 1; }
lp="$build/bench/llvmpipe/llvmpipe_bench"
if [ $llvmpipe -eq 1 ] && [ ! -x "$lp" ]; then echo "run_scenes.sh: $lp is not built" >&2; exit 1; fi

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
grid='/objects/0/mesh={"type":"grid","size":[4,4],"resolution":710,"uv_scale":[2,2]}'

render() {  # render CASE BUILD THREADS ROUND (BUILD: qdmr = the best kernel, qdmr-sse = --isa sse4.2)
  isa=auto
  if [ "$2" = qdmr-sse ]; then isa=sse4.2; fi
  scene="$root/scenes/$1.json"
  if [ "$1" = grid1m ]; then scene="$root/scenes/plane.json"; fi
  set -- "$1" "$2" "$3" "$4" "$scene"
  if [ "$1" = grid1m ]; then
    "$build/qdmr" render "$5" --set "$grid" -o "$out/image.png" --threads "$3" --isa "$isa" --stats "$out/$1__$2__t$3__r$4.json" >/dev/null
  else
    "$build/qdmr" render "$5" -o "$out/image.png" --threads "$3" --isa "$isa" --stats "$out/$1__$2__t$3__r$4.json" >/dev/null
  fi
}

for c in $cases; do
  [ -f "$root/scenes/$c.json" ] || [ "$c" = grid1m ] || { echo "run_scenes.sh: unknown case $c" >&2; exit 2; }
  r=1
  while [ $r -le "$runs" ]; do
    for t in $threads; do
      for b in $binaries; do render "$c" "$b" "$t" "$r"; done
      if [ $llvmpipe -eq 1 ] && { [ "$c" = plane ] || [ "$c" = grid1m ]; }; then
        mesh=plane
        if [ "$c" = grid1m ]; then mesh=grid; fi
        LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe LP_NUM_THREADS=$t "$lp" --mesh $mesh --runs 3 \
          >"$out/${c}__llvmpipe__t${t}__r${r}.lp.json"
      fi
    done
    r=$((r + 1))
  done
done

echo "Cases: $cases; $runs rounds; threads: $threads; builds: $binaries$([ $llvmpipe -eq 1 ] && echo ', llvmpipe' || true)"
python3 "$root/bench/summarize.py" "$out"
