#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "qdmr/program/program_key.hpp"
#include "texture/twin_texels.hpp"
#include "kernel/height_surface.hpp"
#include "kernel/sampler.hpp"
#include "kernel/trace_ray.hpp"
#include "texture/sampler_test_util.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using namespace test;

Float load(const Lanes& a) { return Float::load_unaligned(a.data()); }
Lanes lanes(const Float& f) {
  Lanes a;
  f.store_unaligned(a.data());
  return a;
}


SamplerState state_of(Filter filter, AddressMode address, float bias = 0, SamplePrecision p = SamplePrecision::Exact) {
  SamplerState s;
  s.filter = filter;
  s.address = address;
  s.lod_bias = bias;
  s.precision = p;
  return s;
}

// t(x, y) = x + w * y, stored as R32F so values are exact; box mips.
Texture ramp_chain(int w, int h) {
  Image img(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y, 0) = float(x + w * y);
  return make_mip_texture(img, TexelFormat::R32F, false, MipReduce::Box);
}

// One channel sampled with every lane at the same (u, v, lod); checks all lanes agree and returns lane 0.
float sample1(const Texture& texture, Filter filter, AddressMode address, float u, float v, float lod, float bias = 0,
              SamplePrecision precision = SamplePrecision::Exact) {
  const SamplerState state = state_of(filter, address, bias, precision);
  Float out[4];
  sample(TextureView(texture), state, Float(u), Float(v), Float(lod), out);
  const Lanes r = lanes(out[0]);
  for (int i = 1; i < kLanes; ++i) EXPECT_EQ(bits(r[i]), bits(r[0]));
  return r[0];
}

TEST(TextureSampler, TwoByTwo) {
  const Texture c = ramp_chain(2, 2);  // 0 1 / 2 3, then 1.5
  const auto W = AddressMode::Wrap;
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.25f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.75f, 0.25f, 0), 1.0f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.25f, 0.75f, 0), 2.0f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.25f, 0.75f, 0.6f), 1.5f);  // nearest level: 1
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.5f, 0.5f, 0), 1.5f);
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.25f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.0f, 0.25f, 0), 0.5f);  // wraps to texel 1
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, AddressMode::Clamp, 0.0f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, AddressMode::Mirror, 0.0f, 0.25f, 0), 0.0f);
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.5f, 0.25f, 0.4f), 0.5f);  // mip point: level 0
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.25f, 0.25f, 0.5f), 0.75f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.25f, 0.25f, 0.25f), 0.375f);
}

TEST(TextureSampler, FourByFour) {
  const Texture c = ramp_chain(4, 4);  // levels 4x4, (2.5 4.5 / 10.5 12.5), 7.5
  const auto W = AddressMode::Wrap;
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.125f, 0.125f, 0.4f), 0.0f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.125f, 0.125f, 0.6f), 2.5f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.125f, 0.125f, 0.0f, 1.0f), 2.5f);  // bias
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.125f, 0.125f, 10.0f), 7.5f);       // clamped to the last level
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.875f, 0.375f, -5.0f), 7.0f);
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, W, 0.125f, 0.125f, std::numeric_limits<float>::quiet_NaN()), 7.5f);
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.125f, 0.125f, 1.0f), 5.0f);  // taps wrap on level 1
  EXPECT_EQ(sample1(c, Filter::LinearMipPoint, W, 0.5f, 0.5f, 0.0f), 7.5f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.125f, 0.125f, 1.5f), 6.25f);
  EXPECT_EQ(sample1(c, Filter::Trilinear, W, 0.125f, 0.125f, 2.0f), 7.5f);
}

TEST(TextureSampler, AddressModes) {
  const Texture c = ramp_chain(4, 4);
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
    EXPECT_EQ(sample1(c, Filter::PointMipPoint, k.mode, k.u, 0.125f, 0), k.point) << int(k.mode) << " u=" << k.u;
    EXPECT_EQ(sample1(c, Filter::LinearMipPoint, k.mode, k.u, 0.125f, 0), k.bilinear) << int(k.mode) << " u=" << k.u;
  }
  // Non-finite coordinates give level-0 texel (0, 0) whatever the filter and LOD; v like u.
  Image marked(4, 4, 1);
  marked.at(0, 0, 0) = 42.0f;
  const Texture shifted = make_mip_texture(marked, TexelFormat::R32F, false, MipReduce::Box);
  for (AddressMode m : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
    for (Filter f : kFilters)
      for (float bad : {nan, inf, -inf}) {
        EXPECT_EQ(sample1(shifted, f, m, bad, 0.6f, 1.3f), 42.0f);
        EXPECT_EQ(sample1(shifted, f, m, 0.6f, bad, 1.3f), 42.0f);
      }
  EXPECT_EQ(sample1(c, Filter::PointMipPoint, AddressMode::Wrap, 0.625f, 1e4f + 0.875f, 0), 14.0f);
}

float lod1(const Texture& c, float dudx, float dvdx, float dudy, float dvdy) {
  const Lanes r = lanes(lod_from_derivatives(TextureView(c), Float(dudx), Float(dvdx), Float(dudy), Float(dvdy)));
  for (int i = 1; i < kLanes; ++i) EXPECT_EQ(bits(r[i]), bits(r[0]));
  return r[0];
}

