// Per-frame horizon ambient occlusion: exactly 1 on flat ground, closed forms for a pit and a V-groove, the
// direction pattern, jitter determinism, and agreement with the baked map at texel centres.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <vector>

#include "bake/ao_map.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "kernel/ambient_occlusion.hpp"
#include "bake/ao_pattern.hpp"
#include "kernel/height_surface.hpp"
#include "plan/program_choice.hpp"

namespace qdmr {
namespace {

using simd::Float;

struct AoPoint {
  float u, v, s, ds, pixel_x, pixel_y;
};

// A height map stored R32F (the heights exactly) with its max-quadtree, as a SingleLayerSurface.
class AoHarness {
public:
  AoHarness(const Image& heights, HeightFetch fetch)
      : height_(make_mip_texture(heights, TexelFormat::R32F, false, MipReduce::Box)),
        quadtree_(make_mip_texture(heights, TexelFormat::R32F, false, MipReduce::Max)),
        textures_(height_, &quadtree_, SamplerState{}, fetch),
        surface_(textures_) {}
  AoHarness(const AoHarness&) = delete;
  AoHarness& operator=(const AoHarness&) = delete;

  // One AO value per point; lanes past the end of `points` are inactive.
  std::vector<float> run(const AoParams& desc, const std::vector<AoPoint>& points) const {
    std::vector<float> out;
    for (std::size_t first = 0; first < points.size(); first += simd::kLanes) {
      alignas(64) float lane[6][simd::kLanes] = {};
      std::uint32_t active = 0;
      for (int l = 0; l < simd::kLanes && first + std::size_t(l) < points.size(); ++l) {
        const AoPoint& p = points[first + std::size_t(l)];
        const float values[6] = {p.u, p.v, p.s, p.ds, p.pixel_x, p.pixel_y};
        for (int k = 0; k < 6; ++k) lane[k][l] = values[k];
        active |= 1u << l;
      }
      const auto at = [&](int k) { return Float::load_aligned(lane[k]); };
      alignas(64) float ao[simd::kLanes];
      ambient_occlusion(surface_, desc, at(0), at(1), at(2), at(3), at(4), at(5), simd::from_bits(active))
          .store_aligned(ao);
      for (int l = 0; l < simd::kLanes && first + std::size_t(l) < points.size(); ++l) out.push_back(ao[l]);
    }
    return out;
  }

private:
  Texture height_, quadtree_;
  HeightLayerTextures textures_;
  SingleLayerSurface surface_;
};

Image filled(int size, float value) {
  Image img(size, size, 1);
  for (float& t : img.texels) t = value;
  return img;
}

HeightField field_of(const Image& img) {
  HeightField f;
  f.width = img.width;
  f.height = img.height;
  f.h.assign(img.texels.begin(), img.texels.end());
  return f;
}

// A smooth bumpy field: two sine octaves (exact in R32F, stored from the same floats the bake reads).
Image bumps(int size) {
  Image img(size, size, 1);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double a = 2 * std::numbers::pi * x / size, b = 2 * std::numbers::pi * y / size;
      img.at(x, y, 0) = float(0.5 + 0.25 * std::sin(2 * a) * std::cos(3 * b) + 0.2 * std::sin(5 * a + 7 * b));
    }
  return img;
}

// The visibility of one direction whose horizon rises `rise` (depth units) over a UV distance `distance`.
double visibility(double rise, double distance) {
  const double slope = rise / distance;
  return 1.0 - slope / std::sqrt(1.0 + slope * slope);
}

AoParams frame_params(int directions, float radius, bool coarse) {
  AoParams d;
  d.directions = directions;
  d.radius = radius;
  d.coarse = coarse;
  return d;
}

TEST(AmbientOcclusion, DirectionTableIsTheUnitCircle) {
  for (int n = ao::kMinDirections; n <= ao::kMaxDirections; ++n)
    for (int i = 0; i < n; ++i)
      for (int r = 0; r < ao::kRotations; ++r) {
        const int k = ao::direction_index(n, i, r);
        const double angle = 2 * std::numbers::pi * (i + r / double(ao::kRotations)) / n;
        // Correctly rounded floats of cos and sin are within half an ulp (<= 2^-25 for |x| <= 1) of libm's
        // double values, which are themselves good to ~1e-16: 3e-8 bounds both.
        EXPECT_NEAR(ao::kDirections.cos[std::size_t(k)], std::cos(angle), 3e-8) << n << " " << i << " " << r;
        EXPECT_NEAR(ao::kDirections.sin[std::size_t(k)], std::sin(angle), 3e-8) << n << " " << i << " " << r;
      }
  // Quarter turns are exact, so the axis directions of n = 4 have no stray components.
  EXPECT_EQ(ao::kDirections.cos[std::size_t(ao::direction_index(4, 1, 0))], 0.0f);
  EXPECT_EQ(ao::kDirections.sin[std::size_t(ao::direction_index(4, 1, 0))], 1.0f);
  EXPECT_EQ(ao::kDirections.cos[std::size_t(ao::direction_index(4, 2, 0))], -1.0f);
  EXPECT_EQ(ao::kDirections.sin[std::size_t(ao::direction_index(4, 2, 0))], 0.0f);
}

TEST(AmbientOcclusion, TapDistances) {
  AoParams d = frame_params(8, 20.0f / 64.0f, true);
  ao::Taps taps = ao::make_taps(pattern_of(d), 64, 32);  // one texel = 1/64 UV (the larger side)
  ASSERT_EQ(taps.count, 5);                  // 1, 2, 4, 8, 16 texels
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(taps.tap[std::size_t(k)].distance, float(1 << k) / 64.0f);
    EXPECT_EQ(taps.tap[std::size_t(k)].level, k);
  }
  d.coarse = false;
  taps = ao::make_taps(pattern_of(d), 64, 32);
  ASSERT_EQ(taps.count, 20);
  EXPECT_EQ(taps.tap[19].distance, 20.0f / 64.0f);
  d.radius = 1.0f;  // 256 texels of a 256 map: capped at 64 evenly spread taps
  taps = ao::make_taps(pattern_of(d), 256, 256);
  ASSERT_EQ(taps.count, ao::kMaxFineTaps);
  EXPECT_EQ(taps.tap[0].distance, 1.0f / 64.0f);
  EXPECT_EQ(taps.tap[63].distance, 1.0f);
  d.radius = 0.5f / 256.0f;  // below one texel: nothing to look at
  EXPECT_EQ(ao::make_taps(pattern_of(d), 256, 256).count, 0);
}

