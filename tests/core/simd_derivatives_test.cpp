// Screen-space derivatives within 2x2 quads (lanes 0 1 / 2 3 of each quad): coarse ones broadcast one difference
// to the quad, fine ones take each pixel's own row or column. Checked lane by lane against their definition,
// bit for bit, on values whose differences round.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>

#include "core/simd.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;

std::uint32_t bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

TEST(SimdDerivatives, QuadAndPixelDifferencesMatchTheirDefinition) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(-1000.0f, 1000.0f);
  for (int round = 0; round < 64; ++round) {
    alignas(64) float v[kLanes], ddx[kLanes], ddy[kLanes], fine_x[kLanes], fine_y[kLanes];
    for (float& x : v) x = value(rng);
    const Float batch = Float::load_aligned(v);
    simd::quad_ddx(batch).store_aligned(ddx);
    simd::quad_ddy(batch).store_aligned(ddy);
    simd::pixel_ddx(batch).store_aligned(fine_x);
    simd::pixel_ddy(batch).store_aligned(fine_y);
    for (int l = 0; l < kLanes; ++l) {
      const float* q = v + l / 4 * 4;  // the lane's quad: top-left, top-right, bottom-left, bottom-right
      const int corner = l % 4, row = corner / 2, column = corner % 2;
      ASSERT_EQ(bits(ddx[l]), bits(q[1] - q[0])) << "lane " << l;
      ASSERT_EQ(bits(ddy[l]), bits(q[2] - q[0])) << "lane " << l;
      ASSERT_EQ(bits(fine_x[l]), bits(q[2 * row + 1] - q[2 * row])) << "lane " << l;
      ASSERT_EQ(bits(fine_y[l]), bits(q[2 + column] - q[column])) << "lane " << l;
    }
  }
}

}  // namespace
}  // namespace qdmr
