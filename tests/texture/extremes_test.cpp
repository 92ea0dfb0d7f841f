// The sampler at its extremes: height maps from 1x1 to 16384² (R8, Max chains, as QDM stores them), every
// address mode, UV far outside [0,1], LODs below 0 and beyond the last level, derivatives of 0, infinity and
// NaN. Every result must equal the scalar reference (which reads texels only through the range-checked
// Texture::texel) and, where docs/sampling.md "Extremes" documents a value, that value. Both fetch paths run:
// the portable one reads texels with memcpy, which AddressSanitizer checks (it does not see AVX2 gathers).
#include <gtest/gtest.h>

#include "texture/sampler_test_util.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "qdmr/texture/texture_level0.hpp"
#include "texture/reference_sampler.hpp"
#include "kernel/sampler.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using namespace test;


SamplingDesc desc_of(Filter filter, AddressMode address, SamplePrecision precision = SamplePrecision::Exact) {
  SamplingDesc d;
  d.filter = filter;
  d.address = address;
  d.precision = precision;
  return d;
}

struct Point {
  float u, v, lod;
};

// Samples channel 0 at every point, kLanes points per batch, on both fetch paths; asserts each result has the
// reference's bits and returns them.
std::vector<float> sample_checked(const Texture& texture, const TextureView& view, const SamplingDesc& desc,
                                  const std::vector<Point>& points) {
  std::vector<float> result(points.size());
  for (std::size_t first = 0; first < points.size(); first += std::size_t(kLanes)) {
    alignas(64) float u[kLanes], v[kLanes], lod[kLanes], got[kLanes];
    for (std::size_t i = 0; i < std::size_t(kLanes); ++i) {
      const Point& p = points[std::min(first + i, points.size() - 1)];  // the last batch repeats its last point
      u[i] = p.u, v[i] = p.v, lod[i] = p.lod;
    }
    for (simd::FetchPath path : {simd::FetchPath::Gather, simd::FetchPath::Portable}) {
      SamplerState state = test::sampler_state(desc);
      state.fetch = path;
      Float out[4];
      sample(view, state, Float::load_aligned(u), Float::load_aligned(v), Float::load_aligned(lod), out);
      out[0].store_aligned(got);
      for (std::size_t i = 0; i < std::size_t(kLanes) && first + i < points.size(); ++i) {
        float expected[4];
        reference_sample(texture, desc, u[i], v[i], lod[i], expected);
        EXPECT_EQ(bits(got[i]), bits(expected[0]))
            << got[i] << " vs reference " << expected[0] << ": " << texture.width() << "x" << texture.height()
            << " filter " << int(desc.filter) << " address " << int(desc.address) << " precision "
            << int(desc.precision) << " u " << u[i] << " v " << v[i] << " lod " << lod[i];
        result[first + i] = got[i];
      }
    }
  }
  return result;
}

float sample_one(const Texture& texture, const SamplingDesc& desc, float u, float v, float lod) {
  return sample_checked(texture, TextureView(texture), desc, {{u, v, lod}})[0];
}

float lod_checked(const Texture& texture, float dudx, float dvdx, float dudy, float dvdy) {
  alignas(64) float got[kLanes];
  lod_from_derivatives(TextureView(texture), Float(dudx), Float(dvdx), Float(dudy), Float(dvdy)).store_aligned(got);
  const float expected = reference_lod(texture, dudx, dvdx, dudy, dvdy);
  for (int i = 0; i < kLanes; ++i) EXPECT_EQ(bits(got[i]), bits(expected)) << dudx << " " << dvdx << " " << dudy << " " << dvdy;
  return got[0];
}

Texture height_map(ProceduralPattern pattern, int size) {
  ProceduralDesc d;
  d.pattern = pattern;
  d.size = size;
  d.cells = 8;
  return make_mip_texture(generate_procedural(d), TexelFormat::R8, false, MipReduce::Max);
}

// The highest texel of level 0 of an R8 height map (the stored bytes order like the heights they decode to).
float level0_max(const Texture& t) {
  EXPECT_EQ(t.format, TexelFormat::R8);
  const std::uint8_t* first = t.texel_address(0, 0, 0);
  return float(*std::max_element(first, first + std::size_t(t.width()) * std::size_t(t.height()))) / 255.0f;
}

