// Displacement techniques against the exact reference, and their termination at the extremes.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

#include <nlohmann/json.hpp>

#include "qdmr/render/render.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "kernel/displacement_test_util.hpp"
#include "kernel/traversal.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

TEST(Qdm, HitsTheBoxSurfaceExactlyWithEveryLevelUpPolicy) {
  for (QdmLevelUp policy : {QdmLevelUp::Stay, QdmLevelUp::One, QdmLevelUp::Aligned}) {
    TechniqueDesc t;
    t.kind = TechniqueKind::Qdm;
    t.refinement = QdmRefinement::None;
    t.level_up = policy;
    t.depth_scale = 0.1f;
    t.max_iterations = 100000;  // sufficient: the cap must never be what ends a ray here
    for (const Field& field : fields()) {
      const TechniqueHarness harness(field.heights, t);
      const std::vector<TechniqueRay> rs = rays(24, 7);
      const std::vector<TechniqueResult> results = harness.run(rs);
      double worst = 0.0;
      for (std::size_t i = 0; i < rs.size(); ++i) {
        const ReferenceHit ref = intersect_reference(harness.field(), t.depth_scale,
                                                     {{rs[i].u0, rs[i].v0, 0.0}, {rs[i].du, rs[i].dv, 1.0}},
                                                     ReferenceSurface::Box);
        ASSERT_TRUE(ref.hit);
        ASSERT_LT(results[i].iterations, t.max_iterations);
        worst = std::max(worst, error_texels(harness.field(), results[i], ref));
      }
      // The issue's bound. The fp32 ray itself (direction from a normalised fp32 view vector, positions
      // uv0 + d * s) is good to ~1e-5 texel here, so 1e-3 leaves room without hiding a wrong cell.
      EXPECT_LE(worst, 1e-3) << field.name << " level_up " << int(policy);
    }
  }
}

// One read per cell visited: a ray that reaches a cell's top plane descends in the same iteration (it does not
// read the cell again to find itself at its top). Straight down into a flat surface of a 2^k map the ray meets
// one top plane per level: k + 1 iterations (k + 2 when each plane cost a second read), the hit at its depth.
TEST(Qdm, ReadsEachLevelOnceOnTheWayDown) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.1f;
  t.max_iterations = 1000;
  for (int size : {1, 2, 64, 256}) {
    const int levels = std::countr_zero(unsigned(size)) + 1;
    const TechniqueHarness harness(filled(size, 0.5f), t);
    const std::vector<TechniqueResult> results = harness.run({{0.3, 0.6, 0.0, 0.0}, {0.71, 0.2, 0.0, 0.0}});
    for (const TechniqueResult& r : results) {
      EXPECT_EQ(r.iterations, levels) << size;
      EXPECT_NEAR(r.hit_depth, 0.05, 1e-7) << size;  // ds (1 - h)
    }
  }
}

TEST(Qdm, BilinearPatchRefinementHitsTheBilinearSurfaceExactly) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::BilinearPatch;
  t.depth_scale = 0.1f;
  t.max_iterations = 100000;
  for (const Field& field : fields()) {
    const TechniqueHarness harness(field.heights, t);
    const std::vector<TechniqueRay> rs = rays(24, 13);
    const std::vector<TechniqueResult> results = harness.run(rs);
    double worst = 0.0;
    for (std::size_t i = 0; i < rs.size(); ++i) {
      const ReferenceHit ref = intersect_reference(harness.field(), t.depth_scale,
                                                   {{rs[i].u0, rs[i].v0, 0.0}, {rs[i].du, rs[i].dv, 1.0}},
                                                   ReferenceSurface::Bilinear);
      ASSERT_TRUE(ref.hit);
      worst = std::max(worst, error_texels(harness.field(), results[i], ref));
    }
    // Same bound as for the box surface: the patches are solved in fp64 from the fp32 ray's traversal point,
    // so what remains is the fp32 ray (~1e-5 texel) and the fp32 hit depth.
    EXPECT_LE(worst, 1e-3) << field.name;
  }
}

TEST(Qdm, Sm3AgreesWithSm4OnSmallMaps) {
  // Up to 64 texels, fp32 cell positions are exact enough that the emulation finds the same cells.
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.1f;
  t.max_iterations = 100000;
  for (const Field& field : fields()) {
    TechniqueHarness sm4(field.heights, t);
    TechniqueHarness sm3(field.heights, t);
    sm3.set_math(MathMode::Sm3);
    const std::vector<TechniqueRay> rs = rays(16, 3);
    const auto a = sm4.run(rs), b = sm3.run(rs);
    for (std::size_t i = 0; i < rs.size(); ++i)
      EXPECT_LE(std::hypot((a[i].hit_u - b[i].hit_u) * 64, (a[i].hit_v - b[i].hit_v) * 64), 1e-3) << field.name << " " << i;
  }
}

