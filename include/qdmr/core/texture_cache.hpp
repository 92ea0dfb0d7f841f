#pragma once
// The emulated texture cache a scene may ask for (scene key `texture_cache`, docs/texture_cache.md): what is
// modelled, not how. Off by default: a frame without it records nothing and pays nothing.
#include <optional>
#include <string>

namespace qdmr {

// How the texels (or BC3 blocks) of one mip level are ordered in memory.
enum class TexelLayout {
  Linear,  // rows
  Tiled4,  // 4x4 tiles, row-major inside and between tiles
  Tiled8,  // 8x8 tiles
  Morton   // Z-order inside power-of-two squares, the squares row-major
};

// Where a max-quadtree's levels live: a mip chain (one 2D level after the other, in the texel layout), or the
// talk's 3D texture: every level a full-resolution slice (each texel the maximum of its cell), stored in
// 4x4x4-texel bricks, so a descent to the child cell often stays in the same cache line.
enum class QuadtreeStorage { MipChain, Volume };

enum class CacheReplacement { Lru, Fifo };

struct TextureCacheDesc {
  bool enabled = false;
  // Defaults: a texture L1 of the talk's GPUs. The CUDA programming guide (compute capability 1.x, G80/GT200)
  // gives 6 to 8 KB of texture cache working set per multiprocessor; 32-byte lines and 8 ways are assumptions
  // (docs/texture_cache.md).
  int size_bytes = 8192;
  int line_bytes = 32;
  int ways = 8;
  CacheReplacement replacement = CacheReplacement::Lru;
  TexelLayout layout = TexelLayout::Linear;
  QuadtreeStorage quadtree = QuadtreeStorage::MipChain;
  // Square screen regions of this many pixels a side each run on one texture unit, starting with a cold cache:
  // the unit of replay, so the statistics do not depend on threads or SIMD width (the tile size must be a
  // multiple of it).
  int region = 32;
  // A GPU warp: this many pixels (whole 2x2 quads) fetch in lock step, iteration by iteration.
  int warp = 32;
};

// What is wrong with a cache description, if anything: the field (a TextureCacheDesc member name, as in the
// scene file) and what it must be.
struct TextureCacheProblem {
  std::string field, what;
};
std::optional<TextureCacheProblem> check_texture_cache(const TextureCacheDesc& desc);

const char* texel_layout_name(TexelLayout layout);
const char* quadtree_storage_name(QuadtreeStorage storage);
const char* cache_replacement_name(CacheReplacement replacement);

}  // namespace qdmr
