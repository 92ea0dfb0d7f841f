#pragma once
// The texture cache model: a set-associative cache of lines, and the map from a texel of a texture level to a
// byte address under a memory layout. Both are plain sequential models, fed by the replay of recorded fetches
// (draw/fetch_replay) and testable on synthetic access patterns.
#include <cstdint>
#include <vector>

#include "qdmr/core/texture_cache.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

// A set-associative cache of size_bytes in lines of line_bytes, `ways` lines per set, set = line address modulo
// the set count; LRU or FIFO replacement. Starts cold.
class TextureCache {
public:
  explicit TextureCache(const TextureCacheDesc& desc);  // throws qdmr::Error when check_texture_cache() fails

  // One access to the byte at `address`; true on a hit. A miss brings the line in, evicting per the policy.
  bool access(std::uint64_t address);
  void clear();  // cold again

  int sets() const { return sets_; }
  int ways() const { return ways_; }
  int line_bytes() const { return 1 << line_shift_; }

private:
  struct Way {
    std::uint64_t tag = ~std::uint64_t(0);  // line address; all ones: empty
    std::uint64_t stamp = 0;                // last use (LRU) or fill (FIFO); 0: empty
  };
  int sets_, ways_, line_shift_;
  bool lru_;
  std::uint64_t clock_ = 0;
  std::vector<Way> ways_storage_;  // sets_ x ways_
};

// The address space of a frame's textures: each registered texture gets a base (4 KiB aligned, in registration
// order) and its levels are laid out per the layout. BC3 textures are addressed by 4x4 block (16 bytes).
class TextureAddressMap {
public:
  struct Entry {
    const Texture* texture;
    bool quadtree;  // a max-quadtree: stored per QuadtreeStorage
    bool bc3;
  };

  TextureAddressMap(TexelLayout layout, QuadtreeStorage quadtree) : layout_(layout), quadtree_(quadtree) {}

  // Registers a texture once (later calls return the same slot); slots number the registered textures.
  int add(const Texture& texture, bool quadtree, bool bc3);
  // The slot of a registered texture, or -1.
  int slot(const Texture* texture) const;
  // Byte address of texel (x, y) of `level` of the texture in `slot`.
  std::uint64_t address(int slot, int level, int x, int y) const;
  // Bytes every registered texture occupies in this layout (padding to tiles and 3D bricks included).
  std::uint64_t footprint_bytes() const { return next_base_; }
  int size() const { return int(entries_.size()); }
  const Entry& entry(int slot) const { return entries_[std::size_t(slot)]; }

private:
  struct Level {
    std::uint64_t base = 0;
    int width = 0, height = 0;    // in elements (texels, or BC3 blocks)
    int tiles_x = 0;              // tiled layouts: tiles per row; morton: squares per row
    int square = 0;               // morton: side of the squares (a power of two)
  };
  struct Layout {
    std::vector<Level> levels;
    int element_bytes = 1, block = 1;  // bytes per element; texels per element side (4 for BC3)
    bool volume = false;               // levels as full-resolution slices in 4x4x4 bricks
    int bricks_x = 0, bricks_y = 0;    // volume: bricks per row and per slice row
  };
  std::uint64_t level_offset(const Level& level, int x, int y) const;

  TexelLayout layout_;
  QuadtreeStorage quadtree_;
  std::vector<Entry> entries_;
  std::vector<Layout> layouts_;
  std::uint64_t next_base_ = 0;
};

}  // namespace qdmr