// Far from the origin the fp32 emulation breaks where #3's math-mode study says fp32 positions do: at a texel
// position |uv| * n the fp32 spacing is 2^(floor(log2(|uv| n)) - 23) texels, and SM3's 1/64-texel nudge across a
// wall is lost once that spacing exceeds it, from |uv| * n >= 2^18 on: the cell is recomputed as the one just
// left and the ray stalls until its cap. SM4 steps integer cells and keeps going (its error then comes only from
// the fp32 ray itself).
TEST(Qdm, Sm3DivergesFromSm4WhereFp32PositionsRunOut) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.05f;
  t.max_iterations = 4096;
  struct Case {
    int size;
    double offset;
    bool diverges;
  };
  for (const Case& c : {Case{64, 1000.0, false}, Case{256, 1000.0, false}, Case{64, 10000.0, true},
                        Case{1024, 100.0, false}, Case{1024, 1000.0, true}}) {
    const Image heights = pattern(ProceduralPattern::Sine, c.size, 4);
    TechniqueHarness sm4(heights, t), sm3(heights, t);
    sm3.set_math(MathMode::Sm3);
    std::vector<TechniqueRay> rs = rays(16, 3);
    for (TechniqueRay& r : rs) r.u0 += c.offset, r.v0 += c.offset;
    const auto a = sm4.run(rs), b = sm3.run(rs);
    int differ = 0, sm4_capped = 0;
    for (std::size_t i = 0; i < rs.size(); ++i) {
      differ += a[i].hit_u != b[i].hit_u || a[i].hit_v != b[i].hit_v;
      sm4_capped += a[i].iterations >= t.max_iterations;
    }
    EXPECT_EQ(sm4_capped, 0) << c.size << " at " << c.offset;
    if (c.diverges)
      EXPECT_GT(differ, 0) << c.size << " at " << c.offset;
    else
      EXPECT_EQ(differ, 0) << c.size << " at " << c.offset;
  }
}

// math: exact computes where the ray crosses a wall or a mid line, (wall - origin) / direction, in fp64 rounded
// once; sm4 in fp32 as GPUs divide, (wall - origin) * fl(1 / direction), rounded three times. The two are the same
// function of the same floats wherever the fp32 result happens to be correctly rounded, and differ by an ulp or
// two elsewhere.
TEST(Qdm, ExactComputesWallCrossingsInFp64) {
  using simd::Float;
  int differ = 0;
  for (int wall = 1; wall <= 64; ++wall) {
    const Float w = Float(float(wall)), o = Float(0.3f), d = Float(0.7f), inv_d = Float(1.0f) / d;
    float fp32[simd::kLanes], fp64[simd::kLanes];
    crossing<false>(w, o, d, inv_d).store_unaligned(fp32);
    crossing<true>(w, o, d, inv_d).store_unaligned(fp64);
    const float reciprocal = 1.0f / 0.7f;
    EXPECT_EQ(fp32[0], (float(wall) - 0.3f) * reciprocal);
    EXPECT_EQ(fp64[0], float((double(wall) - double(0.3f)) / double(0.7f)));
    differ += fp32[0] != fp64[0];
  }
  EXPECT_GT(differ, 0);  // e.g. 5 - 0.3f is not a float: fp32 rounds it before dividing
}