TEST(AmbientOcclusion, FlatSurfaceIsExactlyOpen) {
  const float h = 0.3f;
  for (HeightFetch fetch : {HeightFetch::Point, HeightFetch::Bilinear}) {
    const AoHarness harness(filled(32, h), fetch);
    std::vector<AoPoint> points;
    for (int k = 0; k < 21; ++k) {
      const float ds = 0.02f + 0.01f * float(k);
      points.push_back({0.037f * float(k) - 0.3f, 0.71f - 0.053f * float(k), ds * (1.0f - h), ds, float(k), 3.0f});
    }
    for (bool coarse : {true, false})
      for (bool jitter : {false, true}) {
        AoParams d = frame_params(7, 0.4f, coarse);
        d.jitter = jitter;
        for (float ao : harness.run(d, points)) EXPECT_EQ(ao, 1.0f);
      }
  }
}

// A pit of radius r texels and depth d (height units) around texel (c, c) of an n x n map at height 1, seen from
// its centre on the box surface (point fetch). The exact horizon of every direction is atan(D / r), D = ds * d.
TEST(AmbientOcclusion, PitCentreMatchesTheClosedForm) {
  const int n = 128, c = 64;
  const double r = 24.0, d = 0.5;
  const float ds = 0.1f;
  Image img = filled(n, 1.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      if ((x - c) * (x - c) + (y - c) * (y - c) < r * r) img.at(x, y, 0) = float(1.0 - d);
  const AoHarness harness(img, HeightFetch::Point);
  const float h0 = float(1.0 - d);
  const std::vector<AoPoint> centre{{(c + 0.5f) / n, (c + 0.5f) / n, ds * (1.0f - h0), ds, 0.0f, 0.0f}};
  const double depth = double(ds) * d;  // the rise of every tap outside the pit
  const double exact = visibility(depth, r / n);

  // Fine: taps every texel. A tap lies within sqrt(2)/2 texel of its texel's centre, and a texel is outside iff its
  // centre is at least r from the pit's centre, so the first tap outside (the horizon: the rise is constant and
  // the distance grows) is at t in [r - sqrt(2)/2, r + sqrt(2)/2 + 1) texels in every direction.
  const double half_diagonal = std::sqrt(0.5);
  for (int directions : {4, 8, 16}) {
    const float ao = harness.run(frame_params(directions, 0.5f, false), centre)[0];
    EXPECT_GE(ao, visibility(depth, (r - half_diagonal) / n)) << directions;
    EXPECT_LE(ao, visibility(depth, (r + half_diagonal + 1) / n)) << directions;
    EXPECT_NEAR(ao, exact, 0.03) << directions;  // the bounds above are exact +-0.026
  }
  // Coarse: the tap at 2^k texels reads the max over a 2^k cell holding it, whose texel centres lie within
  // sqrt(2) 2^k of the tap: it sees the rim only once (1 + sqrt(2)) 2^k >= r (k >= 4 for r = 24), and surely at
  // 2^k >= r + sqrt(2)/2 (k = 5). So each direction's horizon distance is 16 or 32 texels.
  for (int directions : {4, 8, 16}) {
    const float ao = harness.run(frame_params(directions, 0.5f, true), centre)[0];
    EXPECT_GE(ao, visibility(depth, 16.0 / n)) << directions;
    EXPECT_LE(ao, visibility(depth, 32.0 / n)) << directions;
  }
}

// A V-groove along v: heights |x| / w texels from the bottom texel (x = 0, height 0) up to 1 at |x| = w. Bilinear
// filtering of samples of a piecewise linear profile with kinks at texel centres reproduces it exactly, so from
// the bottom every direction at angle theta sees the wall slope over its whole ascent: tan(horizon) =
// ds |cos theta| / (w texels in UV), and the AO is the average of 1 - sin(atan(.)) over the n directions.
TEST(AmbientOcclusion, VGrooveBottomMatchesTheClosedForm) {
  const int n = 64, c = 32, w = 8;
  const float ds = 0.05f;
  Image img = filled(n, 1.0f);
  for (int y = 0; y < n; ++y)
    for (int x = c - w + 1; x < c + w; ++x) img.at(x, y, 0) = float(std::abs(x - c)) / float(w);
  const AoHarness harness(img, HeightFetch::Bilinear);
  const std::vector<AoPoint> bottom{{(c + 0.5f) / n, 0.5f, ds, ds, 0.0f, 0.0f}};
  for (int directions : {4, 5, 8, 12, 16}) {
    double expected = 0.0;
    for (int i = 0; i < directions; ++i)
      expected += visibility(ds * std::abs(std::cos(2 * std::numbers::pi * i / directions)), double(w) / n);
    expected /= directions;
    // Rounding only: the tap's u (u0 + dx t, fp32 near 0.5: error <= 6e-8 UV) and the sampler's u * 64 - 0.5 (<= 6e-8
    // UV) move it along a wall of slope ds / (8/64) = 0.4, so the rise is off by <= 5e-8 and the slope
    // rise / t (t >= 1/64) by <= 3.2e-6; a visibility's derivative in the slope is at most 1. 1e-5 covers that
    // and the few roundings of the weights and the average.
    EXPECT_NEAR(harness.run(frame_params(directions, 0.25f, false), bottom)[0], expected, 1e-5) << directions;
  }
  // Strength blends towards open: 1 - strength * (1 - ao).
  AoParams half = frame_params(8, 0.25f, false);
  const float full = harness.run(half, bottom)[0];
  half.strength = 0.5f;
  EXPECT_EQ(harness.run(half, bottom)[0], 1.0f - 0.5f * (1.0f - full));
  half.strength = 0.0f;
  EXPECT_EQ(harness.run(half, bottom)[0], 1.0f);
}

TEST(AmbientOcclusion, JitterRotationIsAHashOfPixelAndSeed) {
  // The SIMD hash (frame) equals the scalar one (bake), and all 16 rotations occur over a 32x32 tile.
  std::set<int> seen;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; x += simd::kLanes) {
      alignas(64) float px[simd::kLanes];
      alignas(64) std::int32_t r[simd::kLanes];
      for (int l = 0; l < simd::kLanes; ++l) px[l] = float(x + l) + 0.5f;
      ao_rotation(Float::load_aligned(px), Float(float(y) + 0.5f), 9u).store_aligned(r);
      for (int l = 0; l < simd::kLanes; ++l) {
        EXPECT_EQ(r[l], ao::rotation(std::uint32_t(x + l), std::uint32_t(y), 9u));
        seen.insert(r[l]);
      }
    }
  EXPECT_EQ(seen.size(), std::size_t(ao::kRotations));
}

