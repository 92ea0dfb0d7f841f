#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "texture/sampler.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using Lanes = std::array<float, kLanes>;

Float load(const Lanes& a) { return Float::load_unaligned(a.data()); }
Lanes lanes(const Float& f) {
  Lanes a;
  f.store_unaligned(a.data());
  return a;
}
std::uint32_t bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

// t(x, y) = x + w * y.
MipChain ramp_chain(int w, int h) {
  Image img(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y, 0) = float(x + w * y);
  return build_mip_chain(std::move(img), TexturePurpose::Height);
}

// One channel sampled with every lane at the same (u, v, lod); checks all lanes agree and returns lane 0.
float sample1(const MipChain& chain, Filter filter, AddressMode address, float u, float v, float lod, float bias = 0) {
  const SamplerState state{filter, address, bias};
  Float out[4];
  sample(chain, state, Float(u), Float(v), Float(lod), out);
  const Lanes r = lanes(out[0]);
  for (int i = 1; i < kLanes; ++i) EXPECT_EQ(bits(r[i]), bits(r[0]));
  return r[0];
}

TEST(TextureSampler, TwoByTwo) {
  const MipChain c = ramp_chain(2, 2);  // 0 1 / 2 3, then 1.5
  const auto W = AddressMode::Wrap;
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.25f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.75f, 0.25f, 0), 1.0f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.25f, 0.75f, 0), 2.0f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.25f, 0.75f, 0.6f), 1.5f);  // nearest level: 1
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.5f, 0.5f, 0), 1.5f);
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.25f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.0f, 0.25f, 0), 0.5f);  // wraps to texel 1
  EXPECT_EQ(sample1(c, Filter::Bilinear, AddressMode::Clamp, 0.0f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::Bilinear, AddressMode::Mirror, 0.0f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.5f, 0.25f, 0.4f), 0.5f);  // mip point: level 0
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.25f, 0.25f, 0.5f), 0.75f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.25f, 0.25f, 0.25f), 0.375f);
}

TEST(TextureSampler, FourByFour) {
  const MipChain c = ramp_chain(4, 4);  // levels 4x4, (2.5 4.5 / 10.5 12.5), 7.5
  const auto W = AddressMode::Wrap;
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.125f, 0.125f, 0.4f), 0.0f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.125f, 0.125f, 0.6f), 2.5f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.125f, 0.125f, 0.0f, 1.0f), 2.5f);  // bias
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.125f, 0.125f, 10.0f), 7.5f);       // clamped to the last level
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.875f, 0.375f, -5.0f), 7.0f);
  EXPECT_EQ(sample1(c, Filter::Point, W, 0.125f, 0.125f, std::numeric_limits<float>::quiet_NaN()), 7.5f);
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.125f, 0.125f, 1.0f), 5.0f);  // taps wrap on level 1
  EXPECT_EQ(sample1(c, Filter::Bilinear, W, 0.5f, 0.5f, 0.0f), 7.5f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.125f, 0.125f, 1.5f), 6.25f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.125f, 0.125f, 2.0f), 7.5f);
}

