// core/det_math.hpp: pow_uniform raises to a whole exponent by products (pow_whole) and to any other by
// exp2(y log2 x); a lane of a batch gives exactly the scalar result, and pow_whole stays within its error bound.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "core/det_math.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

using simd::Float;
using simd::kLanes;

std::array<float, kLanes> lanes(const Float& f) {
  std::array<float, kLanes> a;
  f.store_unaligned(a.data());
  return a;
}

TEST(DetMath, PowWholeIsWithinItsRoundingsOfTheExactPowerAndLanesMatchTheScalar) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const unsigned n : {1u, 2u, 3u, 5u, 8u, 16u, 17u, 32u, 64u, 100u, 255u, 1024u}) {
    for (int round = 0; round < 200; ++round) {
      std::array<float, kLanes> x;
      for (float& v : x) v = unit(rng) * (round % 2 ? 1.0f : 1.5f);
      const std::array<float, kLanes> got = lanes(detmath::pow_whole(Float::load_unaligned(x.data()), n));
      for (int l = 0; l < kLanes; ++l) {
        const float scalar = detmath::pow_whole(x[std::size_t(l)], n);
        ASSERT_EQ(std::bit_cast<std::uint32_t>(got[std::size_t(l)]), std::bit_cast<std::uint32_t>(scalar)) << n;
        const double exact = std::pow(double(x[std::size_t(l)]), double(n));
        // Relative error bound of n - 1 roundings (2^-24 each, first order; 1 % for the higher orders), only
        // where the result is a normal float: below 2^-126 the absolute rounding of subnormals dominates.
        if (exact < 1e-37 || exact > 1e37) continue;
        EXPECT_LE(std::abs(double(scalar) - exact), exact * double(n - 1) * 0x1p-24 * 1.01) << x[std::size_t(l)] << "^" << n;
      }
    }
  }
}

TEST(DetMath, PowUniformTakesProductsOnlyForWholeExponentsUpToItsLimit) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::array<float, 8> xs = {0.0f, -0.5f, nan, 1e-3f, 0.3f, 0.999f, 1.0f, 1.7f};
  for (const float y : {1.0f, 4.0f, 32.0f, 1024.0f, 0.5f, 2.5f, 1025.0f, 0.0f, 1e9f}) {
    for (const float x : xs) {
      const float got = lanes(detmath::pow_uniform(Float(x), y))[0];
      const float scalar = detmath::pow_uniform(x, y);
      EXPECT_EQ(std::bit_cast<std::uint32_t>(got), std::bit_cast<std::uint32_t>(scalar)) << x << "^" << y;
      // x NaN or <= 0 gives 0 on both paths, as pow's; whole y in [1, 1024] by products, any other y by pow.
      const bool whole = y >= 1.0f && y <= detmath::kMaxProductExponent && y == std::floor(y);
      const float expected = !(x > 0.0f) ? 0.0f : whole ? detmath::pow_whole(x, unsigned(y)) : detmath::pow(x, y);
      EXPECT_EQ(std::bit_cast<std::uint32_t>(scalar), std::bit_cast<std::uint32_t>(expected)) << x << "^" << y;
    }
  }
}

}  // namespace
}  // namespace qdmr::QDMR_ISA_NAMESPACE