// Every pair of math modes gives other hits on some rays, where the arithmetic they differ in decides, and the
// same bits where it cannot matter.
TEST(Qdm, EachPairOfMathModesDiffersWhereItsArithmeticDoes) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.05f;
  t.max_iterations = 4096;
  const auto run = [&](const Image& heights, MathMode math, double offset) {
    TechniqueHarness harness(heights, t);
    harness.set_math(math);
    std::vector<TechniqueRay> rs = rays(32, 11);
    for (TechniqueRay& r : rs) r.u0 += offset, r.v0 += offset;
    return harness.run(rs);
  };
  // How many hits differ in any bit, and the largest distance between two hits in texels of a `size` map.
  struct Difference {
    int rays = 0;
    double texels = 0.0;
  };
  const auto compare = [](const std::vector<TechniqueResult>& a, const std::vector<TechniqueResult>& b, int size) {
    Difference d;
    for (std::size_t i = 0; i < a.size(); ++i) {
      d.rays += a[i].hit_u != b[i].hit_u || a[i].hit_v != b[i].hit_v || a[i].hit_depth != b[i].hit_depth;
      d.texels = std::max(d.texels, std::hypot(a[i].hit_u - b[i].hit_u, a[i].hit_v - b[i].hit_v) * size);
    }
    return d;
  };
  // sm4 against exact: sm4 multiplies by the direction's fp32 reciprocal where exact divides in fp64 (and, in the
  // first repeat, where texel positions are finer than fp32 keeps in wall - x0, rounds the difference too), so
  // some crossings differ by an ulp or two, at every distance from the origin; the hits move by far less than a
  // texel (1e-3 texel: a thousand times the spacing of fp32 texel positions in a 1024 map's first repeats).
  const Image sine = pattern(ProceduralPattern::Sine, 1024, 4);
  for (const double offset : {0.0, 1.0, 100.0}) {
    const Difference d = compare(run(sine, MathMode::Sm4, offset), run(sine, MathMode::Exact, offset), 1024);
    EXPECT_GT(d.rays, 0) << offset;
    EXPECT_LT(d.texels, 1e-3) << offset;
  }
  // sm3 against sm4 and exact: at |uv| = 1000 its fp32 positions lose the cell (Sm3DivergesFromSm4...).
  const auto sm3_farther = run(sine, MathMode::Sm3, 1000.0);
  EXPECT_GT(compare(sm3_farther, run(sine, MathMode::Sm4, 1000.0), 1024).rays, 0);
  EXPECT_GT(compare(sm3_farther, run(sine, MathMode::Exact, 1000.0), 1024).rays, 0);
  // Near the origin: sm3 finds sm4's cells, and its crossings are sm4's.
  EXPECT_EQ(compare(run(sine, MathMode::Sm4, 0.0), run(sine, MathMode::Sm3, 0.0), 1024).rays, 0);
}

TEST(Qdm, LevelUpAfterCrossingsAvoidsDegeneratingIntoLinearSearch) {
  // The talk's failure case: a ray that descended next to a tall feature and then travels far over low ground
  // keeps stepping cell by cell at the fine level unless it goes up after crossings. One pillar on a floor,
  // grazing rays leaving the pillar's neighbourhood.
  TechniqueDesc t;
  t.kind = TechniqueKind::Qdm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.05f;
  t.max_iterations = 100000;
  const Image heights = pillar(128);
  std::vector<TechniqueRay> rs;
  for (int i = 0; i < 16; ++i) {
    const double azimuth = 2.0 * std::numbers::pi * (i + 0.5) / 16.0, reach = 1.0 / std::tan(2.0 * std::numbers::pi / 180.0);
    rs.push_back({(64.5 + 1.5 * std::cos(azimuth)) / 128.0, (64.5 + 1.5 * std::sin(azimuth)) / 128.0,
                  reach * std::cos(azimuth), reach * std::sin(azimuth)});
  }
  auto mean_iterations = [&](QdmLevelUp policy) {
    t.level_up = policy;
    double total = 0;
    for (const TechniqueResult& r : TechniqueHarness(heights, t).run(rs)) total += r.iterations;
    return total / double(rs.size());
  };
  const double stay = mean_iterations(QdmLevelUp::Stay), one = mean_iterations(QdmLevelUp::One),
               aligned = mean_iterations(QdmLevelUp::Aligned);
  EXPECT_LT(one, stay / 2) << "stay " << stay << ", one " << one;
  EXPECT_LT(aligned, stay / 2) << "stay " << stay << ", aligned " << aligned;
}

TEST(Relief, FindsTheFilteredSurfaceWithinItsSearchResolution) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Relief;
  t.depth_scale = 0.1f;
  t.linear_steps = 64;
  t.binary_steps = 8;
  const Image heights = pattern(ProceduralPattern::Sine, 64, 2);  // smooth: no feature thinner than a step
  const TechniqueHarness harness(heights, t);
  std::vector<TechniqueRay> rs;
  for (const TechniqueRay& r : rays(24, 5))
    if (std::hypot(r.du, r.dv) <= 1.0 / std::tan(30.0 * std::numbers::pi / 180.0) + 1e-9) rs.push_back(r);
  const auto results = harness.run(rs);
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const ReferenceHit ref = intersect_reference(harness.field(), t.depth_scale,
                                                 {{rs[i].u0, rs[i].v0, 0.0}, {rs[i].du, rs[i].dv, 1.0}},
                                                 ReferenceSurface::Bilinear);
    // The binary search ends in a depth bracket of depth_scale / linear_steps / 2^binary_steps; its
    // horizontal extent, in texels, bounds the error (plus 1e-3 texel of fp32 sampling).
    const double bracket = t.depth_scale / t.linear_steps / std::pow(2.0, t.binary_steps) * std::hypot(rs[i].du, rs[i].dv) * 64;
    EXPECT_LE(error_texels(harness.field(), results[i], ref), bracket + 1e-3) << i;
    EXPECT_LE(results[i].iterations, t.linear_steps + 1 + t.binary_steps);
  }
}