TEST(TextureSampler, LodFromDerivatives) {
  const Texture c = ramp_chain(4, 4);  // 3 levels
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
  const Texture big = ramp_chain(256, 128);
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
  const Texture texture = make_mip_texture(img, TexelFormat::RGBA8, true, MipReduce::Box);
  const TextureView chain(texture);
  std::uniform_real_distribution<float> coord(-3.0f, 4.0f), lod(-1.0f, 7.0f), deriv(-0.2f, 0.2f);
  for (Filter f : kFilters)
    for (AddressMode m : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
      for (int round = 0; round < 50; ++round) {
        Lanes u, v, l, dx, dy;
        for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng), dx[i] = deriv(rng), dy[i] = deriv(rng);
        u[0] = round % 2 ? std::numeric_limits<float>::quiet_NaN() : u[0];
        const SamplerState state = state_of(f, m, 0.25f, SamplePrecision(round % 3));
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

namespace qdmr {
namespace {

TEST(TextureSampler, LevelZeroFiltersIgnoreLod) {
  const Texture c = ramp_chain(4, 4);
  for (float lod : {-3.0f, 0.0f, 1.7f, 9.0f}) {
    EXPECT_EQ(sample1(c, Filter::Point, AddressMode::Wrap, 0.375f, 0.625f, lod), 9.0f);      // texel (1, 2)
    EXPECT_EQ(sample1(c, Filter::Bilinear, AddressMode::Wrap, 0.5f, 0.625f, lod), 9.5f);     // between (1,2) and (2,2)
  }
}

TEST(TextureSampler, PointMipLinearBlendsNearestTexelsOfTwoLevels) {
  const Texture c = ramp_chain(4, 4);  // level 1 texel (0,0) = 2.5
  EXPECT_EQ(sample1(c, Filter::PointMipLinear, AddressMode::Wrap, 0.125f, 0.125f, 0.5f), 1.25f);
  EXPECT_EQ(sample1(c, Filter::PointMipLinear, AddressMode::Wrap, 0.125f, 0.125f, 0.25f), 0.625f);
}

TEST(TextureSampler, HardwarePrecisionQuantisesWeightsAndLodFraction) {
  const Texture c = ramp_chain(4, 1);  // 0 1 2 3
  // u = 0.3 -> p = 0.7 texels past texel 0's centre: exact weight 0.7; hw8 keeps floor(0.7 * 256) / 256.
  const float u = 0.3f, v = 0.5f;
  const float exact = sample1(c, Filter::Bilinear, AddressMode::Clamp, u, v, 0);
  const float hw8 = sample1(c, Filter::Bilinear, AddressMode::Clamp, u, v, 0, 0, SamplePrecision::Hw8);
  const float hw6 = sample1(c, Filter::Bilinear, AddressMode::Clamp, u, v, 0, 0, SamplePrecision::Hw6);
  const float p = 0.3f * 4.0f - 0.5f;
  EXPECT_EQ(exact, p);
  EXPECT_EQ(hw8, std::floor(p * 256.0f) / 256.0f);
  EXPECT_EQ(hw6, std::floor(p * 64.0f) / 64.0f);
  // LOD fraction: 0.3 -> 76/256 (hw8), 19/64 (hw6); a 2x2-texel ramp makes the blend visible.
  const Texture r = ramp_chain(2, 2);  // level 1: 1.5
  const float lod = 0.3f;
  EXPECT_EQ(sample1(r, Filter::Trilinear, AddressMode::Wrap, 0.25f, 0.25f, lod, 0, SamplePrecision::Hw8),
            0.0f + 1.5f * (std::floor(lod * 256.0f) / 256.0f));
  EXPECT_EQ(sample1(r, Filter::Trilinear, AddressMode::Wrap, 0.25f, 0.25f, lod, 0, SamplePrecision::Hw6),
            0.0f + 1.5f * (std::floor(lod * 64.0f) / 64.0f));
}

TEST(TextureSampler, LodClampsApply) {
  const Texture c = ramp_chain(4, 4);  // levels: 4x4, 2x2, 1x1 (7.5)
  SamplerState s = state_of(Filter::PointMipPoint, AddressMode::Wrap);
  s.min_lod = 2.0f;
  Float out[4];
  sample(TextureView(c), s, Float(0.1f), Float(0.1f), Float(0.0f), out);
  EXPECT_EQ(lanes(out[0])[0], 7.5f);
  s.min_lod = 0.0f;
  s.max_lod = 0.0f;
  sample(TextureView(c), s, Float(0.1f), Float(0.1f), Float(5.0f), out);
  EXPECT_EQ(lanes(out[0])[0], 0.0f);
}

TEST(TextureSampler, GatherAndPortableFetchGiveTheSameBits) {
  if (!simd::kHasHardwareGather) GTEST_SKIP() << "this build has no hardware gather (SSE4.2): only the portable path exists";
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-2.0f, 3.0f), lod(-1.0f, 9.0f);
  for (TexelFormat format : {TexelFormat::R8, TexelFormat::RG8, TexelFormat::RGBA8, TexelFormat::R16, TexelFormat::R32F}) {
    Image img(61, 35, channel_count(format));
    for (float& t : img.texels) t = unit(rng);
    const Texture texture = make_mip_texture(img, format, format == TexelFormat::RGBA8, MipReduce::Box);
    const TextureView view(texture);
    for (Filter f : kFilters)
      for (int round = 0; round < 20; ++round) {
        Lanes u, v, l;
        for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng);
        SamplerState gather = state_of(f, AddressMode(round % 3), 0, SamplePrecision(round % 3));
        SamplerState portable = gather;
        gather.fetch = simd::FetchPath::Gather;
        portable.fetch = simd::FetchPath::Portable;
        Float a[4], b[4];
        sample(view, gather, load(u), load(v), load(l), a);
        sample(view, portable, load(u), load(v), load(l), b);
        for (int c = 0; c < texture.channels(); ++c)
          for (int i = 0; i < kLanes; ++i) ASSERT_EQ(bits(lanes(a[c])[i]), bits(lanes(b[c])[i]));
      }
  }
}

// Where no lane weighs a mip-linear sample's coarse level (every lane's LOD fraction 0: magnified, at a whole LOD,
// or past the last level), the sampler skips that level for the unorm formats (sampling_code.hpp,
// coarse_level_weightless). The skip must keep the bits: each batch is sampled once with every lane at such a LOD
// and once more with lane 0 alone at a fractional LOD, which makes the batch fetch both levels; lanes 1.. must agree.
// Every format (R32F never skips, and holds -0, infinities and NaN here), sRGB with and without the decoded copy,
// every address mode, exact and 8-bit precision.
TEST(TextureSampler, SkippingAWeightlessCoarseLevelKeepsTheBits) {
  if (kLanes < 2) GTEST_SKIP() << "needs a second lane";
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-1.5f, 2.5f);
  struct Case {
    TexelFormat format;
    bool srgb, decoded_copy;
  };
  const Case cases[] = {{TexelFormat::R8, false, false},   {TexelFormat::RG8, false, false},
                        {TexelFormat::RGBA8, false, false}, {TexelFormat::RGBA8, true, false},
                        {TexelFormat::RGBA8, true, true},   {TexelFormat::R16, false, false},
                        {TexelFormat::R32F, false, false}};
  const float whole_lods[] = {-3.0f, -0.25f, 0.0f, 1.0f, 2.0f, 5.0f, 40.0f};  // 40: past the last level (5)
  for (const Case& c : cases) {
    Image img(32, 32, channel_count(c.format));
    for (float& t : img.texels) t = unit(rng);
    if (c.format == TexelFormat::R32F) {  // values a skipped level could not reproduce if R32F skipped
      img.texels[5] = -0.0f;
      img.texels[40] = std::numeric_limits<float>::infinity();
      img.texels[77] = std::numeric_limits<float>::quiet_NaN();
    }
    Texture texture = make_mip_texture(img, c.format, c.srgb, MipReduce::Box);
    if (c.decoded_copy) add_linear_copy(texture);
    const TextureView view(texture);
    for (const Filter filter : {Filter::Trilinear, Filter::PointMipLinear})
      for (const AddressMode address : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
        for (const SamplePrecision precision : {SamplePrecision::Exact, SamplePrecision::Hw8})
          for (int round = 0; round < 40; ++round) {
            Lanes u, v, lod;
            for (int i = 0; i < kLanes; ++i) {
              u[i] = coord(rng);
              v[i] = coord(rng);
              lod[i] = whole_lods[std::size_t(round + i) % std::size(whole_lods)];
            }
            const SamplerState state = state_of(filter, address, 0.0f, precision);
            Float skipped[4], both[4];
            sample(view, state, load(u), load(v), load(lod), skipped);
            lod[0] = 0.5f;
            sample(view, state, load(u), load(v), load(lod), both);
            for (int ch = 0; ch < texture.channels(); ++ch) {
              const Lanes a = lanes(skipped[ch]), b = lanes(both[ch]);
              for (int i = 1; i < kLanes; ++i)
                ASSERT_EQ(bits(a[std::size_t(i)]), bits(b[std::size_t(i)]))
                    << "format " << int(c.format) << " srgb " << c.srgb << " copy " << c.decoded_copy << " filter "
                    << int(filter) << " lane " << i << " lod " << lod[std::size_t(i)];
            }
          }
  }
}

// Bilinear taps come two per load where a row's pair is adjacent in memory (sampling_code.hpp, fetch_pair: 4 bytes
// for texels of 1 or 2 bytes, 8 for texels of 4); they must give the bits of fp32 textures holding the same decoded
// values, one per channel, which are fetched one texel at a time: at random points, with lanes at the wrap and
// clamp edges mixed into the batch, on both fetch paths.
TEST(TextureSampler, PairedTexelLoadsGiveTheBitsOfSingleLoads) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coord(-1.5f, 2.5f), lod(-1.0f, 6.0f);
  const std::pair<TexelFormat, bool> formats[] = {{TexelFormat::R8, false},    {TexelFormat::R16, false},
                                                  {TexelFormat::RG8, false},   {TexelFormat::RGBA8, false},
                                                  {TexelFormat::RGBA8, true},  {TexelFormat::R32F, false}};
  for (const auto& [format, srgb] : formats) {
    const int channels = channel_count(format);
    Image codes(32, 16, channels);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 32; ++x)
        for (int c = 0; c < channels; ++c) codes.at(x, y, c) = float((x * 977 + y * 131 + c * 61) % 256) / 255.0f;
    const Texture narrow = make_mip_texture(codes, format, srgb, MipReduce::Box);
    std::vector<Texture> wide;  // bilinear reads level 0 only
    for (int c = 0; c < channels; ++c) {
      Image decoded(32, 16, 1);
      for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) decoded.at(x, y, 0) = narrow.texel(0, x, y, c);
      wide.push_back(make_mip_texture(decoded, TexelFormat::R32F, false, MipReduce::Box));
    }
    for (const AddressMode address : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
      for (int round = 0; round < 200; ++round) {
        Lanes u, v, l;
        for (int i = 0; i < kLanes; ++i) {
          u[i] = round % 4 == 0 && i == 0 ? 31.75f / 32.0f : coord(rng);  // a lane whose right tap wraps or clamps
          v[i] = coord(rng);
          l[i] = lod(rng);
        }
        SamplerState state = state_of(Filter::Bilinear, address, 0, SamplePrecision(round % 3));
        state.fetch = round % 2 == 0 ? simd::FetchPath::Gather : simd::FetchPath::Portable;
        Float a[4];
        sample(TextureView(narrow), state, load(u), load(v), load(l), a);
        for (int c = 0; c < channels; ++c) {
          Float b[4];
          sample(TextureView(wide[std::size_t(c)]), state, load(u), load(v), load(l), b);
          for (int i = 0; i < kLanes; ++i)
            ASSERT_EQ(bits(lanes(a[c])[i]), bits(lanes(b[0])[i]))
                << "format " << int(format) << " srgb " << srgb << " channel " << c << " u " << u[i] << " v " << v[i];
        }
      }
  }
}