TEST(TextureSampler, AddressModes) {
  const MipChain c = ramp_chain(4, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  struct Case {
    AddressMode mode;
    float u, point, bilinear;
  };
  // Row 0 (v = 1/8): texels 0 1 2 3.
  const Case cases[] = {
      {AddressMode::Wrap, -0.25f, 3, 2.5f},   {AddressMode::Wrap, 1.25f, 1, 0.5f},
      {AddressMode::Wrap, 1e4f, 0, 1.5f},     {AddressMode::Wrap, -1e4f + 0.125f, 0, 0},
      {AddressMode::Clamp, -0.25f, 0, 0},     {AddressMode::Clamp, 1.25f, 3, 3},
      {AddressMode::Clamp, 1e4f, 3, 3},       {AddressMode::Clamp, -1e4f, 0, 0},
      {AddressMode::Mirror, -0.25f, 0, 0.5f}, {AddressMode::Mirror, 1.25f, 2, 2.5f},
      {AddressMode::Mirror, 1e4f, 0, 0},      {AddressMode::Mirror, 1.125f, 3, 3},
  };
  for (const Case& k : cases) {
    EXPECT_EQ(sample1(c, Filter::Point, k.mode, k.u, 0.125f, 0), k.point) << int(k.mode) << " u=" << k.u;
    EXPECT_EQ(sample1(c, Filter::Bilinear, k.mode, k.u, 0.125f, 0), k.bilinear) << int(k.mode) << " u=" << k.u;
  }
  // Non-finite coordinates give level-0 texel (0, 0) whatever the filter and LOD; v like u.
  Image marked(4, 4, 1);
  marked.at(0, 0, 0) = 42.0f;
  const MipChain shifted = build_mip_chain(marked, TexturePurpose::Height);
  for (AddressMode m : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
    for (Filter f : {Filter::Point, Filter::Bilinear, Filter::Trilinear})
      for (float bad : {nan, inf, -inf}) {
        EXPECT_EQ(sample1(shifted, f, m, bad, 0.6f, 1.3f), 42.0f);
        EXPECT_EQ(sample1(shifted, f, m, 0.6f, bad, 1.3f), 42.0f);
      }
  EXPECT_EQ(sample1(c, Filter::Point, AddressMode::Wrap, 0.625f, 1e4f + 0.875f, 0), 14.0f);
}

float lod1(const MipChain& c, float dudx, float dvdx, float dudy, float dvdy) {
  const Lanes r = lanes(lod_from_derivatives(c, Float(dudx), Float(dvdx), Float(dudy), Float(dvdy)));
  for (int i = 1; i < kLanes; ++i) EXPECT_EQ(bits(r[i]), bits(r[0]));
  return r[0];
}

TEST(TextureSampler, LodFromDerivatives) {
  const MipChain c = ramp_chain(4, 4);  // 3 levels
  EXPECT_EQ(lod1(c, 0.25f, 0, 0, 0.25f), 0.0f);
  EXPECT_EQ(lod1(c, 1.0f, 0, 0, 0.25f), 2.0f);
  EXPECT_EQ(lod1(c, 0, 0, 0, 2.0f), 3.0f);
  EXPECT_EQ(lod1(c, 1.0f / 16, 0, 0, 0), -2.0f);
  EXPECT_EQ(lod1(c, 0, -1.0f / 1024, 0, 0), -8.0f);
  EXPECT_NEAR(lod1(c, 0.75f, 1.0f, 0, 0), std::log2(5.0), 1e-6);       // texels (3, 4)
  EXPECT_EQ(lod1(c, 0, 0, 0, 0), -64.0f);
  EXPECT_EQ(lod1(c, 1e-30f, 0, 0, 0), -64.0f);  // underflows
  EXPECT_EQ(lod1(c, std::numeric_limits<float>::infinity(), 0, 0, 0), 2.0f);
  EXPECT_EQ(lod1(c, 0, 0, std::numeric_limits<float>::quiet_NaN(), 0), 2.0f);
  EXPECT_EQ(lod1(c, 1e30f, 0, 0, 0), 2.0f);  // overflows

  // Against std::log2 in double: |error| <= 4e-6 over 2^-40 .. 2^40 texel footprints.
  const MipChain big = ramp_chain(256, 128);
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-48, 32);
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const float d[4] = {std::ldexp(mantissa(rng), exponent(rng)), std::ldexp(mantissa(rng), exponent(rng)),
                        std::ldexp(mantissa(rng), exponent(rng)), std::ldexp(mantissa(rng), exponent(rng))};
    const float ax = d[0] * 256, ay = d[1] * 128, bx = d[2] * 256, by = d[3] * 128;
    const float rho2 = std::max(ax * ax + ay * ay, bx * bx + by * by);
    if (rho2 < 1.17549435e-38f) continue;
    const double expected = 0.5 * std::log2(double(rho2));
    worst = std::max(worst, std::abs(lod1(big, d[0], d[1], d[2], d[3]) - expected));
  }
  EXPECT_LE(worst, 4e-6);
}

// Lane i of a mixed batch gives the same bits as a batch holding lane i's inputs in every lane.
TEST(TextureSampler, LanesIndependent) {
  Image img(37, 20, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (float& t : img.texels) t = unit(rng);
  const MipChain chain = build_mip_chain(std::move(img), TexturePurpose::Albedo);
  std::uniform_real_distribution<float> coord(-3.0f, 4.0f), lod(-1.0f, 7.0f), deriv(-0.2f, 0.2f);
  for (Filter f : {Filter::Point, Filter::Bilinear, Filter::Trilinear})
    for (AddressMode m : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
      for (int round = 0; round < 50; ++round) {
        Lanes u, v, l, dx, dy;
        for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng), dx[i] = deriv(rng), dy[i] = deriv(rng);
        u[0] = round % 2 ? std::numeric_limits<float>::quiet_NaN() : u[0];
        const SamplerState state{f, m, 0.25f};
        Float out[4];
        sample(chain, state, load(u), load(v), load(l), out);
        const Lanes lods = lanes(lod_from_derivatives(chain, load(dx), load(dy), load(dy), load(dx)));
        for (int i = 0; i < kLanes; ++i) {
          Float one[4];
          sample(chain, state, Float(u[i]), Float(v[i]), Float(l[i]), one);
          for (int c = 0; c < 3; ++c) ASSERT_EQ(bits(lanes(out[c])[i]), bits(lanes(one[c])[0])) << i;
          const Float lod_i = lod_from_derivatives(chain, Float(dx[i]), Float(dy[i]), Float(dy[i]), Float(dx[i]));
          ASSERT_EQ(bits(lods[i]), bits(lanes(lod_i)[0]));
        }
      }
}

}  // namespace
}  // namespace qdmr
