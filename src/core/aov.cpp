#include "qdmr/core/aov.hpp"

namespace qdmr {
namespace {

struct AovInfo {
  Aov aov;
  const char* name;
  int channels;
};
constexpr AovInfo kAovs[kAovCount] = {
    {Aov::Depth, "depth", 1},          {Aov::Normal, "normal", 3},        {Aov::UV, "uv", 2},
    {Aov::Iterations, "iterations", 1}, {Aov::HitUV, "hit_uv", 2},         {Aov::HitDepth, "hit_depth", 1},
    {Aov::ErrorTexels, "error_texels", 1}, {Aov::Missed, "missed", 1},    {Aov::Shadow, "shadow", 1},
    {Aov::Ao, "ao", 1},                {Aov::CacheMisses, "cache_misses", 1}};

}  // namespace

std::optional<Aov> parse_aov(const std::string& name) {
  for (const AovInfo& a : kAovs)
    if (name == a.name) return a.aov;
  return std::nullopt;
}

std::string aov_name(Aov aov) { return kAovs[int(aov)].name; }
int aov_channels(Aov aov) { return kAovs[int(aov)].channels; }

std::vector<std::string> aov_names() {
  std::vector<std::string> names;
  for (const AovInfo& a : kAovs) names.push_back(a.name);
  return names;
}

}  // namespace qdmr
