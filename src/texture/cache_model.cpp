#include "texture/cache_model.hpp"

#include <algorithm>
#include <bit>
#include <string>

#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

constexpr std::uint64_t kTextureAlignment = 4096;  // where each texture starts
constexpr std::uint64_t kLevelAlignment = 256;     // where each mip level starts
constexpr int kBc3Block = 4, kBc3BlockBytes = 16;  // a DXT5 block: 4x4 texels in 16 bytes
constexpr int kBrick = 4;                          // volume storage: 4x4x4-texel bricks

std::uint64_t align_up(std::uint64_t n, std::uint64_t a) { return (n + a - 1) / a * a; }
int ceil_div(int n, int d) { return (n + d - 1) / d; }

// Interleaves the bits of x (even positions) and y (odd positions).
std::uint64_t morton(std::uint32_t x, std::uint32_t y) {
  const auto spread = [](std::uint64_t v) {
    v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
    v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
    v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
    v = (v | (v << 2)) & 0x3333333333333333ull;
    v = (v | (v << 1)) & 0x5555555555555555ull;
    return v;
  };
  return spread(x) | (spread(y) << 1);
}

int tile_side(TexelLayout layout) { return layout == TexelLayout::Tiled4 ? 4 : layout == TexelLayout::Tiled8 ? 8 : 1; }

}  // namespace

TextureCache::TextureCache(const TextureCacheDesc& desc) {
  if (const auto p = check_texture_cache(desc)) throw Error("texture_cache." + p->field, p->what);
  ways_ = desc.ways;
  sets_ = desc.size_bytes / (desc.line_bytes * desc.ways);
  line_shift_ = std::countr_zero(unsigned(desc.line_bytes));
  lru_ = desc.replacement == CacheReplacement::Lru;
  ways_storage_.resize(std::size_t(sets_) * std::size_t(ways_));
}

void TextureCache::clear() {
  std::fill(ways_storage_.begin(), ways_storage_.end(), Way{});
  clock_ = 0;
}

bool TextureCache::access(std::uint64_t address) {
  const std::uint64_t line = address >> line_shift_;
  Way* set = ways_storage_.data() + std::size_t(line % std::uint64_t(sets_)) * std::size_t(ways_);
  ++clock_;
  Way* victim = set;
  for (int w = 0; w < ways_; ++w) {
    if (set[w].tag == line) {
      if (lru_) set[w].stamp = clock_;
      return true;
    }
    if (set[w].stamp < victim->stamp) victim = set + w;  // empty ways (stamp 0) first, then the oldest
  }
  victim->tag = line;
  victim->stamp = clock_;
  return false;
}

int TextureAddressMap::add(const Texture& texture, bool quadtree, bool bc3) {
  if (const int s = slot(&texture); s >= 0) return s;
  Layout l;
  l.volume = quadtree && quadtree_ == QuadtreeStorage::Volume;
  const int bytes = bytes_per_texel(texture.format);
  std::uint64_t base = align_up(next_base_, kTextureAlignment);
  if (l.volume) {
    // Level k of the tree at full resolution in slice k: texel (x << k, y << k, k).
    l.element_bytes = bytes;
    l.bricks_x = ceil_div(texture.width(), kBrick);
    l.bricks_y = ceil_div(texture.height(), kBrick);
    const int slabs = ceil_div(texture.level_count(), kBrick);
    Level level;
    level.base = base;
    l.levels.assign(std::size_t(texture.level_count()), level);
    next_base_ = base + std::uint64_t(l.bricks_x) * std::uint64_t(l.bricks_y) * std::uint64_t(slabs) *
                            std::uint64_t(kBrick * kBrick * kBrick) * std::uint64_t(bytes);
  } else {
    l.block = bc3 ? kBc3Block : 1;
    l.element_bytes = bc3 ? kBc3BlockBytes : bytes;
    const int tile = tile_side(layout_);
    for (const TextureLevel& t : texture.levels) {
      Level level;
      level.base = base;
      level.width = ceil_div(t.width, l.block);
      level.height = ceil_div(t.height, l.block);
      std::uint64_t elements = 0;
      if (layout_ == TexelLayout::Morton) {
        level.square = int(std::bit_floor(unsigned(std::min(level.width, level.height))));
        level.tiles_x = ceil_div(level.width, level.square);
        elements = std::uint64_t(level.tiles_x) * std::uint64_t(ceil_div(level.height, level.square)) *
                   std::uint64_t(level.square) * std::uint64_t(level.square);
      } else {
        level.tiles_x = ceil_div(level.width, tile);
        elements = std::uint64_t(level.tiles_x) * std::uint64_t(ceil_div(level.height, tile)) * std::uint64_t(tile * tile);
      }
      l.levels.push_back(level);
      base = align_up(base + elements * std::uint64_t(l.element_bytes), kLevelAlignment);
    }
    next_base_ = base;
  }
  entries_.push_back({&texture, quadtree, bc3});
  layouts_.push_back(std::move(l));
  return int(entries_.size()) - 1;
}

int TextureAddressMap::slot(const Texture* texture) const {
  for (std::size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].texture == texture) return int(i);
  return -1;
}

std::uint64_t TextureAddressMap::level_offset(const Level& level, int x, int y) const {
  switch (layout_) {
    case TexelLayout::Linear: return std::uint64_t(y) * std::uint64_t(level.width) + std::uint64_t(x);
    case TexelLayout::Tiled4:
    case TexelLayout::Tiled8: {
      const int t = tile_side(layout_);
      const std::uint64_t tile = std::uint64_t(y / t) * std::uint64_t(level.tiles_x) + std::uint64_t(x / t);
      return tile * std::uint64_t(t * t) + std::uint64_t((y % t) * t + x % t);
    }
    case TexelLayout::Morton: {
      const int s = level.square;
      const std::uint64_t square = std::uint64_t(y / s) * std::uint64_t(level.tiles_x) + std::uint64_t(x / s);
      return square * std::uint64_t(s) * std::uint64_t(s) + morton(std::uint32_t(x % s), std::uint32_t(y % s));
    }
  }
  return 0;
}

std::uint64_t TextureAddressMap::address(int slot, int level_index, int x, int y) const {
  const Layout& l = layouts_[std::size_t(slot)];
  const Level& level = l.levels[std::size_t(level_index)];
  if (l.volume) {
    const Texture& t = *entries_[std::size_t(slot)].texture;
    const int X = std::min(x << level_index, t.width() - 1), Y = std::min(y << level_index, t.height() - 1);
    const int Z = level_index;
    const std::uint64_t brick =
        (std::uint64_t(Z / kBrick) * std::uint64_t(l.bricks_y) + std::uint64_t(Y / kBrick)) * std::uint64_t(l.bricks_x) +
        std::uint64_t(X / kBrick);
    const int inside = ((Z % kBrick) * kBrick + Y % kBrick) * kBrick + X % kBrick;
    return level.base + (brick * std::uint64_t(kBrick * kBrick * kBrick) + std::uint64_t(inside)) * std::uint64_t(l.element_bytes);
  }
  return level.base + level_offset(level, x / l.block, y / l.block) * std::uint64_t(l.element_bytes);
}

}  // namespace qdmr
