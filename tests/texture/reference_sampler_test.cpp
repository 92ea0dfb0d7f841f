// The SIMD sampler against the scalar reference sampler, bit for bit in every lane: both fetch paths, every
// filter x address x precision x math mode, every format, sizes from 1x1 to NPOT, coordinates and LODs including
// the special values (far outside [0,1], texel boundaries and one float either side, NaN, infinities).
#include <gtest/gtest.h>

#include "texture/sampler_test_util.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "texture/reference_sampler.hpp"
#include "kernel/sampler.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using namespace test;


Lanes lanes(const Float& f) {
  Lanes a;
  f.store_unaligned(a.data());
  return a;
}

struct FormatCase {
  TexelFormat format;
  bool srgb;
};
constexpr FormatCase kFormats[] = {{TexelFormat::R8, false},  {TexelFormat::R8, true},   {TexelFormat::RG8, false},
                                   {TexelFormat::RG8, true},  {TexelFormat::RGBA8, false}, {TexelFormat::RGBA8, true},
                                   {TexelFormat::R16, false}, {TexelFormat::R32F, false}};

// Random texels (R32F also outside [0,1]); Box chains for colour, Max chains for the single-channel formats as
// height maps use them.
Texture random_texture(const FormatCase& f, int w, int h, std::mt19937& rng) {
  Image img(w, h, channel_count(f.format));
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), wide(-2.0f, 3.0f);
  for (float& t : img.texels) t = f.format == TexelFormat::R32F ? wide(rng) : unit(rng);
  const MipReduce reduce = channel_count(f.format) == 1 ? MipReduce::Max : MipReduce::Box;
  return make_mip_texture(img, f.format, f.srgb, reduce);
}

// Coordinates: mostly uniform in [-3, 4]; some on texel centres and edges of a random level (where floor
// and the fixed-point conversion are most sensitive); some special values.
float random_coordinate(std::mt19937& rng, int size) {
  static constexpr float kSpecial[] = {1e4f,       -1e4f,       1e4f + 0.375f, kNaN,   kInf, -kInf, 0.0f, -0.0f,
                                       1.0f,       2.0f,        -1.0f,         -1e-30f, 1e-45f, 0.99999994f,
                                       1.0000001f, 1e30f,       -3.0f,         4.0f};
  std::uniform_int_distribution<int> kind(0, 9), special(0, int(std::size(kSpecial)) - 1), level(0, 4), k(-2, 3 * size);
  std::uniform_real_distribution<float> uniform(-3.0f, 4.0f);
  switch (kind(rng)) {
    case 0: return kSpecial[special(rng)];
    case 1: {
      const int n = std::max(1, size >> level(rng));
      return (float(k(rng)) + (k(rng) % 2 ? 0.5f : 0.0f)) / float(n);
    }
    case 2: {  // one float either side of a texel edge or centre, or of an edge of 1/256 texel (hw8 fixed point)
      const int n = std::max(1, size >> level(rng));
      const float t = (float(k(rng)) + float(k(rng) % 256) / 256.0f) / float(n);
      return std::nextafter(t, k(rng) % 2 ? kInf : -kInf);
    }
    default: return uniform(rng);
  }
}

float random_lod(std::mt19937& rng) {
  static constexpr float kSpecial[] = {kNaN, kInf, -kInf, 0.0f, -64.0f, 1e30f, 0.5f, 1.5f, 13.0f};
  std::uniform_int_distribution<int> kind(0, 9), special(0, int(std::size(kSpecial)) - 1), eighths(-16, 112);
  std::uniform_real_distribution<float> uniform(-2.0f, 14.0f);
  switch (kind(rng)) {
    case 0: return kSpecial[special(rng)];
    case 1: return float(eighths(rng)) / 8.0f;  // exact level fractions
    default: return uniform(rng);
  }
}

// LOD bias and clamps: the defaults, a bias, a narrow clamp window, and min_lod above max_lod (max_lod wins).
struct LodSettings {
  float bias, min_lod, max_lod;
};
constexpr LodSettings kLodSettings[] = {{0.0f, 0.0f, 16.0f}, {0.3f, 0.0f, 16.0f}, {-1.5f, 0.5f, 3.25f}, {0.0f, 2.0f, 1.0f}};

std::string describe(const SamplingDesc& d, const Texture& t, int lane, int c, float u, float v, float lod) {
  std::ostringstream s;
  s << "filter " << int(d.filter) << " address " << int(d.address) << " precision " << int(d.precision) << " math "
    << int(d.math) << " bias "
    << d.lod_bias << " lod clamp [" << d.min_lod << ", " << d.max_lod << "] format " << format_name(t.format)
    << (t.srgb ? " srgb " : " ") << t.width() << "x" << t.height() << " lane " << lane << " channel " << c << " u "
    << u << " v " << v << " lod " << lod;
  return s.str();
}