// Every filter, address mode, precision, math mode (sm4, sm3) and fetch path this build has, LOD bias 0.25.
std::vector<SamplerState> every_sampler_state() {
  std::vector<SamplerState> states;
  for (Filter f : kFilters)
    for (AddressMode m : kAddressModes)
      for (SamplePrecision p : kPrecisions)
        for (MathMode math : {MathMode::Sm4, MathMode::Sm3})
          for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
            if (path == simd::FetchPath::Gather && !simd::kHasHardwareGather) continue;
            SamplerState state = state_of(f, m, 0.25f, p);
            state.math = math;
            state.fetch = path;
            states.push_back(state);
          }
  return states;
}

// An RGBA8 sRGB chain keeps a decoded copy (Texture::linear) that the sampler reads whole texels from; sampling
// with it must give the bits of the per-channel table decode, for every filter, address mode, precision, math mode
// and fetch path, specialised and generic, with non-finite coordinates and lanes at the wrap and clamp edges.
// The decoded copy (Texture::linear) of an sRGB colour texture and of R16 and R8 heights gives the bits of the
// per-fetch decode, through every sampler, the generic sampler and texel loads on every level.
TEST(TextureSampler, TheDecodedCopyGivesThePerFetchDecodesBits) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-3.0f, 4.0f), lod(-1.0f, 9.0f);
  std::uniform_int_distribution<int> index(-70, 70);
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::RGBA8, false), 0u);
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::R8, true), 0u);
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::RG8, false), 0u);
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::R32F, false), 0u);
  EXPECT_EQ(linear_copy_bytes(8192, 8192, TexelFormat::RGBA8, true), 0u) << "above kLinearCopyMaxBytes";
  EXPECT_EQ(linear_copy_bytes(16384, 16384, TexelFormat::R16, false), 0u) << "above kLinearCopyMaxBytes";
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::R16, false), 2 * mip_chain_bytes(64, 32, TexelFormat::R16));
  EXPECT_EQ(linear_copy_bytes(64, 32, TexelFormat::R8, false), 4 * mip_chain_bytes(64, 32, TexelFormat::R8));
  struct Case {
    TexelFormat format;
    bool srgb;
  };
  for (const Case& format : {Case{TexelFormat::RGBA8, true}, Case{TexelFormat::R16, false}, Case{TexelFormat::R8, false}}) {
    const std::string name = format_name(format.format);
    Image img(64, 32, channel_count(format.format));
    for (float& t : img.texels) t = unit(rng);
    const Texture decoded_per_fetch = make_mip_texture(img, format.format, format.srgb, MipReduce::Max);
    Texture copied = decoded_per_fetch;
    add_linear_copy(copied);
    ASSERT_EQ(copied.linear.size(),
              copied.storage.size() / bytes_per_texel(format.format) * std::size_t(copied.channels())) << name;
    EXPECT_EQ(copied.bytes(), linear_copy_bytes(64, 32, format.format, format.srgb) + copied.storage.size()) << name;
    for (const SamplerState& state : every_sampler_state()) {
      const Filter f = state.filter;
      const TextureSampler with_decode(decoded_per_fetch, state), with_copy(copied, state);
      for (int round = 0; round < 16; ++round) {
        Lanes u, v, l;
        for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng);
        if (round == 0) u[1] = kNaN, v[2] = -kInf, l[3] = kNaN;
        if (round % 2 == 1)  // every lane inside one row pair: the paired loads run for the whole batch
          for (int i = 0; i < kLanes; ++i) u[i] = 0.25f + 0.01f * float(i), v[i] = 0.5f + 0.02f * float(i);
        Float a[4], b[4], c[4];
        with_decode.sample(load(u), load(v), load(l), a);
        with_copy.sample(load(u), load(v), load(l), b);
        sample(with_copy.view(), state, load(u), load(v), load(l), c);
        for (int ch = 0; ch < copied.channels(); ++ch)
          for (int i = 0; i < kLanes; ++i) {
            ASSERT_EQ(bits(lanes(a[ch])[i]), bits(lanes(b[ch])[i])) << name << " " << filter_name(f) << " channel " << ch;
            ASSERT_EQ(bits(lanes(a[ch])[i]), bits(lanes(c[ch])[i])) << name << " " << filter_name(f) << " generic";
          }
        // Texel loads (QDM's max-chain reads), wrapped into every level, on both fetch paths.
        alignas(64) std::int32_t level[kLanes], x[kLanes], y[kLanes];
        for (int i = 0; i < kLanes; ++i) level[i] = index(rng) % 8, x[i] = index(rng), y[i] = index(rng);
        const simd::Int li = simd::Int::load_aligned(level), xi = simd::Int::load_aligned(x), yi = simd::Int::load_aligned(y);
        with_decode.load_wrapped(li, xi, yi, a);
        with_copy.load_wrapped(li, xi, yi, b);
        for (int ch = 0; ch < copied.channels(); ++ch)
          for (int i = 0; i < kLanes; ++i)
            ASSERT_EQ(bits(lanes(a[ch])[i]), bits(lanes(b[ch])[i])) << name << " load, level " << level[i];
      }
    }
  }
}