TEST(AmbientOcclusion, JitterIsDeterministicPerPixel) {
  const AoHarness harness(bumps(64), HeightFetch::Bilinear);
  AoParams d = frame_params(4, 0.2f, false);
  d.jitter = true;
  d.seed = 5;
  std::vector<AoPoint> points;
  for (int k = 0; k < 40; ++k) {
    const float u = 0.013f * float(k * 7 % 40), v = 0.021f * float(k);
    points.push_back({u, v, 0.1f * 0.6f, 0.1f, float(k % 9) + 0.5f, float(k / 9) + 0.5f});
  }
  const std::vector<float> a = harness.run(d, points), b = harness.run(d, points);
  EXPECT_EQ(a, b);
  // Each lane alone, in another batch position: the same bits (nothing but its own pixel and the seed counts).
  for (std::size_t k = 0; k < points.size(); k += 3) {
    const std::vector<AoPoint> alone{points[(k + 1) % points.size()], points[(k + 2) % points.size()], points[k]};
    EXPECT_EQ(harness.run(d, alone)[2], a[k]) << k;
  }
  // Another seed rotates most pixels' directions differently.
  d.seed = 6;
  const std::vector<float> c = harness.run(d, points);
  int differ = 0;
  for (std::size_t k = 0; k < a.size(); ++k) differ += a[k] != c[k];
  EXPECT_GE(differ, 30);  // 15/16 of 40 pixels get another rotation; a few may coincide in value
  // A pixel whose rotation is 0 sees the unjittered directions.
  AoParams plain = d;
  plain.jitter = false;
  const std::vector<float> unjittered = harness.run(plain, points);
  for (std::size_t k = 0; k < points.size(); ++k)
    if (ao::rotation(std::uint32_t(points[k].pixel_x), std::uint32_t(points[k].pixel_y), d.seed) == 0) {
      EXPECT_EQ(c[k], unjittered[k]) << k;
    }
}

