// core/gather.hpp's per-lane loads of single 4-byte values and of texels of 4 floats, on both fetch paths of the build these tests are compiled
// for (the AVX2 kernel, and the AVX-512 one in qdmr_avx512_tests: their transposes, and the portable lane-by-lane
// loop).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "kernel/gather.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;
using simd::kLanes;

// Texel t of the table holds 4t + c + 0.25 in float c: every float says where it came from.
std::vector<float> texel_table(int texels) {
  std::vector<float> table(std::size_t(texels) * 4);
  for (std::size_t i = 0; i < table.size(); ++i) table[i] = float(i) + 0.25f;
  return table;
}

// The lanes' offsets into a table of `size` entries: any order, repeated, the first and the last (ASan would see a
// read past the end), for the single-value loads.
std::vector<std::int32_t> lane_offsets(int size) {
  std::vector<std::int32_t> o(kLanes);
  for (int l = 0; l < kLanes; ++l) o[l] = (l * 13 + 3) % size;
  o[0] = size - 1;
  o[kLanes - 1] = 0;
  if (kLanes > 2) o[1] = o[2];
  return o;
}

TEST(Gather, Bytes4GivesEachLaneItsFourBytes) {
  // Unaligned offsets up to the table's last 4 bytes; every 4-byte window of the table differs.
  std::vector<std::uint8_t> table(41);
  for (std::size_t i = 0; i < table.size(); ++i) table[i] = std::uint8_t(i * 37 + 11);
  const std::vector<std::int32_t> o = lane_offsets(int(table.size()) - 3);
  for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
    alignas(64) std::int32_t value[kLanes];
    simd::load_bytes4(table.data(), Int::load_unaligned(o.data()), path).store_aligned(value);
    for (int l = 0; l < kLanes; ++l) {
      std::int32_t expected;
      std::memcpy(&expected, table.data() + o[l], 4);
      EXPECT_EQ(value[l], expected) << "lane " << l;
    }
  }
}

TEST(Gather, I32AndF32GiveEachLaneItsTableEntry) {
  const int size = 23;
  std::vector<std::int32_t> ints(size);
  std::vector<float> floats(size);
  for (int i = 0; i < size; ++i) {
    ints[std::size_t(i)] = i * 1000003 - 7;
    floats[std::size_t(i)] = float(i) + 0.25f;
  }
  const std::vector<std::int32_t> o = lane_offsets(size);
  const Int index = Int::load_unaligned(o.data());
  for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
    alignas(64) std::int32_t i32[kLanes];
    alignas(64) float f32[kLanes];
    simd::load_i32(ints.data(), index, path).store_aligned(i32);
    simd::load_f32(floats.data(), index, path).store_aligned(f32);
    for (int l = 0; l < kLanes; ++l) {
      EXPECT_EQ(i32[l], o[l] * 1000003 - 7) << "lane " << l;
      EXPECT_EQ(f32[l], float(o[l]) + 0.25f) << "lane " << l;
    }
  }
}

TEST(Gather, F32x4GivesEachLaneItsTexelsFourFloats) {
  // Exactly as long as its texels (ASan would see a read past the last one), texels in any order, repeated,
  // the first and the last.
  const int texels = 37;
  const std::vector<float> table = texel_table(texels);
  for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
    alignas(64) std::int32_t texel[kLanes];
    for (int l = 0; l < kLanes; ++l) texel[l] = (l * 11 + 5) % texels;
    texel[0] = texels - 1;
    texel[kLanes - 1] = 0;
    if (kLanes > 2) texel[1] = texel[2];
    Float out[4];
    simd::load_f32x4(table.data(), Int::load_aligned(texel) * Int(4), path, out);
    for (int c = 0; c < 4; ++c) {
      alignas(64) float value[kLanes];
      out[c].store_aligned(value);
      for (int l = 0; l < kLanes; ++l)
        EXPECT_EQ(value[l], float(4 * texel[l] + c) + 0.25f) << "channel " << c << ", lane " << l;
    }
  }
}

TEST(Gather, F32x4PairGivesEachLaneTwoAdjacentTexels) {
  const int texels = 20;
  const std::vector<float> table = texel_table(texels);
  for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
    alignas(64) std::int32_t texel[kLanes];
    for (int l = 0; l < kLanes; ++l) texel[l] = (l * 7 + 3) % (texels - 1);  // its pair ends at the last texel
    texel[0] = texels - 2;
    Float first[4], second[4];
    simd::load_f32x4_pair(table.data(), Int::load_aligned(texel) * Int(4), path, first, second);
    for (int c = 0; c < 4; ++c) {
      alignas(64) float a[kLanes], b[kLanes];
      first[c].store_aligned(a);
      second[c].store_aligned(b);
      for (int l = 0; l < kLanes; ++l) {
        EXPECT_EQ(a[l], float(4 * texel[l] + c) + 0.25f) << "channel " << c << ", lane " << l;
        EXPECT_EQ(b[l], float(4 * (texel[l] + 1) + c) + 0.25f) << "channel " << c << ", lane " << l;
      }
    }
  }
}

}  // namespace
}  // namespace qdmr
