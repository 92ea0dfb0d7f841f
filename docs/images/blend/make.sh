#!/bin/sh
# Regenerates the images of docs/shadows-ao-blending.md: each one rendered by qdmr at 1920x1080 (the frame
# time printed at the end is geometry + binning + raster_shade of that single render, from --stats), then
# downscaled to 640x360 with oiiotool to keep the repository small.
#
#   docs/images/blend/make.sh [BUILD_DIR]      (default build/release; needs oiiotool and python3)
#
# Baked AO maps and other derived data go to a temporary QDMR_CACHE_DIR, so baking is in `prepare`, not in
# the frame time. One render per image on a shared machine: for costs use bench/blend.py and
# bench/shadows_ao.py (docs/performance.md).
set -eu

root=$(cd "$(dirname "$0")/../../.." && pwd)
build=${1:-$root/build/release}
dest=$root/docs/images/blend
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export QDMR_CACHE_DIR="$tmp/cache"
blend=$root/scenes/surface_blend_4layers.json
terrain=$root/scenes/terrain.json
M=/materials/blend

shot() {  # shot NAME SCENE [--set ...]
  name=$1 scene=$2
  shift 2
  "$build/qdmr" render "$scene" -o "$tmp/$name.png" --stats "$tmp/$name.json" --width 1920 --height 1080 "$@" >/dev/null
  oiiotool "$tmp/$name.png" --resize 640x360 -o "$dest/$name.png"
}

# Self-shadowing: QDM at depth 0.06 (the scene has POM at 0.045), the sun lowered to 17 degrees.
sun='/lights/0/direction=[-0.9,0.25,0.3]'
for mode in off hard horizon qdm_soft; do
  shot "shadow_$mode" "$blend" --set $M/technique/name=qdm --set $M/technique/depth_scale=0.06 --set "$sun" \
    --set $M/shadow/mode=$mode
done
# Hard shadows of the box surface show terraces on smooth slopes under a low sun; a small bias removes them.
shot shadow_hard_bias "$blend" --set $M/technique/name=qdm --set $M/technique/depth_scale=0.06 --set "$sun" \
  --set $M/shadow/mode=hard --set $M/shadow/bias=0.02

# Ambient occlusion: same QDM surface, the sun dimmed (0.35) and the sky brightened (0.9) so the ambient
# term, the one AO multiplies, dominates.
for mode in off frame baked; do
  shot "ao_$mode" "$blend" --set $M/technique/name=qdm --set $M/technique/depth_scale=0.06 \
    --set /lights/0/intensity=0.35 --set /lights/1/intensity=0.9 --set $M/ao/mode=$mode --set $M/ao/jitter=true
done

# Blend operators: the scene as stored (POM, per-vertex weights), operator changed.
for op in alpha height height_width; do
  shot "blend_$op" "$blend" --set $M/blend/operator=$op
done

# Per-vertex vs per-pixel weights at a high depth scale (0.25), QDM over the height blend.
for mode in vertex pixel; do
  shot "weights_$mode" "$blend" --set $M/technique/name=qdm --set $M/technique/depth_scale=0.25 \
    --set $M/blend/weights/mode=$mode
done

# Lighting models: the scene as stored (specular 0.15 = Cook-Torrance F0), Cook-Torrance at roughness 0.35.
shot lighting_blinn_phong "$blend" --set $M/lighting/model=blinn_phong
shot lighting_cook_torrance "$blend" --set $M/lighting/model=cook_torrance --set $M/lighting/roughness=0.35

# The default scene as stored: QDMHB over four layers, per-pixel terrain weights, qdm_soft shadows, baked AO.
shot terrain "$terrain"

# The same on real data (../shared/data beside the repository; skipped without it).
if [ -d "$root/../shared/data" ]; then shot real_terrain "$root/scenes/real_terrain.json"; fi

python3 - "$tmp" <<'EOF'
import json, pathlib, sys
print("| image | frame ms (1920x1080, one render) | iterations mean / p99 |")
print("|---|---|---|")
for f in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    s = json.loads(f.read_text())
    t = s["time_ms"]
    print(f"| {f.stem}.png | {t['geometry'] + t['binning'] + t['raster_shade']:.0f} | "
          f"{s['iterations']['mean']:.1f} / {s['iterations']['p99']:.0f} |")
EOF