// Coordinates: far outside [0,1], on and next to the edges of the repeat, non-finite.
std::vector<float> extreme_coordinates(int size) {
  const float texel = 1.0f / float(size);
  return {1e4f, -1e4f, 1e4f + 0.3f, -1e4f - 0.7f, 1e30f, -1e30f, 0.0f, 1.0f, 2.0f, -1.0f, 0.99999994f,
          -1e-30f, 0.5f * texel, 1.0f - 0.5f * texel, 3.5f, kNaN, kInf, -kInf};
}

std::vector<float> extreme_lods(int levels) {
  const float last = float(levels - 1);
  return {-kInf, -1e30f, -64.0f, -1.0f, 0.0f, 0.3f, last - 0.5f, last, last + 0.5f, 100.0f, kInf, kNaN};
}

// A sample of the extreme coordinate and LOD combinations (all of them would be ~4000 per sampler state).
std::vector<Point> extreme_points(const Texture& t, int count, std::mt19937& rng) {
  const std::vector<float> uv = extreme_coordinates(std::max(t.width(), t.height()));
  const std::vector<float> lods = extreme_lods(t.level_count());
  std::uniform_int_distribution<std::size_t> pick_uv(0, uv.size() - 1), pick_lod(0, lods.size() - 1);
  std::vector<Point> points;
  for (int i = 0; i < count; ++i) points.push_back({uv[pick_uv(rng)], uv[pick_uv(rng)], lods[pick_lod(rng)]});
  return points;
}

// The documented results (docs/sampling.md, "Extremes") that hold at every size W x H of a square map.
void expect_documented_results(const Texture& t) {
  const int w = t.width(), h = t.height(), last = t.level_count() - 1;
  const float first = t.texel(0, 0, 0, 0), corner = t.texel(0, w - 1, h - 1, 0);
  const float row0 = 0.5f / float(h);
  for (float far : {1e4f, 1e30f}) {
    // Wrap and mirror: |u| >= 2^24 is an even integer, reduced to u' = 0 (so is 1e4): column 0.
    EXPECT_EQ(sample_one(t, desc_of(Filter::Point, AddressMode::Wrap), far, -far, 0), first);
    EXPECT_EQ(sample_one(t, desc_of(Filter::Point, AddressMode::Mirror), -far, far, 0), first);
    EXPECT_EQ(sample_one(t, desc_of(Filter::Bilinear, AddressMode::Mirror), far, far, 0), first);
    // Wrap, bilinear: u' = 0 sits halfway between the last column and the first.
    const float left = t.texel(0, w - 1, 0, 0), right = first;
    EXPECT_EQ(sample_one(t, desc_of(Filter::Bilinear, AddressMode::Wrap), far, row0, 0), left + (right - left) * 0.5f);
    // Clamp: the edge texels.
    for (Filter f : {Filter::Point, Filter::Bilinear}) {
      EXPECT_EQ(sample_one(t, desc_of(f, AddressMode::Clamp), far, far, 0), corner);
      EXPECT_EQ(sample_one(t, desc_of(f, AddressMode::Clamp), -far, -far, 0), first);
    }
  }
  // Non-finite coordinates: level-0 texel (0, 0), whatever the filter, address mode and LOD.
  for (Filter f : kFilters)
    for (float bad : {kNaN, kInf, -kInf}) {
      EXPECT_EQ(sample_one(t, desc_of(f, AddressMode::Clamp), bad, 0.7f, 3.0f), first);
      EXPECT_EQ(sample_one(t, desc_of(f, AddressMode::Wrap), 0.7f, bad, kNaN), first);
    }
  // LOD below 0: level 0 (the mip filters give the level-0 filter's result); beyond the last level, +inf and
  // NaN: the last level, whose single texel of a Max chain is the highest point of the map.
  const float u = 0.3f, v = 0.8f;
  const float point0 = sample_one(t, desc_of(Filter::Point, AddressMode::Wrap), u, v, 0);
  const float bilinear0 = sample_one(t, desc_of(Filter::Bilinear, AddressMode::Wrap), u, v, 0);
  const float top = t.texel(last, 0, 0, 0);
  ASSERT_EQ(t.levels[std::size_t(last)].width * t.levels[std::size_t(last)].height, 1);
  EXPECT_EQ(top, level0_max(t));
  for (float below : {-kInf, -1e30f, -64.0f, -0.5f}) {
    EXPECT_EQ(sample_one(t, desc_of(Filter::PointMipPoint, AddressMode::Wrap), u, v, below), point0);
    EXPECT_EQ(sample_one(t, desc_of(Filter::PointMipLinear, AddressMode::Wrap), u, v, below), point0);
    EXPECT_EQ(sample_one(t, desc_of(Filter::LinearMipPoint, AddressMode::Wrap), u, v, below), bilinear0);
    EXPECT_EQ(sample_one(t, desc_of(Filter::Trilinear, AddressMode::Wrap), u, v, below), bilinear0);
  }
  for (float beyond : {float(last), float(last) + 0.5f, 1e30f, kInf, kNaN})
      for (Filter f : {Filter::PointMipPoint, Filter::PointMipLinear, Filter::LinearMipPoint, Filter::Trilinear})
      EXPECT_EQ(sample_one(t, desc_of(f, AddressMode::Wrap), u, v, beyond), top);
}