// Level 0's wrap footprints (Texture::wrap_footprints) of R16 and R8 heights hold each texel's bilinear footprint
// with wrapped neighbours, and sampling with them gives the bits of sampling without them (texel pairs per row,
// single taps at the edge), through every sampler, the specialised and the generic one, on power-of-two and other
// sizes, with non-finite and far-off coordinates.
TEST(TextureSampler, WrapFootprintsGiveTheBitsOfTheTexelPairs) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-3.0f, 4.0f), lod(-1.0f, 9.0f);
  EXPECT_EQ(wrap_footprint_bytes(64, 32, TexelFormat::R16, false), 64u * 32u * 16u);
  EXPECT_EQ(wrap_footprint_bytes(64, 32, TexelFormat::R8, false), 64u * 32u * 16u);
  EXPECT_EQ(wrap_footprint_bytes(64, 32, TexelFormat::RGBA8, true), 0u) << "colour: four channels";
  EXPECT_EQ(wrap_footprint_bytes(64, 32, TexelFormat::R32F, false), 0u) << "no decoded copy";
  EXPECT_EQ(wrap_footprint_bytes(2048, 2048, TexelFormat::R16, false), kWrapFootprintsMaxBytes);
  EXPECT_EQ(wrap_footprint_bytes(4096, 2048, TexelFormat::R16, false), 0u) << "above kWrapFootprintsMaxBytes";
  for (const TexelFormat format : {TexelFormat::R16, TexelFormat::R8})
    for (const auto& [w, h] : {std::pair{64, 32}, std::pair{37, 19}}) {
      const std::string name = format_name(format) + " " + std::to_string(w) + "x" + std::to_string(h);
      Image img(w, h, 1);
      for (float& t : img.texels) t = unit(rng);
      Texture pairs = make_mip_texture(img, format, false, MipReduce::Box);
      add_linear_copy(pairs);
      Texture footprints = pairs;
      add_wrap_footprints(footprints);
      ASSERT_EQ(footprints.wrap_footprints.size(), std::size_t(w) * std::size_t(h) * 4) << name;
      EXPECT_EQ(footprints.bytes(), pairs.bytes() + wrap_footprint_bytes(w, h, format, false)) << name;
      // The last texel's footprint wraps in both axes: (w-1, h-1), (0, h-1), (w-1, 0), (0, 0).
      const float* corner = footprints.wrap_footprints.data() + (std::size_t(h) * std::size_t(w) - 1) * 4;
      EXPECT_EQ(corner[0], pairs.texel(0, w - 1, h - 1, 0)) << name;
      EXPECT_EQ(corner[1], pairs.texel(0, 0, h - 1, 0)) << name;
      EXPECT_EQ(corner[2], pairs.texel(0, w - 1, 0, 0)) << name;
      EXPECT_EQ(corner[3], pairs.texel(0, 0, 0, 0)) << name;
      for (const SamplerState& state : every_sampler_state()) {
        const TextureSampler without(pairs, state), with(footprints, state);
        for (int round = 0; round < 16; ++round) {
          Lanes u, v, l;
          for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng);
          if (round == 0) u[1] = kNaN, v[2] = -kInf, l[3] = kNaN, u[4] = 3e7f, v[5] = -1e30f;
          if (round % 2 == 1)  // every lane inside one row pair: without footprints, the paired loads run
            for (int i = 0; i < kLanes; ++i) u[i] = 0.25f + 0.01f * float(i), v[i] = 0.5f + 0.02f * float(i);
          if (round == 2)  // every lane on the last column and row: the footprints' wrapped neighbours
            for (int i = 0; i < kLanes; ++i) u[i] = 1.0f - 0.1f / float(w), v[i] = float(i % 3) - 0.2f / float(h);
          Float a[4], b[4], c[4];
          without.sample(load(u), load(v), load(l), a);
          with.sample(load(u), load(v), load(l), b);
          sample(with.view(), state, load(u), load(v), load(l), c);
          for (int i = 0; i < kLanes; ++i) {
            ASSERT_EQ(bits(lanes(a[0])[i]), bits(lanes(b[0])[i])) << name << " " << filter_name(state.filter) << " lane " << i;
            ASSERT_EQ(bits(lanes(a[0])[i]), bits(lanes(c[0])[i])) << name << " " << filter_name(state.filter) << " generic";
          }
        }
      }
    }
}

