#include "qdmr/core/texture_cache.hpp"

namespace qdmr {

const char* texel_layout_name(TexelLayout layout) {
  switch (layout) {
    case TexelLayout::Linear: return "linear";
    case TexelLayout::Tiled4: return "tiled4";
    case TexelLayout::Tiled8: return "tiled8";
    case TexelLayout::Morton: return "morton";
  }
  return "?";
}

const char* quadtree_storage_name(QuadtreeStorage storage) {
  return storage == QuadtreeStorage::Volume ? "volume" : "mip_chain";
}

const char* cache_replacement_name(CacheReplacement replacement) {
  return replacement == CacheReplacement::Fifo ? "fifo" : "lru";
}

std::optional<TextureCacheProblem> check_texture_cache(const TextureCacheDesc& d) {
  const auto pow2 = [](int n) { return n > 0 && (n & (n - 1)) == 0; };
  const auto problem = [](const char* field, const std::string& what, int got) {
    return TextureCacheProblem{field, what + ", got " + std::to_string(got)};
  };
  if (!pow2(d.line_bytes) || d.line_bytes < 4 || d.line_bytes > 4096)
    return problem("line_bytes", "must be a power of two from 4 to 4096", d.line_bytes);
  if (d.ways < 1 || d.ways > 1024) return problem("ways", "must be 1 to 1024", d.ways);
  const long long set_bytes = 1LL * d.line_bytes * d.ways;
  if (d.size_bytes < set_bytes || d.size_bytes % set_bytes != 0 || d.size_bytes > (64 << 20))
    return problem("size_bytes",
                   "must be a whole number of sets (line_bytes x ways = " + std::to_string(set_bytes) +
                       " bytes) and at most 64 MiB",
                   d.size_bytes);
  if (d.region < 8 || d.region > 1024 || d.region % 8 != 0)
    return problem("region", "must be a multiple of 8 from 8 to 1024 pixels", d.region);
  if (d.warp < 4 || d.warp > 1024 || d.warp % 4 != 0)
    return problem("warp", "must be a multiple of 4 pixels (whole quads) from 4 to 1024", d.warp);
  return std::nullopt;
}

}  // namespace qdmr
