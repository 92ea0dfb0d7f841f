#pragma once
// AOVs: per-pixel outputs besides colour, named the same by the plan, the rasterizer, the programs and the writer.
#include <optional>
#include <string>
#include <vector>

namespace qdmr {

// Displacement AOVs: `iterations` of the intersection loop, `hit_uv` and `hit_depth` (UV units) of the hit;
// against the exact reference: `error_texels` (distance from the reference hit, in level-0 texels) and `missed`
// (1 where the technique hit more than a texel away from the reference, i.e. another feature or layer). Normal
// mapping reports 0 iterations and the hit at the polygon.
// Lighting AOVs, both in [0, 1] and 1 from programs or materials without the feature: `shadow`, the
// self-shadow visibility of the scene's first directional light (1 lit, 0 shadowed; 0 when that light is below
// the polygon; 1 with shadow mode off or no directional light) and `ao`, the ambient occlusion term that
// multiplies the ambient light (after ao.strength; 1 = open, also with ao mode off). Pixels nothing covers are
// 0 in every AOV.
// `cache_misses`: texel reads of that pixel's lanes that missed the emulated texture cache (the scene's
// texture_cache; docs/texture_cache.md), helper lanes of its quad included.
enum class Aov { Depth, Normal, UV, Iterations, HitUV, HitDepth, ErrorTexels, Missed, Shadow, Ao, CacheMisses };
inline constexpr int kAovCount = 11;

std::optional<Aov> parse_aov(const std::string& name);
std::string aov_name(Aov aov);
int aov_channels(Aov aov);
std::vector<std::string> aov_names();
// error_texels and missed: the program traces the exact reference too.
inline bool is_reference_aov(Aov aov) { return aov == Aov::ErrorTexels || aov == Aov::Missed; }

}  // namespace qdmr