// The sampler reads level 0 for any LOD plus bias of at most 0, whatever its exact value (sample_levels clamps it
// there): normal mapping relies on it and passes 0 for batches whose footprints are at most one texel (LOD at most
// 0 in every lane) when the bias is at most 0. Every sampler state, biases 0 to -3, LOD clamps below and above 0.
TEST(TextureSampler, EveryLodOfAtMostZeroReadsWhatLodZeroReads) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-3.0f, 4.0f), magnified(-64.0f, 0.0f);
  Image img(32, 16, 4);
  for (float& t : img.texels) t = unit(rng);
  Texture albedo = make_mip_texture(img, TexelFormat::RGBA8, true, MipReduce::Box);
  add_linear_copy(albedo);
  const Texture normal = make_mip_texture(img, TexelFormat::RGBA8, false, MipReduce::Box);
  for (SamplerState state : every_sampler_state())
    for (const float bias : {0.0f, -0.5f, -3.0f})
      for (const auto& [min_lod, max_lod] : {std::pair{0.0f, 16.0f}, std::pair{-2.0f, 16.0f}, std::pair{1.5f, 3.0f},
                                             std::pair{-4.0f, -1.0f}}) {
        state.lod_bias = bias;
        state.min_lod = min_lod;
        state.max_lod = max_lod;
        for (const Texture* t : {static_cast<const Texture*>(&albedo), &normal}) {
          const TextureSampler sampler(*t, state);
          Lanes u, v, l;
          for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = magnified(rng);
          l[0] = 0.0f, l[1 % kLanes] = -64.0f, l[2 % kLanes] = -0.0f;
          Float exact[4], zero[4];
          sampler.sample(load(u), load(v), load(l), exact);
          sampler.sample(load(u), load(v), Float(0.0f), zero);
          for (int ch = 0; ch < 4; ++ch)
            for (int i = 0; i < kLanes; ++i)
              ASSERT_EQ(bits(lanes(exact[ch])[i]), bits(lanes(zero[ch])[i]))
                  << filter_name(state.filter) << " bias " << bias << " clamp " << min_lod << ".." << max_lod
                  << " LOD " << l[i] << " channel " << ch;
        }
      }
}

TEST(TextureSampler, DecodesEveryFormatLikeTheScalarTexelAccessor) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (TexelFormat format : {TexelFormat::R8, TexelFormat::RG8, TexelFormat::RGBA8, TexelFormat::R16, TexelFormat::R32F})
    for (bool srgb : {false, true}) {
      if (srgb && (format == TexelFormat::R16 || format == TexelFormat::R32F)) continue;
      Image img(5, 3, channel_count(format));
      for (float& t : img.texels) t = unit(rng);
      const Texture texture = make_mip_texture(img, format, srgb, MipReduce::Box);
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) {
          Float out[4];
          load(TextureView(texture), simd::Int(0), simd::Int(x), simd::Int(y), simd::FetchPath::Portable, out);
          for (int c = 0; c < texture.channels(); ++c) ASSERT_EQ(lanes(out[c])[0], texture.texel(0, x, y, c));
        }
    }
}

}  // namespace
}  // namespace qdmr