TEST(Pom, StaysWithinOneStepOnSmoothFieldsAndCountsItsSteps) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Pom;
  t.depth_scale = 0.1f;
  t.min_steps = 16;
  t.max_steps = 64;
  t.lod_threshold = 16.0f;  // no fade in this test
  const Image heights = pattern(ProceduralPattern::Sine, 64, 2);
  const TechniqueHarness harness(heights, t);
  // Down to 10 degrees: below that a step spans more than half a sine period and POM can jump over a crest
  // (its known failure at grazing angles, shown in docs/techniques.md).
  std::vector<TechniqueRay> rs;
  for (const TechniqueRay& r : rays(24, 9))
    if (std::hypot(r.du, r.dv) <= 1.0 / std::tan(10.0 * std::numbers::pi / 180.0) + 1e-9) rs.push_back(r);
  const auto results = harness.run(rs);
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const ReferenceHit ref = intersect_reference(harness.field(), t.depth_scale,
                                                 {{rs[i].u0, rs[i].v0, 0.0}, {rs[i].du, rs[i].dv, 1.0}},
                                                 ReferenceSurface::Bilinear);
    // POM's linear intersection lies within the last step, whose horizontal extent is
    // depth_scale / min_steps * |d| at worst (fewer steps are taken at steep views, where |d| is small).
    const double step = t.depth_scale / t.min_steps * std::hypot(rs[i].du, rs[i].dv) * 64;
    EXPECT_LE(error_texels(harness.field(), results[i], ref), step + 1e-3) << i;
    EXPECT_LE(results[i].iterations, t.max_steps + 1);
  }
}

TEST(Techniques, TerminateWithinTheirCapsAtTheExtremes) {
  std::vector<Field> extremes = {{"all0", filled(16, 0.0f)}, {"all1", filled(16, 1.0f)}, {"1x1", filled(1, 0.3f)},
                                 {"spikes", pattern(ProceduralPattern::Spikes, 64, 8)}};
  std::vector<TechniqueRay> rs = rays(8, 1);
  rs.push_back({0.5, 0.5, 1e6, 0.0});    // parallel to the surface, in effect
  rs.push_back({-1e4, 1e4, 0.3, -0.2});  // far outside [0,1]
  for (TechniqueKind kind :
       {TechniqueKind::Relief, TechniqueKind::Pom, TechniqueKind::Qdm, TechniqueKind::Csm, TechniqueKind::Rcsm})
    for (float depth_scale : {0.0f, 1e-3f, 1.0f, 100.0f})
      for (const Field& field : extremes) {
        TechniqueDesc t;
        t.kind = kind;
        t.depth_scale = depth_scale;
        t.max_iterations = 256;
        const double cap = kind == TechniqueKind::Relief ? t.linear_steps + 1 + t.binary_steps
                           : kind == TechniqueKind::Pom  ? t.max_steps + 1
                           : kind == TechniqueKind::Csm  ? t.max_iterations + 2  // + the linear refinement's samples
                           : kind == TechniqueKind::Rcsm ? t.max_iterations + t.binary_steps + 2
                                                         : t.max_iterations + 8;  // + refinement samples
        for (const TechniqueResult& r : TechniqueHarness(field.heights, t).run(rs)) {
          ASSERT_TRUE(std::isfinite(r.hit_u) && std::isfinite(r.hit_v) && std::isfinite(r.hit_depth)) << field.name;
          ASSERT_LE(r.iterations, cap) << field.name << " kind " << int(kind);
          ASSERT_GE(r.hit_depth, 0.0);
          ASSERT_LE(r.hit_depth, depth_scale * (1.0 + 1e-6));
        }
      }
}

TEST(Techniques, DepthScaleZeroGivesExactlyTheNormalMappingImage) {
  const TemporaryConeCache cache;  // csm and rcsm bake their cone maps through the cache
  const auto render_with = [](const std::string& technique) {
    std::vector<SceneOverride> sets = {{"/output/width", "160"}, {"/output/height", "90"},
                                       {"/materials/bricks/technique/name", technique}};
    if (technique != "normal") sets.push_back({"/materials/bricks/technique/depth_scale", "0"});
    return render_frame(load_scene(source_dir() / "scenes" / "plane.json", sets), RenderOptions{}).color;
  };
  const PixelBuffer normal = render_with("normal");
  for (const char* technique : {"relief", "pom", "qdm", "csm", "rcsm"}) {
    const PixelBuffer displaced = render_with(technique);
    ASSERT_EQ(displaced.size(), normal.size());
    EXPECT_EQ(0, std::memcmp(displaced.data(), normal.data(), normal.size() * sizeof(float))) << technique;
  }
}

}  // namespace
}  // namespace qdmr::test