// Every filter x address x precision on the extreme points, against the reference.
void expect_extremes_match_reference(const Texture& t, int points_per_state, std::mt19937& rng) {
  const TextureView view(t);
  for (Filter f : kFilters)
    for (AddressMode a : kAddressModes)
      for (SamplePrecision p : kPrecisions) sample_checked(t, view, desc_of(f, a, p), extreme_points(t, points_per_state, rng));
}

TEST(Extremes, OneTexelTextureGivesItsTexelEverywhere) {
  Image rgba(1, 1, 4), height(1, 1, 1);
  rgba.texels = {0.6f, 0.2f, 0.9f, 0.4f};
  height.texels = {0.6f};
  for (TexelFormat format : {TexelFormat::R8, TexelFormat::RGBA8, TexelFormat::R32F}) {
    const bool colour = format == TexelFormat::RGBA8;
    const Texture t = make_mip_texture(colour ? rgba : height, format, colour, colour ? MipReduce::Box : MipReduce::Max);
    ASSERT_EQ(t.level_count(), 1);
    const TextureView view(t);
    const std::vector<float> uv = extreme_coordinates(1), lods = extreme_lods(1);
    std::vector<Point> points;
    for (float u : uv)
      for (float v : uv)
        for (float lod : lods) points.push_back({u, v, lod});
    for (Filter f : kFilters)
      for (AddressMode a : kAddressModes)
        for (SamplePrecision p : kPrecisions) {
          const SamplingDesc desc = desc_of(f, a, p);
          for (float got : sample_checked(t, view, desc, points)) ASSERT_EQ(got, t.texel(0, 0, 0, 0));
          // Every channel: the reference agrees with the SIMD sampler above; here the value itself.
          float all[4];
          reference_sample(t, desc, 1e4f, kNaN, kInf, all);
          for (int c = 0; c < t.channels(); ++c) EXPECT_EQ(all[c], t.texel(0, 0, 0, c));
        }
    EXPECT_EQ(lod_checked(t, 0, 0, 0, 0), -64.0f);
    EXPECT_EQ(lod_checked(t, kInf, 0, 0, 0), 0.0f);
    EXPECT_EQ(lod_checked(t, 0, 0, kNaN, 0), 0.0f);
  }
}

TEST(Extremes, HeightMapsOfEverySizeUpTo4096) {
  std::mt19937 rng(99);
  for (ProceduralPattern pattern : {ProceduralPattern::Steps, ProceduralPattern::Checker})
    for (int size = 1; size <= 4096; size *= 2) {
      SCOPED_TRACE(testing::Message() << "pattern " << int(pattern) << " size " << size);
      const Texture t = height_map(pattern, size);
      expect_documented_results(t);
      expect_extremes_match_reference(t, 64, rng);
    }
}

// Long thin maps: NPOT-like level chains whose short side stays 1 while the long side keeps halving.
TEST(Extremes, OneTexelWideStrips) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const auto& [w, h] : {std::pair{16384, 1}, std::pair{1, 16384}, std::pair{16383, 3}}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h);
    Image img(w, h, 1);
    for (float& x : img.texels) x = unit(rng);
    const Texture t = make_mip_texture(img, TexelFormat::R8, false, MipReduce::Max);
    expect_documented_results(t);
    expect_extremes_match_reference(t, 64, rng);
  }
}