// Samples one batch on both fetch paths; every lane and channel must equal the reference's bits.
void expect_batch_matches_reference(const Texture& texture, const TextureView& view, const SamplingDesc& desc,
                                    const Lanes& u, const Lanes& v, const Lanes& lod) {
  for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
    SamplerState state = test::sampler_state(desc);
    state.fetch = path;
    Float out[4];
    sample(view, state, Float::load_unaligned(u.data()), Float::load_unaligned(v.data()),
           Float::load_unaligned(lod.data()), out);
    for (int c = 0; c < texture.channels(); ++c) {
      const Lanes got = lanes(out[c]);
      for (int i = 0; i < kLanes; ++i) {
        float expected[4];
        reference_sample(texture, desc, u[std::size_t(i)], v[std::size_t(i)], lod[std::size_t(i)], expected);
        ASSERT_EQ(bits(got[std::size_t(i)]), bits(expected[c]))
            << (path == simd::FetchPath::Gather ? "gather: " : "portable: ") << got[std::size_t(i)] << " vs "
            << expected[c] << "; " << describe(desc, texture, i, c, u[std::size_t(i)], v[std::size_t(i)], lod[std::size_t(i)]);
      }
    }
  }
}

TEST(ReferenceSampler, SimdSamplerMatchesBitForBit) {
  struct Size {
    int w, h;
  };
  constexpr Size kSizes[] = {{1, 1}, {1, 6}, {7, 1}, {2, 2}, {5, 3}, {37, 20}, {64, 64}, {130, 9}, {16383, 3}};
  std::mt19937 rng(2024);
  for (const FormatCase& format : kFormats)
    for (const Size& size : kSizes) {
      const Texture texture = random_texture(format, size.w, size.h, rng);
      const TextureView view(texture);
      for (Filter filter : kFilters)
        for (AddressMode address : kAddressModes)
          for (SamplePrecision precision : kPrecisions)
            for (MathMode math : kMathModes)
              for (const LodSettings& lod_settings : kLodSettings) {
                SamplingDesc desc;
                desc.math = math;
                desc.filter = filter;
                desc.address = address;
                desc.precision = precision;
                desc.lod_bias = lod_settings.bias;
                desc.min_lod = lod_settings.min_lod;
                desc.max_lod = lod_settings.max_lod;
                for (int round = 0; round < 16; ++round) {
                  Lanes u, v, lod;
                  for (int i = 0; i < kLanes; ++i) {
                    u[std::size_t(i)] = random_coordinate(rng, size.w);
                    v[std::size_t(i)] = random_coordinate(rng, size.h);
                    lod[std::size_t(i)] = random_lod(rng);
                  }
                  expect_batch_matches_reference(texture, view, desc, u, v, lod);
                  if (HasFatalFailure()) return;
                }
              }
    }
}

TEST(ReferenceSampler, LodFromDerivativesMatchesBitForBit) {
  static constexpr float kSpecial[] = {0.0f, -0.0f, kInf, -kInf, kNaN, 1e30f, -1e30f, 1e-30f, 1e-45f, 1e-19f, 1.0f};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-70, 40), kind(0, 7), special(0, int(std::size(kSpecial)) - 1);
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{16384, 1}, std::pair{37, 20}, std::pair{256, 256}}) {
    Image img(w, h, 1);
    const Texture texture = make_mip_texture(img, TexelFormat::R8, false, MipReduce::Max);
    const TextureView view(texture);
    for (int round = 0; round < 4000; ++round) {
      std::array<Lanes, 4> d;
      for (Lanes& a : d)
        for (float& x : a) x = kind(rng) == 0 ? kSpecial[special(rng)] : std::ldexp(mantissa(rng), exponent(rng));
      const Lanes got = lanes(lod_from_derivatives(view, Float::load_unaligned(d[0].data()), Float::load_unaligned(d[1].data()),
                                                   Float::load_unaligned(d[2].data()), Float::load_unaligned(d[3].data())));
      for (std::size_t i = 0; i < std::size_t(kLanes); ++i)
        ASSERT_EQ(bits(got[i]), bits(reference_lod(texture, d[0][i], d[1][i], d[2][i], d[3][i])))
            << w << "x" << h << " derivatives " << d[0][i] << " " << d[1][i] << " " << d[2][i] << " " << d[3][i];
    }
  }
}

