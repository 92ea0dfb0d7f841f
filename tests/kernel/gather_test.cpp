// core/gather.hpp's per-lane loads of texels of 4 floats, on both fetch paths of the build these tests are compiled
// for (the AVX2 kernel, and the AVX-512 one in qdmr_avx512_tests: their transposes, and the portable lane-by-lane
// loop).
#include <gtest/gtest.h>

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