// The bake evaluates the same pattern in double at texel centres on the bilinear surface (fine) or on the max
// pyramid (coarse); the frame AO at the same points, with s from the texel's own height, agrees to rounding.
TEST(AmbientOcclusion, FrameMatchesTheBakeAtTexelCentres) {
  const int n = 32;
  const float ds = 0.05f;
  const Image img = bumps(n);
  const HeightField field = field_of(img);
  const AoHarness harness(img, HeightFetch::Bilinear);
  std::vector<AoPoint> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      points.push_back({(float(i) + 0.5f) / n, (float(j) + 0.5f) / n, ds * (1.0f - img.at(i, j, 0)), ds,
                        float(i) + 0.5f, float(j) + 0.5f});
  for (bool coarse : {false, true})
    for (bool jitter : {false, true}) {
      AoDesc d;  // one AO asked of a material, baked and traced per frame
      d.directions = jitter ? 5 : 8;
      d.radius = 0.3f;
      d.coarse = coarse;
      d.jitter = jitter;
      d.seed = 3;
      const Image baked = bake_ao_map(field, ds, d);
      const std::vector<float> frame = harness.run(ao_params(d), points);
      double worst = 0.0;
      for (int k = 0; k < n * n; ++k) worst = std::max(worst, std::abs(double(frame[std::size_t(k)]) - baked.texels[std::size_t(k)]));
      // fp32 against fp64 on the same heights. The fp32 tap position u0 + d t is off by <= 2e-7 UV; the bumps'
      // slope is at most 2 pi (0.25 * 5 + 0.2 * 9) < 20 height units per UV (the bilinear surface's is lower), so a
      // rise is off by <= ds * 20 * 2e-7 = 2e-7 and a slope rise / t (t >= 1/32) by <= 6.4e-6; a visibility moves
      // by no more. s, the heights and the average round at ~1e-7. Coarse taps would pick another cell if one fell
      // within rounding of a cell edge (an error of a whole cell's height): none does at these texel centres.
      EXPECT_LE(worst, 1e-5) << coarse << jitter;
      double mean = 0.0;
      for (float a : frame) mean += a;
      EXPECT_LT(mean / (n * n), 0.99) << "the bumps must occlude, or the comparison says nothing";
    }
}

}  // namespace
}  // namespace qdmr
