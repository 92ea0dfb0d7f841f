// kernel/quad_rows.hpp: a batch's lanes to and from the two framebuffer rows it covers (lane 4q + 2r + c is pixel
// (2q + c, r)), the shuffles of the build these tests are compiled for: the AVX2 kernel (qdmr_tests) and the
// AVX-512 one (qdmr_avx512_tests, where the CPU has it); the SSE4.2 version is covered by golden.shipped_scenes,
// which renders with every kernel the CPU runs.
#include <gtest/gtest.h>

#include <vector>

#include "kernel/quad_rows.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;

constexpr int kRowPixels = kLanes / 2;

TEST(QuadRows, LoadGivesEachLaneItsPixel) {
  // Rows inside a wider buffer at an odd offset: the loads are unaligned and read no pixel outside the batch.
  std::vector<float> buffer(3 + 2 * 40, -1.0f);
  float* row0 = buffer.data() + 3;
  float* row1 = row0 + 40;
  for (int x = 0; x < kRowPixels; ++x) {
    row0[x] = float(100 + x);
    row1[x] = float(200 + x);
  }
  alignas(64) float lanes[kLanes];
  simd::load_quad_rows(row0, row1).store_aligned(lanes);
  for (int l = 0; l < kLanes; ++l) {
    const int q = l / 4, r = (l % 4) / 2, c = l % 2;
    EXPECT_EQ(lanes[l], float((r == 0 ? 100 : 200) + 2 * q + c)) << "lane " << l;
  }
}

TEST(QuadRows, StoreWritesEachLaneToItsPixelAndNothingElse) {
  std::vector<float> buffer(3 + 2 * 40, -1.0f);
  float* row0 = buffer.data() + 3;
  float* row1 = row0 + 40;
  alignas(64) float lanes[kLanes];
  for (int l = 0; l < kLanes; ++l) lanes[l] = float(l);
  simd::store_quad_rows(Float::load_aligned(lanes), row0, row1);
  for (int l = 0; l < kLanes; ++l) {
    const int q = l / 4, r = (l % 4) / 2, c = l % 2;
    EXPECT_EQ((r == 0 ? row0 : row1)[2 * q + c], float(l)) << "lane " << l;
  }
  int untouched = 0;
  for (float v : buffer) untouched += v == -1.0f;
  EXPECT_EQ(untouched, int(buffer.size()) - kLanes);
  // And back: the load of what was stored gives the lanes.
  alignas(64) float again[kLanes];
  simd::load_quad_rows(row0, row1).store_aligned(again);
  for (int l = 0; l < kLanes; ++l) EXPECT_EQ(again[l], lanes[l]);
}

TEST(QuadRows, RgbStoreWritesEachLanesThreeChannelsToItsPixelAndNothingElse) {
  // Two rows of interleaved RGB at an odd float offset (unaligned stores), with guard values around them.
  constexpr int kStride = 3 * 40;
  std::vector<float> buffer(5 + 2 * kStride, -1.0f);
  float* row0 = buffer.data() + 5;
  float* row1 = row0 + kStride;
  alignas(64) float lanes[3][kLanes];
  for (int c = 0; c < 3; ++c)
    for (int l = 0; l < kLanes; ++l) lanes[c][l] = float(100 * c + l);
  simd::store_quad_rows_rgb(Float::load_aligned(lanes[0]), Float::load_aligned(lanes[1]),
                            Float::load_aligned(lanes[2]), row0, row1);
  for (int l = 0; l < kLanes; ++l) {
    const int q = l / 4, r = (l % 4) / 2, x = 2 * q + l % 2;
    for (int c = 0; c < 3; ++c) EXPECT_EQ((r == 0 ? row0 : row1)[3 * x + c], lanes[c][l]) << "lane " << l << " channel " << c;
  }
  int untouched = 0;
  for (float v : buffer) untouched += v == -1.0f;
  EXPECT_EQ(untouched, int(buffer.size()) - 3 * kLanes);
}

}  // namespace
}  // namespace qdmr