// The largest map qdmr accepts: a 16384² checker (8 squares per side), R8 with its Max chain (~358 MB).
TEST(Extremes, LargestHeightMap16384) {
  const Texture t = height_map(ProceduralPattern::Checker, 16384);
  ASSERT_EQ(t.level_count(), 15);
  // Every byte of the chain is addressable with the 32-bit offsets of the SIMD fetch.
  ASSERT_LT(t.bytes(), std::size_t(std::numeric_limits<std::int32_t>::max()));
  expect_documented_results(t);
  // Checker: texel (x, y) of level 0 is ((x / 2048 + y / 2048) & 1); the last level is its maximum, 1.
  const SamplingDesc point = desc_of(Filter::Point, AddressMode::Wrap);
  EXPECT_EQ(sample_one(t, point, 2049.5f / 16384, 0.5f / 16384, 0), 1.0f);
  EXPECT_EQ(sample_one(t, point, 1.0f - 0.5f / 16384, 1.0f - 0.5f / 16384, 0), 0.0f);  // texel (16383, 16383)
  EXPECT_EQ(sample_one(t, desc_of(Filter::Trilinear, AddressMode::Clamp), 0.5f, 0.5f, kInf), 1.0f);
  // Far from [0,1] the float spacing of u limits the texels reached: at |u| in [2^13, 2^14) (1e4) u moves in
  // steps of 2^-10, 16 texels of this map; the next float after 1e4 lands on column 16, in the same square.
  EXPECT_EQ(std::nextafter(1e4f, kInf) - 1e4f, 0x1p-10f);
  EXPECT_EQ(sample_one(t, point, std::nextafter(1e4f, kInf) + 2048.0f / 16384, 0.0f, 0), 1.0f);  // column 2064
  std::mt19937 rng(16384);
  expect_extremes_match_reference(t, 32, rng);
  // Random points anywhere in the map (mostly cache misses), against the reference.
  std::uniform_real_distribution<float> coord(-2.0f, 3.0f), lod(-1.0f, 15.0f);
  std::vector<Point> points(2048);
  for (Point& p : points) p = {coord(rng), coord(rng), lod(rng)};
  for (Filter f : kFilters) sample_checked(t, TextureView(t), desc_of(f, AddressMode::Wrap, SamplePrecision::Hw8), points);
}

TEST(Extremes, DerivativesOfZeroInfinityAndNaN) {
  Image strip(16384, 1, 1);
  for (int x = 0; x < 16384; ++x) strip.at(x, 0, 0) = float(x % 251) / 250.0f;
  for (const Texture& t : {height_map(ProceduralPattern::Steps, 1), height_map(ProceduralPattern::Steps, 4096),
                           make_mip_texture(strip, TexelFormat::R8, false, MipReduce::Max)}) {
    SCOPED_TRACE(testing::Message() << t.width() << "x" << t.height());
    const float last = float(t.level_count() - 1);
    // A zero (or denormal) footprint: -64, i.e. level 0.
    EXPECT_EQ(lod_checked(t, 0, 0, 0, 0), -64.0f);
    EXPECT_EQ(lod_checked(t, -0.0f, 0, 0, -0.0f), -64.0f);
    EXPECT_EQ(lod_checked(t, 1e-30f, 1e-30f, 0, 0), -64.0f);
    EXPECT_EQ(lod_checked(t, 1e-45f, 0, 0, 1e-45f), -64.0f);
    // Infinite, NaN, or a squared footprint that overflows float: the last level.
    for (float bad : {kInf, -kInf, kNaN, 1e30f, -1e20f}) {
      EXPECT_EQ(lod_checked(t, bad, 0, 0, 0), last);
      EXPECT_EQ(lod_checked(t, 0, 0, 0, bad), last);
      EXPECT_EQ(lod_checked(t, 0.01f, bad, 0.01f, 0.01f), last);
    }
    // NaN beats a zero footprint: a NaN derivative gives the last level even if the other axis is 0.
    EXPECT_EQ(lod_checked(t, kNaN, kNaN, 0, 0), last);
    // Trilinear with those LODs: level 0 (a bilinear sample), or the last level's texel.
    const float u = 0.37f, v = 0.61f;
    const float bilinear0 = sample_one(t, desc_of(Filter::Bilinear, AddressMode::Wrap), u, v, 0);
    EXPECT_EQ(sample_one(t, desc_of(Filter::Trilinear, AddressMode::Wrap), u, v, lod_checked(t, 0, 0, 0, 0)), bilinear0);
    const float coarsest = sample_one(t, desc_of(Filter::LinearMipPoint, AddressMode::Wrap), u, v, last);
    EXPECT_EQ(sample_one(t, desc_of(Filter::Trilinear, AddressMode::Wrap), u, v, lod_checked(t, kInf, 0, 0, 0)), coarsest);
  }
}

}  // namespace
}  // namespace qdmr