namespace qdmr {
namespace {

// A TextureSampler runs an instantiation of the sampler for its key (sampler.cpp lists the common ones); it must
// give the generic sampler's bits for every filter, address mode, precision, math mode, format and size, on
// both fetch paths, including lanes with non-finite coordinates and LODs outside the chain. Loads likewise.
TEST(TextureSampler, SpecialisedSamplersGiveTheGenericBits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-3.0f, 4.0f), lod(-1.0f, 9.0f);
  struct Case {
    TexelFormat format;
    bool srgb;
    int w, h;
  };
  const Case cases[] = {{TexelFormat::R8, false, 64, 32},   {TexelFormat::RG8, false, 16, 16},
                        {TexelFormat::RGBA8, false, 37, 20}, {TexelFormat::RGBA8, true, 32, 64},
                        {TexelFormat::R16, false, 48, 48},   {TexelFormat::R32F, false, 16, 8}};
  int specialised = 0;
  for (const Case& c : cases) {
    Image img(c.w, c.h, channel_count(c.format) == 2 ? 2 : channel_count(c.format) == 1 ? 1 : 3);
    for (float& t : img.texels) t = unit(rng);
    const Texture texture = make_mip_texture(img, c.format, c.srgb, MipReduce::Box);
    for (const SamplerState& state : every_sampler_state()) {
      const Filter f = state.filter;
      const simd::FetchPath path = state.fetch;
      const TextureSampler bound(texture, state);
      specialised += bound.specialised() ? 1 : 0;
      // A listening recorder takes the generic sampler, which reports every fetch.
      EXPECT_EQ(sample_function(bound.key(), true), &sample);
      EXPECT_EQ(sample_function(bound.key(), false) != &sample, bound.specialised());
      for (int round = 0; round < 8; ++round) {
        Lanes u, v, l;
        for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng);
        if (round == 0) u[1] = std::numeric_limits<float>::quiet_NaN(), v[2] = -INFINITY, l[3] = NAN;
        Float generic[4], fixed[4];
        sample(bound.view(), state, load(u), load(v), load(l), generic);
        // What bound.sample() calls when no texture-cache recorder listens.
        sample_function(bound.key(), false)(bound.view(), state, load(u), load(v), load(l), fixed);
        for (int ch = 0; ch < texture.channels(); ++ch)
          for (int i = 0; i < kLanes; ++i)
            ASSERT_EQ(bits(lanes(generic[ch])[i]), bits(lanes(fixed[ch])[i]))
                << filter_name(f) << " format " << int(c.format) << " lane " << i;
        std::array<std::int32_t, kLanes> level, x, y;
        for (int i = 0; i < kLanes; ++i)
          level[std::size_t(i)] = int(rng() % 6) - 1, x[std::size_t(i)] = int(rng() % 200) - 50,
          y[std::size_t(i)] = int(rng() % 200) - 50;
        const simd::Int li = simd::Int::load_unaligned(level.data()), xi = simd::Int::load_unaligned(x.data()),
                        yi = simd::Int::load_unaligned(y.data());
        load(bound.view(), li, xi, yi, path, generic);
        bound.load(li, xi, yi, fixed);
        for (int ch = 0; ch < texture.channels(); ++ch)
          ASSERT_EQ(simd::to_bits(generic[ch] == fixed[ch]), (1u << kLanes) - 1) << "load, format " << int(c.format);
      }
    }
  }
  // Point, bilinear and trilinear with wrap, exact or 8-bit weights, sm4 and sm3, on the default path: 3 x 2 x 2
  // keys per format with a specialisation (5 of the 6 formats).
  EXPECT_EQ(specialised, 3 * 2 * 2 * 5);
}

// load_wrapped: indices wrap into the level (power-of-two sizes) for any level in range.
TEST(TextureSampler, LoadWrappedWrapsIntoTheLevel) {
  const Texture c = ramp_chain(8, 4);  // level 1: 4 x 2, level 2: 2 x 1
  const TextureSampler bound(c, SamplerState{});
  for (int level = 0; level < c.level_count(); ++level)
    for (int y = -9; y < 9; ++y)
      for (int x = -17; x < 17; ++x) {
        Float wrapped[4], direct[4];
        const int w = c.levels[std::size_t(level)].width, h = c.levels[std::size_t(level)].height;
        bound.load_wrapped(simd::Int(level), simd::Int(x), simd::Int(y), wrapped);
        bound.load(simd::Int(level), simd::Int(((x % w) + w) % w), simd::Int(((y % h) + h) % h), direct);
        ASSERT_EQ(lanes(wrapped[0])[0], lanes(direct[0])[0]) << level << " " << x << " " << y;
      }
}

// The max chain's reads in QDM's traversal (SingleLayerSurface::cell_max): inlined for R8 and R16 chains, through
// the sampler for others; the bits of load_wrapped()'s first channel either way, every lane on its own level
// (out-of-range levels clamp) and cell (wrapping far out on both sides).
TEST(TextureSampler, CellMaxIsLoadWrapped) {
  for (const TexelFormat format : {TexelFormat::R8, TexelFormat::R16, TexelFormat::R32F}) {
    Image img(16, 8, 1);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 16; ++x) img.at(x, y, 0) = float((x * 7 + y * 13) % 31) / 30.0f;
    const Texture heights = make_mip_texture(img, format, false, MipReduce::Box);
    const Texture chain = make_mip_texture(img, format, false, MipReduce::Max);
    const HeightLayerTextures textures(heights, &chain, SamplerState{}, HeightFetch::Bilinear);
    EXPECT_EQ(textures.inline_max_chain, format == TexelFormat::R16 ? InlineMaxChain::R16
                                         : format == TexelFormat::R8 ? InlineMaxChain::R8
                                                                     : InlineMaxChain::None);
    const SingleLayerSurface surface(textures);
    alignas(64) std::int32_t level[kLanes], x[kLanes], y[kLanes];
    for (int round = 0; round < 64; ++round) {
      for (int l = 0; l < kLanes; ++l) {
        level[l] = (round + l) % (chain.level_count() + 2) - 1;
        x[l] = (round * 5 + l * 11) % 71 - 35;
        y[l] = (round * 3 + l * 17) % 43 - 21;
      }
      const simd::Int lv = simd::Int::load_aligned(level), xv = simd::Int::load_aligned(x), yv = simd::Int::load_aligned(y);
      Float wrapped[4];
      textures.tree.load_wrapped(lv, xv, yv, wrapped);
      const Lanes expected = lanes(wrapped[0]), got = lanes(surface.cell_max(lv, xv, yv));
      for (int l = 0; l < kLanes; ++l)
        ASSERT_EQ(bits(got[l]), bits(expected[l])) << int(format) << " lane " << l << " level " << level[l];
    }
  }
}