namespace qdmr::test {
namespace {

// A red plane just below a displaced white plane: with write_depth the red plane shows where the displaced
// surface lies deeper than it; without, the white polygon hides it everywhere.
TEST(Techniques, WriteDepthLetsCloserGeometryShowThroughDeepParts) {
  const nlohmann::json document = nlohmann::json::parse(R"({
    "output": {"width": 128, "height": 128},
    "camera": {"position": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40, "near": 0.1, "far": 10},
    "lights": [{"type": "ambient", "color": [1, 1, 1], "intensity": 1}],
    "materials": {
      "displaced": {"layers": [{"albedo": {"constant": [1, 1, 1]}, "height": {"procedural": "checker", "size": 16, "cells": 4}}],
                    "technique": {"name": "qdm", "depth_scale": 0.2, "refinement": "none", "write_depth": true}},
      "red": {"layers": [{"albedo": {"constant": [1, 0, 0]}}]}
    },
    "objects": [
      {"mesh": {"type": "plane", "size": 2}, "material": "displaced"},
      {"mesh": {"type": "plane", "size": 2}, "material": "red", "transform": {"translate": [0, 0, -0.1]}}
    ]})");
  // The plane is 2 units per UV repeat, so depth 0.2 UV is 0.4 units: low checker cells lie at 0.4 below the
  // polygon, under the red plane at 0.1; high cells stay at the polygon, above it.
  auto red_fraction = [&](bool write_depth) {
    nlohmann::json doc = document;
    doc["materials"]["displaced"]["technique"]["write_depth"] = write_depth;
    const Frame frame = render_frame(load_scene_json(doc, "test.json", source_dir()), RenderOptions{});
    int red = 0, covered = 0;
    for (std::size_t i = 0; i < frame.color.size(); i += 3) {
      const bool is_red = frame.color[i] > 0.9f && frame.color[i + 1] < 0.1f;
      const bool is_white = frame.color[i] > 0.9f && frame.color[i + 1] > 0.9f;
      red += is_red;
      covered += is_red || is_white;
    }
    return double(red) / double(std::max(covered, 1));
  };
  EXPECT_EQ(red_fraction(false), 0.0);
  const double with_depth = red_fraction(true);
  // About half the cells are low; seen from straight above, red shows where the view ray reaches a low cell.
  EXPECT_GT(with_depth, 0.3);
  EXPECT_LT(with_depth, 0.7);
}

}  // namespace
}  // namespace qdmr::test

namespace qdmr::test {
namespace {

// exact_hits shades at the exact reference's hit: measured against that reference, every covered pixel is off
// by float rounding only, whatever the technique's own error; and the image differs from the traced one.
TEST(Techniques, ExactHitsShadeAtTheReferenceHit) {
  for (const char* technique : {"pom", "relief", "qdm"}) {
    const auto render_with = [&](bool exact) {
      const std::vector<SceneOverride> sets = {{"/output/width", "160"}, {"/output/height", "90"},
                                               {"/materials/bricks/technique/name", technique},
                                               {"/materials/bricks/technique/exact_hits", exact ? "true" : "false"}};
      RenderOptions options;
      options.aovs = {Aov::Depth, Aov::ErrorTexels};
      return render_frame(load_scene(source_dir() / "scenes" / "plane.json", sets), options);
    };
    const Frame traced = render_with(false), exact = render_with(true);
    const auto max_error = [](const Frame& frame) {
      float m = 0.0f;
      for (const AovImage& a : frame.aovs)
        if (a.aov == Aov::ErrorTexels)
          for (float e : a.pixels) m = std::max(m, e);
      return m;
    };
    // The hit's depth is stored in fp32 (relative rounding 6e-8 of a depth up to 0.05 UV), seen on a 512-texel
    // map at grazing rays a few texels per unit of depth long: far below 1e-2 texels.
    EXPECT_LT(max_error(exact), 1e-2f) << technique;
    EXPECT_GT(max_error(traced), 1e-2f) << technique;  // the techniques' own errors are larger: the test can fail
    EXPECT_NE(0, std::memcmp(traced.color.data(), exact.color.data(), exact.color.size() * sizeof(float))) << technique;
  }
}

}  // namespace
}  // namespace qdmr::test