// The reference itself, on values worked out by hand from the documented behaviour (a ramp texel = x + 4y,
// R32F so every value is exact; level 1 of the Box chain is 2.5 4.5 / 10.5 12.5, level 2 is 7.5).
TEST(ReferenceSampler, DocumentedValuesOnARamp) {
  Image img(4, 4, 1);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) img.at(x, y, 0) = float(x + 4 * y);
  const Texture ramp = make_mip_texture(img, TexelFormat::R32F, false, MipReduce::Box);
  const auto at = [&](Filter f, AddressMode a, float u, float v, float lod, SamplePrecision p = SamplePrecision::Exact) {
    SamplingDesc d;
    d.filter = f;
    d.address = a;
    d.precision = p;
    float out[4];
    reference_sample(ramp, d, u, v, lod, out);
    return out[0];
  };
  const auto W = AddressMode::Wrap, C = AddressMode::Clamp, M = AddressMode::Mirror;
  EXPECT_EQ(at(Filter::Point, W, 0.375f, 0.625f, 5.0f), 9.0f);             // texel (1, 2), LOD ignored
  EXPECT_EQ(at(Filter::Point, W, -0.125f, 0.125f, 0.0f), 3.0f);            // wraps to texel 3
  EXPECT_EQ(at(Filter::Point, M, -0.125f, 0.125f, 0.0f), 0.0f);            // mirrors to texel 0
  EXPECT_EQ(at(Filter::Point, M, 1.125f, 0.125f, 0.0f), 3.0f);             // second period reflected
  EXPECT_EQ(at(Filter::Point, C, 1e4f, 0.125f, 0.0f), 3.0f);               // clamped to the edge
  EXPECT_EQ(at(Filter::Bilinear, W, 0.0f, 0.125f, 0.0f), 1.5f);            // taps 3 and 0, halfway
  EXPECT_EQ(at(Filter::Bilinear, C, 0.0f, 0.125f, 0.0f), 0.0f);            // both taps clamp to 0
  EXPECT_EQ(at(Filter::Bilinear, W, 0.5f, 0.5f, 0.0f), 7.5f);              // centre of texels 5 6 9 10
  EXPECT_EQ(at(Filter::PointMipPoint, W, 0.125f, 0.125f, 0.49f), 0.0f);    // nearest level 0
  EXPECT_EQ(at(Filter::PointMipPoint, W, 0.125f, 0.125f, 0.5f), 2.5f);     // ties go to the coarser level
  EXPECT_EQ(at(Filter::PointMipPoint, W, 0.125f, 0.125f, kNaN), 7.5f);     // NaN LOD: the last level
  EXPECT_EQ(at(Filter::PointMipLinear, W, 0.125f, 0.125f, 1.5f), 5.0f);    // 2.5 + (7.5 - 2.5) / 2
  EXPECT_EQ(at(Filter::Trilinear, W, 0.125f, 0.125f, 99.0f), 7.5f);        // clamped to the last level
  EXPECT_EQ(at(Filter::Point, W, kNaN, 0.5f, 0.0f), 0.0f);                 // non-finite: texel (0, 0)
  // hw8: u = 0.3 on a 4-wide level is p = 0.7 texels past texel 0's centre; weight floor(0.7 * 256) / 256.
  const float p = 0.3f * 4.0f - 0.5f;
  EXPECT_EQ(at(Filter::Bilinear, C, 0.3f, 0.125f, 0.0f, SamplePrecision::Hw8), std::floor(p * 256.0f) / 256.0f);
  EXPECT_EQ(at(Filter::Bilinear, C, 0.3f, 0.125f, 0.0f, SamplePrecision::Hw6), std::floor(p * 64.0f) / 64.0f);
  EXPECT_EQ(reference_lod(ramp, 0.25f, 0.0f, 0.0f, 0.25f), 0.0f);
  EXPECT_EQ(reference_lod(ramp, 1.0f, 0.0f, 0.0f, 0.25f), 2.0f);
  EXPECT_EQ(reference_lod(ramp, 0.0f, 0.0f, 0.0f, 0.0f), -64.0f);
  EXPECT_EQ(reference_lod(ramp, kInf, 0.0f, 0.0f, 0.0f), 2.0f);
}

// The reference computes level sizes from the documented rule max(1, floor(n / 2^k)); the chain must agree.
TEST(ReferenceSampler, LevelSizesFollowTheDocumentedRule) {
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{37, 20}, std::pair{16384, 3}, std::pair{5, 1000}}) {
    const Texture t = allocate_texture(w, h, TexelFormat::R8, false);
    for (int k = 0; k < t.level_count(); ++k) {
      EXPECT_EQ(t.levels[std::size_t(k)].width, std::max(1, w >> k));
      EXPECT_EQ(t.levels[std::size_t(k)].height, std::max(1, h >> k));
    }
  }
}

}  // namespace
}  // namespace qdmr