// The heights the tracing loops read (SingleLayerSurface::height): inlined for bilinear R8 and R16 maps with exact or
// 8-bit weights (the math modes whose key floors the exact texel coordinate for hw8), through the sampler
// otherwise; the bits of the height sampler's first channel either way, including coordinates far out and non-finite.
// The same for the fetch a loop takes before it starts (with_height), which reads the wrap footprints with the
// texture's values bound once (FootprintHeight) exactly where the heights are inlined and have footprints and the
// caller says its coordinates are finite (then the same bits at finite coordinates).
TEST(TextureSampler, SurfaceHeightIsTheHeightSamplers) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
  for (const bool footprints : {false, true})
    for (const TexelFormat format : {TexelFormat::R8, TexelFormat::R16, TexelFormat::R32F})
      for (const SamplePrecision precision : kPrecisions)
        for (const MathMode math : kMathModes) {
          Image img(32, 16, 1);
          for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 32; ++x) img.at(x, y, 0) = float((x * 7 + y * 13) % 31) / 30.0f;
          Texture heights = make_mip_texture(img, format, false, MipReduce::Box);
          if (footprints) {
            if (heights.linear.empty()) add_linear_copy(heights);
            add_wrap_footprints(heights);
          }
          SamplerState state;
          state.precision = precision;
          state.math = math;
          const HeightLayerTextures textures(heights, nullptr, state, HeightFetch::Bilinear);
          const bool inlined = format != TexelFormat::R32F && precision != SamplePrecision::Hw6 &&
                               (precision == SamplePrecision::Exact || math != MathMode::Sm3);
          EXPECT_EQ(textures.inline_height != InlineHeight::None, inlined)
              << int(format) << " " << int(precision) << " " << int(math);
          const SingleLayerSurface surface(textures);
          for (int round = 0; round < 32; ++round) {
            Lanes u, v;
            for (int l = 0; l < kLanes; ++l) {
              u[std::size_t(l)] = coordinate(rng);
              v[std::size_t(l)] = coordinate(rng);
            }
            if (round == 0) u[0] = kNaN, v[1 % kLanes] = -kInf, u[2 % kLanes] = 3e7f, v[3 % kLanes] = -1e30f;
            if (round == 1)  // the last column and row: the footprints' wrapped neighbours
              for (std::size_t l = 0; l < std::size_t(kLanes); ++l)
                u[l] = 1.0f - 0.1f / 32.0f, v[l] = float(l % 3) - 0.2f / 16.0f;
            if (round == 2 || round == 3)  // a float either side of texel centres and 8-bit steps, and just above 0
              for (std::size_t l = 0; l < std::size_t(kLanes); ++l) {
                const float centre = (float(l) + 0.5f + (round == 3 ? 1.0f / 256.0f : 0.0f)) / 32.0f;
                u[l] = l % 3 == 0 ? centre : std::nextafter(centre, l % 3 == 1 ? 0.0f : 1.0f);
                v[l] = l % 2 == 0 ? std::ldexp(1.0f, -20 - int(l)) : 1.0f - std::ldexp(1.0f, -24 + int(l % 4));
              }
            Float expected[4];
            textures.height.sample(load(u), load(v), Float(0.0f), expected);
            const Lanes want = lanes(expected[0]), got = lanes(surface.height(load(u), load(v), Float(0.0f)));
            Lanes bound_got{};
            bool bound = false;
            for (const bool finite : {false, true}) {
              surface.with_height<false>(finite, [&](const auto& fetch) {
                bound = requires { fetch.footprints; };
                bound_got = lanes(fetch(load(u), load(v), Float(0.0f)));
              });
              EXPECT_EQ(bound, finite && footprints && inlined)
                  << int(format) << " " << int(precision) << " " << int(math);
              for (std::size_t l = 0; l < std::size_t(kLanes); ++l) {
                ASSERT_EQ(bits(got[l]), bits(want[l])) << int(format) << " lane " << l;
                // The bound fetch is for finite coordinates (any value elsewhere).
                if (!bound || (std::isfinite(u[l]) && std::isfinite(v[l]))) {
                  ASSERT_EQ(bits(bound_got[l]), bits(want[l])) << int(format) << " footprints " << footprints << " lane " << l;
                }
              }
            }
          }
        }
}

// trace::finite_along, which lets relief's and POM's loops take the fetch without the non-finite test: true only
// where every lane it checks has a ray far inside the float range (NaN, infinite and huge values fail; unchecked
// lanes may hold anything).
TEST(TextureSampler, FiniteAlongOnlyForRaysFarInsideTheFloatRange) {
  const auto ray_with = [](int field, float value) {
    std::array<Lanes, 4> f;  // u0, v0, du, dv
    for (Lanes& l : f) l.fill(0.5f);
    if (field < 4) f[std::size_t(field)][0] = value;
    return trace::Ray{load(f[0]), load(f[1]), load(f[2]), load(f[3])};
  };
  const simd::Mask all(true), not_lane0 = ~simd::from_bits(1u);
  EXPECT_TRUE(trace::finite_along(ray_with(4, 0.0f), Float(0.3f), all));
  for (const float bad : {kNaN, kInf, -kInf, 1e35f})
    for (int field = 0; field <= 4; ++field) {
      Lanes ds;
      ds.fill(0.3f);
      if (field == 4) ds[0] = bad;
      const trace::Ray ray = ray_with(field, bad);
      EXPECT_FALSE(trace::finite_along(ray, load(ds), all)) << field << " " << bad;
      EXPECT_TRUE(trace::finite_along(ray, load(ds), not_lane0)) << field << " " << bad;
    }
}

