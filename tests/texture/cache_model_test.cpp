// The texture cache model on synthetic access patterns with known answers: cold misses of a stream, a working
// set that fits, conflict misses in one set, LRU against FIFO, and the texel-to-address maps of every layout.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "qdmr/core/error.hpp"
#include "texture/cache_model.hpp"

namespace qdmr::test {
namespace {

TextureCacheDesc cache_desc(int size, int line, int ways, CacheReplacement r = CacheReplacement::Lru) {
  TextureCacheDesc d;
  d.size_bytes = size;
  d.line_bytes = line;
  d.ways = ways;
  d.replacement = r;
  return d;
}

int count_hits(TextureCache& cache, const std::vector<std::uint64_t>& addresses) {
  int hits = 0;
  for (std::uint64_t a : addresses) hits += cache.access(a);
  return hits;
}

TEST(TextureCacheModel, AStreamMissesOncePerLine) {
  TextureCache cache(cache_desc(8192, 32, 8));
  std::vector<std::uint64_t> bytes(100000);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = 1000 + i;  // not line-aligned on purpose
  const int hits = count_hits(cache, bytes);
  // Bytes 1000 .. 100999 span lines 31 .. 3156: 3126 lines, each a miss once, every other byte a hit.
  EXPECT_EQ(int(bytes.size()) - hits, 3126);
}

TEST(TextureCacheModel, AWorkingSetThatFitsOnlyMissesCold) {
  TextureCache cache(cache_desc(8192, 32, 8));
  std::vector<std::uint64_t> set;
  for (std::uint64_t a = 0; a < 8192; a += 4) set.push_back(a);  // exactly the cache's size
  EXPECT_EQ(int(set.size()) - count_hits(cache, set), 8192 / 32);
  EXPECT_EQ(count_hits(cache, set), int(set.size())) << "a second pass over what fits is all hits";
  cache.clear();
  EXPECT_EQ(int(set.size()) - count_hits(cache, set), 8192 / 32) << "clear() makes the cache cold again";
}

TEST(TextureCacheModel, OneLineMoreThanTheWaysOfASetThrashesUnderLru) {
  TextureCache cache(cache_desc(8192, 32, 8));  // 32 sets
  const std::uint64_t stride = std::uint64_t(cache.sets()) * 32;  // every address in set 0
  std::vector<std::uint64_t> cycle;
  for (int round = 0; round < 10; ++round)
    for (int k = 0; k < 9; ++k) cycle.push_back(std::uint64_t(k) * stride);
  EXPECT_EQ(count_hits(cache, cycle), 0) << "LRU always evicts the line needed next";
  TextureCache fits(cache_desc(8192, 32, 8));
  std::vector<std::uint64_t> eight;
  for (int round = 0; round < 10; ++round)
    for (int k = 0; k < 8; ++k) eight.push_back(std::uint64_t(k) * stride);
  EXPECT_EQ(count_hits(fits, eight), 80 - 8) << "eight lines fit the eight ways of the set";
}

TEST(TextureCacheModel, LruKeepsTheLineInUseWhereFifoEvictsIt) {
  // One set of two ways: A B A C A. LRU evicts B for C (A was used last): A hits twice. FIFO evicts A (filled
  // first) for C: A hits once.
  const std::vector<std::uint64_t> pattern{0, 64, 0, 128, 0};
  TextureCache lru(cache_desc(64, 32, 2, CacheReplacement::Lru));
  TextureCache fifo(cache_desc(64, 32, 2, CacheReplacement::Fifo));
  ASSERT_EQ(lru.sets(), 1);
  EXPECT_EQ(count_hits(lru, pattern), 2);
  EXPECT_EQ(count_hits(fifo, pattern), 1);
}

TEST(TextureCacheModel, RefusesGeometriesItCannotBuild) {
  const auto problem = [](TextureCacheDesc d) {
    const auto p = check_texture_cache(d);
    return p ? p->field : std::string();
  };
  EXPECT_EQ(problem(TextureCacheDesc{}), "");
  EXPECT_EQ(problem(cache_desc(8192, 48, 8)), "line_bytes");
  EXPECT_EQ(problem(cache_desc(8192, 32, 0)), "ways");
  EXPECT_EQ(problem(cache_desc(8000, 32, 8)), "size_bytes");  // not a whole number of 256-byte sets
  EXPECT_EQ(problem(cache_desc(128, 32, 8)), "size_bytes");   // less than one set
  TextureCacheDesc d;
  d.region = 20;
  EXPECT_EQ(problem(d), "region");
  d = TextureCacheDesc{};
  d.warp = 6;
  EXPECT_EQ(problem(d), "warp");
  EXPECT_THROW(TextureCache(cache_desc(8192, 48, 8)), Error);
}

// An R8 texture of w x h with its mip chain (contents do not matter to addresses).
Texture r8(int w, int h) { return allocate_texture(w, h, TexelFormat::R8, false); }

// Every texel of every level maps to a distinct address inside the texture's footprint.
void expect_one_to_one(const TextureAddressMap& map, int slot, const Texture& t) {
  std::set<std::uint64_t> seen;
  for (int l = 0; l < t.level_count(); ++l)
    for (int y = 0; y < t.levels[std::size_t(l)].height; ++y)
      for (int x = 0; x < t.levels[std::size_t(l)].width; ++x) {
        const std::uint64_t a = map.address(slot, l, x, y);
        EXPECT_LT(a, map.footprint_bytes());
        EXPECT_TRUE(seen.insert(a).second) << "level " << l << " texel " << x << "," << y << " shares an address";
      }
}

TEST(TextureCacheModel, EveryLayoutGivesEachTexelItsOwnAddress) {
  const Texture t = r8(64, 32);  // not square: Morton squares side by side
  for (TexelLayout layout : {TexelLayout::Linear, TexelLayout::Tiled4, TexelLayout::Tiled8, TexelLayout::Morton}) {
    TextureAddressMap map(layout, QuadtreeStorage::MipChain);
    const int slot = map.add(t, false, false);
    SCOPED_TRACE(texel_layout_name(layout));
    expect_one_to_one(map, slot, t);
  }
}

TEST(TextureCacheModel, LayoutsPutTheExpectedTexelsInOneLine) {
  const Texture t = r8(256, 256);
  const auto line_of = [](const TextureAddressMap& m, int x, int y) { return m.address(0, 0, x, y) / 32; };
  TextureAddressMap linear(TexelLayout::Linear, QuadtreeStorage::MipChain);
  linear.add(t, false, false);
  EXPECT_EQ(linear.address(0, 0, 5, 3), 3u * 256 + 5);
  EXPECT_EQ(line_of(linear, 0, 0), line_of(linear, 31, 0));
  EXPECT_NE(line_of(linear, 0, 0), line_of(linear, 0, 1));
  // 4x4 tiles of 16 bytes: a 32-byte line holds two tiles side by side (8x4 texels).
  TextureAddressMap tiled4(TexelLayout::Tiled4, QuadtreeStorage::MipChain);
  tiled4.add(t, false, false);
  EXPECT_EQ(line_of(tiled4, 0, 0), line_of(tiled4, 7, 3));
  EXPECT_NE(line_of(tiled4, 0, 0), line_of(tiled4, 0, 4));
  // 8x8 tiles of 64 bytes: a line is the tile's top four rows.
  TextureAddressMap tiled8(TexelLayout::Tiled8, QuadtreeStorage::MipChain);
  tiled8.add(t, false, false);
  EXPECT_EQ(line_of(tiled8, 0, 0), line_of(tiled8, 7, 3));
  EXPECT_NE(line_of(tiled8, 0, 0), line_of(tiled8, 0, 4));
  // Morton: the 32 texels of a line are a 8x4 block (x takes the even bits).
  TextureAddressMap morton(TexelLayout::Morton, QuadtreeStorage::MipChain);
  morton.add(t, false, false);
  EXPECT_EQ(morton.address(0, 0, 1, 0), 1u);
  EXPECT_EQ(morton.address(0, 0, 0, 1), 2u);
  EXPECT_EQ(morton.address(0, 0, 3, 3), 15u);
  EXPECT_EQ(line_of(morton, 0, 0), line_of(morton, 7, 3));
}

TEST(TextureCacheModel, Bc3TexturesAreAddressedBy16ByteBlocks) {
  const Texture t = r8(64, 64);
  TextureAddressMap map(TexelLayout::Linear, QuadtreeStorage::MipChain);
  map.add(t, false, true);
  EXPECT_EQ(map.address(0, 0, 3, 3), map.address(0, 0, 0, 0)) << "one block";
  EXPECT_EQ(map.address(0, 0, 4, 0), map.address(0, 0, 0, 0) + 16);
  EXPECT_EQ(map.address(0, 0, 0, 4), map.address(0, 0, 0, 0) + 16 * 16);
  // Level 0: 16x16 blocks of 16 bytes = 4096 bytes, the size of the R8 texels it replaces (BC3 is 1 byte/texel).
  EXPECT_EQ(map.address(0, 1, 0, 0) - map.address(0, 0, 0, 0), 4096u);
}

TEST(TextureCacheModel, TheVolumeStoresEachTreeLevelAsAFullSizeSliceInBricks) {
  const Texture tree = r8(64, 64);  // 7 levels
  TextureAddressMap map(TexelLayout::Linear, QuadtreeStorage::Volume);
  const int slot = map.add(tree, true, false);
  // 16 x 16 bricks per slab, two slabs (levels 0-3, 4-6) of 64-byte bricks.
  EXPECT_EQ(map.footprint_bytes(), 16u * 16 * 2 * 64);
  // Level k cell (cx, cy) is texel (cx << k, cy << k) of slice k.
  EXPECT_EQ(map.address(slot, 0, 1, 2), 2u * 4 + 1);
  EXPECT_EQ(map.address(slot, 1, 0, 0), 16u);   // slice 1 of brick 0
  EXPECT_EQ(map.address(slot, 1, 1, 0), 16u + 2);
  EXPECT_EQ(map.address(slot, 4, 0, 0), 16u * 16 * 64);  // the second slab
  // A descent at the same corner stays in one 64-byte brick: levels 3 .. 0 of texel (0, 0).
  for (int k = 0; k < 4; ++k) EXPECT_EQ(map.address(slot, k, 0, 0) / 64, 0u);
  // Only quadtrees go into the volume: another texture of the same map keeps its mip chain.
  const Texture colour = r8(64, 64);
  const int other = map.add(colour, false, false);
  EXPECT_EQ(map.address(other, 0, 1, 0) - map.address(other, 0, 0, 0), 1u);
  EXPECT_EQ(map.add(tree, true, false), slot) << "a texture is registered once";
}

}  // namespace
}  // namespace qdmr::test
