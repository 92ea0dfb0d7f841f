// Math modes in the sampler (docs/sampling.md, "Math modes"): the texel coordinate u * size is floored as
// computed in fp32 (sm3) or exactly (sm4, exact). On a size that is not a power of two, a u whose fp32 product
// rounds up onto a texel edge makes sm3 read the next texel; on power-of-two sizes the fp32 product is exact and
// every mode reads the same texels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "kernel/sampler.hpp"
#include "texture/sampler_test_util.hpp"

namespace qdmr {
namespace {

using simd::Float;
using namespace test;

// An n x 1 R32F texture whose texel i holds i.
Texture ramp(int n) {
  Image img(n, 1, 1);
  for (int i = 0; i < n; ++i) img.texels[std::size_t(i)] = float(i);
  return make_mip_texture(img, TexelFormat::R32F, false, MipReduce::Box);
}

float sample_at(const TextureView& view, Filter filter, MathMode math, SamplePrecision precision, float u) {
  SamplingDesc d;
  d.filter = filter;
  d.math = math;
  d.precision = precision;
  Float out[4];
  sample(view, test::sampler_state(d), Float(u), Float(0.5f), Float(0.0f), out);
  float lanes[simd::kLanes];
  out[0].store_unaligned(lanes);
  return lanes[0];
}

// A float u within a few floats of a texel edge k / n whose fp32 product with n rounds up to k: the exact texel
// coordinate is below the edge k, the fp32 one on it. -1 when none of the edges has one.
float edge_rounding_up(int n) {
  for (int k = 1; k < n; ++k) {
    float u = float(k) / float(n);
    for (int i = 0; i < 4; ++i) u = std::nextafter(u, 2.0f);
    for (int i = 0; i < 8; ++i, u = std::nextafter(u, 0.0f))
      if (u * float(n) == float(k) && double(u) * n < k) return u;
  }
  return -1.0f;
}

TEST(SamplerMathModes, Fp32AddressingReadsTheNextTexelWhereTheExactCoordinateIsBelowAnEdge) {
  EXPECT_EQ(edge_rounding_up(3), -1.0f);  // too few edges to have one
  for (int n : {22, 999, 1000, 16383}) {
    const float u = edge_rounding_up(n);
    ASSERT_GT(u, 0.0f) << n;
    const double k = std::floor(double(u) * n) + 1.0;  // the edge the fp32 product lands on
    const Texture texture = ramp(n);
    const TextureView view(texture);
    EXPECT_EQ(sample_at(view, Filter::Point, MathMode::Sm3, SamplePrecision::Exact, u), k) << n;
    EXPECT_EQ(sample_at(view, Filter::Point, MathMode::Sm4, SamplePrecision::Exact, u), k - 1) << n;
    EXPECT_EQ(sample_at(view, Filter::Point, MathMode::Exact, SamplePrecision::Exact, u), k - 1) << n;
    // hw8: the fixed-point coordinate k * 256 of sm3 against k * 256 - 1 (texel k - 1) of the exact one.
    EXPECT_EQ(sample_at(view, Filter::Point, MathMode::Sm3, SamplePrecision::Hw8, u), k) << n;
    EXPECT_EQ(sample_at(view, Filter::Point, MathMode::Sm4, SamplePrecision::Hw8, u), k - 1) << n;
  }
}

TEST(SamplerMathModes, EveryModeReadsTheSameTexelsOnPowerOfTwoSizes) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int n : {1, 2, 64, 1024, 16384}) {
    const Texture texture = ramp(n);
    const TextureView view(texture);
    for (int i = 0; i < 2000; ++i) {
      const float u = i % 2 ? unit(rng) : std::nextafter(float(i % n) / float(n), i % 4 == 0 ? 0.0f : 2.0f);
      for (Filter filter : {Filter::Point, Filter::Bilinear})
        for (SamplePrecision precision : kPrecisions) {
          const float sm4 = sample_at(view, filter, MathMode::Sm4, precision, u);
          ASSERT_EQ(bits(sample_at(view, filter, MathMode::Sm3, precision, u)), bits(sm4)) << n << " " << u;
          ASSERT_EQ(bits(sample_at(view, filter, MathMode::Exact, precision, u)), bits(sm4)) << n << " " << u;
        }
    }
  }
}

TEST(SamplerMathModes, Sm4AndExactAgreeEverywhere) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> wide(-3.0f, 4.0f);
  for (int n : {3, 22, 1000, 16383}) {
    const Texture texture = ramp(n);
    const TextureView view(texture);
    for (int i = 0; i < 2000; ++i) {
      const float u = i % 2 ? wide(rng) : std::nextafter(float(i) / float(n), i % 4 == 0 ? 0.0f : 2.0f);
      for (Filter filter : {Filter::Point, Filter::Bilinear})
        for (SamplePrecision precision : kPrecisions)
          ASSERT_EQ(bits(sample_at(view, filter, MathMode::Exact, precision, u)),
                    bits(sample_at(view, filter, MathMode::Sm4, precision, u)))
              << n << " " << u;
    }
  }
}

}  // namespace
}  // namespace qdmr