// A TwinSampler (albedo and normal map sampled at one UV) gives each texture the bits of its own TextureSampler (their
// rgb; the alphas are not sampled and are 1 on every path), for every sampler state, on both fetch paths, with and
// without the albedo's decoded sRGB copy, with and without the two interleaved (twin_texels.hpp), power-of-two and
// other sizes, lanes with non-finite coordinates, lanes at the wrap and clamp edges, batches that skip the coarse
// level, and with and without a prefetch hint (UvAhead). It shares addresses exactly where sampler.cpp
// instantiates a twin: RGBA8 chains of one size, the second not sRGB, bilinear or trilinear with wrap, exact or
// 8-bit weights, on the default fetch path.
TEST(TwinSampler, GivesEachTextureTheBitsOfItsOwnSampler) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), coord(-3.0f, 4.0f), lod(-1.0f, 9.0f);
  struct Case {
    int w, h;
    bool srgb, decoded_copy;
  };
  const auto chain = [&](int w, int h, bool srgb, bool decoded_copy) {
    Image img(w, h, 4);
    for (float& t : img.texels) t = unit(rng);
    Texture t = make_mip_texture(img, TexelFormat::RGBA8, srgb, MipReduce::Box);
    if (decoded_copy) add_linear_copy(t);
    return t;
  };
  for (const Case& c : {Case{32, 64, true, true}, Case{32, 64, true, false}, Case{37, 20, true, true},
                        Case{16, 16, false, false}, Case{1, 1, true, true}}) {
    const Texture albedo = chain(c.w, c.h, c.srgb, c.decoded_copy), normal = chain(c.w, c.h, false, false);
    ASSERT_EQ(albedo.linear.empty(), !c.decoded_copy);
    int shared = 0, expected_shared = 0;
    const std::vector<float> interleaved = interleave_twin_texels(albedo, normal);
    ASSERT_EQ(interleaved.empty(), !(c.srgb && c.decoded_copy));
    for (const SamplerState& state : every_sampler_state())
      for (const float* texels : {static_cast<const float*>(nullptr), interleaved.empty() ? nullptr : interleaved.data()}) {
        const TwinSampler twin(albedo, normal, state, texels);
        const TextureSampler first(albedo, state), second(normal, state);
        // Exactly where the plan reads the interleaved texels (twin_sampling), on the default fetch path.
        SamplingDesc sampling;
        sampling.filter = state.filter;
        sampling.address = state.address;
        sampling.precision = state.precision;
        const bool common = twin_sampling(sampling) && state.fetch == SamplerState{}.fetch;
        EXPECT_EQ(twin.shares_addresses(), common) << filter_name(state.filter) << " " << c.w << "x" << c.h;
        shared += twin.shares_addresses() ? 1 : 0;
        expected_shared += common ? 1 : 0;
        for (int round = 0; round < 12; ++round) {
          Lanes u, v, l;
          for (int i = 0; i < kLanes; ++i) u[i] = coord(rng), v[i] = coord(rng), l[i] = lod(rng);
          if (round == 0) u[1 % kLanes] = kNaN, v[2 % kLanes] = -kInf, l[3 % kLanes] = kNaN;
          if (round % 3 == 1)  // every lane inside one row pair: the paired loads run for the whole batch
            for (int i = 0; i < kLanes; ++i) u[i] = 0.25f + 0.01f * float(i), v[i] = 0.5f + 0.02f * float(i);
          if (round % 4 == 2)  // whole LODs: no lane weighs the coarse level
            for (int i = 0; i < kLanes; ++i) l[i] = std::floor(l[i]) - state.lod_bias;
          Float a[4], b[4], twin_a[4], twin_b[4];
          first.sample(load(u), load(v), load(l), a);
          second.sample(load(u), load(v), load(l), b);
          twin.sample(load(u), load(v), load(l), load(l), twin_a, twin_b);
          // A prefetch hint, however odd (non-finite, huge, pointing off the texture), changes no bit.
          Lanes du, dv;
          for (int i = 0; i < kLanes; ++i) du[i] = coord(rng), dv[i] = -coord(rng);
          if (round == 0) du[0] = kNaN, dv[1 % kLanes] = kInf, du[2 % kLanes] = -1e30f, dv[3 % kLanes] = 3e38f;
          const UvAhead ahead{load(du), load(dv)};
          Float hinted_a[4], hinted_b[4];
          twin.sample(load(u), load(v), load(l), load(l), hinted_a, hinted_b, &ahead);
          for (int ch = 0; ch < 4; ++ch)
            for (int i = 0; i < kLanes; ++i) {
              ASSERT_EQ(bits(lanes(hinted_a[ch])[i]), bits(lanes(twin_a[ch])[i])) << "hinted, channel " << ch;
              ASSERT_EQ(bits(lanes(hinted_b[ch])[i]), bits(lanes(twin_b[ch])[i])) << "hinted, channel " << ch;
              ASSERT_EQ(bits(lanes(twin_a[ch])[i]), ch < 3 ? bits(lanes(a[ch])[i]) : bits(1.0f))
                  << filter_name(state.filter) << " first, channel " << ch << " lane " << i << ", " << c.w << "x" << c.h
                  << (texels ? ", interleaved" : "");
              // Neither alpha is sampled: 1.
              ASSERT_EQ(bits(lanes(twin_b[ch])[i]), ch < 3 ? bits(lanes(b[ch])[i]) : bits(1.0f))
                  << filter_name(state.filter) << " second, channel " << ch << " lane " << i << ", " << c.w << "x" << c.h;
            }
        }
      }
    EXPECT_GT(shared, 0) << c.w << "x" << c.h;
    EXPECT_EQ(shared, expected_shared);
  }
  // Nothing is shared between chains of different sizes, or with a second texture in another format or in sRGB.
  const Texture a = chain(32, 32, true, true), wider = chain(64, 32, false, false), srgb = chain(32, 32, true, false);
  Image grey(32, 32, 1);
  const Texture r8 = make_mip_texture(grey, TexelFormat::R8, false, MipReduce::Box);
  EXPECT_FALSE(TwinSampler(a, wider, SamplerState{}).shares_addresses());
  EXPECT_FALSE(TwinSampler(a, r8, SamplerState{}).shares_addresses());
  EXPECT_FALSE(TwinSampler(a, srgb, SamplerState{}).shares_addresses());
  EXPECT_TRUE(TwinSampler(a, chain(32, 32, false, false), SamplerState{}).shares_addresses());
}

}  // namespace
}  // namespace qdmr
