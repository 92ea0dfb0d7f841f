// Cone step mapping (csm: conservative cones) and relaxed cone step mapping (rcsm) against the exact reference on
// the box surface, and their iteration counts against relief's linear search.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "kernel/displacement_test_util.hpp"

namespace qdmr::test {
namespace {

// The box-surface hit of the reference for ray r.
ReferenceHit box_hit(const TechniqueHarness& harness, float depth_scale, const TechniqueRay& r) {
  return intersect_reference(harness.field(), depth_scale, {{r.u0, r.v0, 0.0}, {r.du, r.dv, 1.0}},
                             ReferenceSurface::Box);
}

// Terraces of 6 texels on a 24x24 map: not a power of two, so wrap addressing goes by modulo.
Image steps_npot() {
  Image img(24, 24, 1);
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) img.at(x, y, 0) = float((x / 6 + y / 6) % 4) / 3.0f;
  return img;
}

std::vector<Field> cone_fields() {
  std::vector<Field> out = fields();
  out.push_back({"steps 24x24", steps_npot()});  // not a power of two: wrap by modulo
  return out;
}

TEST(ConeStep, CsmHitsTheBoxSurfaceExactly) {
  TechniqueDesc t;
  t.kind = TechniqueKind::Csm;
  t.refinement = QdmRefinement::None;
  t.depth_scale = 0.1f;
  t.max_iterations = 100000;  // sufficient: the cap must never be what ends a ray here
  for (const Field& field : cone_fields()) {
    const TechniqueHarness harness(field.heights, t);
    const std::vector<TechniqueRay> rs = rays(24, 7);
    const std::vector<TechniqueResult> results = harness.run(rs);
    double worst = 0.0;
    for (std::size_t i = 0; i < rs.size(); ++i) {
      const ReferenceHit ref = box_hit(harness, t.depth_scale, rs[i]);
      ASSERT_TRUE(ref.hit);
      ASSERT_LT(results[i].iterations, t.max_iterations);
      worst = std::max(worst, error_texels(harness.field(), results[i], ref));
    }
    // As for QDM: the fp32 ray (direction from a normalised fp32 view vector, positions uv0 + d * s, wall and
    // cone-exit solves in fp32) is good to ~1e-5 texel here; 1e-3 leaves room without hiding a wrong texel.
    EXPECT_LE(worst, 1e-3) << field.name;
  }
}

TEST(ConeStep, RcsmHitsTheBoxSurfaceWithinTheBinarySearchBracket) {
  for (int binary_steps : {6, 20}) {
    TechniqueDesc t;
    t.kind = TechniqueKind::Rcsm;
    t.refinement = QdmRefinement::None;
    t.depth_scale = 0.1f;
    t.binary_steps = binary_steps;
    t.max_iterations = 100000;
    for (const Field& field : cone_fields()) {
      const TechniqueHarness harness(field.heights, t);
      const std::vector<TechniqueRay> rs = rays(24, 7);
      const std::vector<TechniqueResult> results = harness.run(rs);
      for (std::size_t i = 0; i < rs.size(); ++i) {
        const ReferenceHit ref = box_hit(harness, t.depth_scale, rs[i]);
        ASSERT_TRUE(ref.hit);
        ASSERT_LT(results[i].iterations, t.max_iterations);
        // A relaxed step that ends below the surface entered it once and has not left it (cone_map.hpp), so
        // "below the box surface" is false before the first hit and true after it within the step: the search
        // keeps the hit in [lo, hi] and returns hi. The step lies within [0, depth_scale], so after n halvings
        // the bracket is at most depth_scale / 2^n deep, |d| depth_scale / 2^n in UV, times W in texels. Hits
        // on a texel top reached before its wall, and rays starting in the surface, are exact. + 1e-3 texel of
        // fp32 as for csm.
        const double bracket = t.depth_scale / std::pow(2.0, binary_steps) * std::hypot(rs[i].du, rs[i].dv) *
                               harness.field().width;
        EXPECT_LE(error_texels(harness.field(), results[i], ref), bracket + 1e-3)
            << field.name << " binary_steps " << binary_steps << " ray " << i;
      }
    }
  }
}

TEST(ConeStep, FewerIterationsThanReliefForTheSameAccuracy) {
  // A smooth field, rays from 60 down to 3 degrees. The same accuracy on the box surface: relief needs a sample
  // per texel along the ray (a coarser linear search can step over a one-texel column, so it is not exact in
  // general) and then 10 halvings to reach 1e-3 texel; csm is exact by construction, rcsm halves its last step
  // 10 times. Exact box cones are 0 on every texel with a higher 8-neighbour (conservative) or with a stepping-down
  // wall of a higher texel next to it (relaxed), which is most of the rising flanks of a smooth field: there the
  // march crosses one wall per iteration, about as often as the linear search samples. So the gain is the
  // halvings relief always pays plus the skips over the falling flanks: measured csm/relief 0.27 (60 degrees) to
  // 0.95 (3 degrees), 0.74 over all four; rcsm 0.86 (its relaxed steps save little here and it pays the
  // halvings too). The bounds leave that measured margin to the deterministic (fixed rays, bit-exact) counts.
  const Image heights = pattern(ProceduralPattern::Sine, 64, 2);
  const float depth_scale = 0.1f;
  double csm = 0, rcsm = 0, relief = 0;
  for (double elevation : {60.0, 30.0, 10.0, 3.0}) {
    const double reach = 1.0 / std::tan(elevation * std::numbers::pi / 180.0);
    std::vector<TechniqueRay> rs;
    for (const TechniqueRay& r : rays(32, 13))
      if (std::abs(std::hypot(r.du, r.dv) - reach) < 1e-9) rs.push_back(r);
    ASSERT_EQ(rs.size(), 32u);
    auto mean_iterations = [&](TechniqueDesc t) {
      t.depth_scale = depth_scale;
      t.refinement = QdmRefinement::None;
      t.binary_steps = 10;
      t.max_iterations = 100000;
      double total = 0;
      for (const TechniqueResult& r : TechniqueHarness(heights, t, Filter::Point).run(rs)) total += r.iterations;
      return total / double(rs.size());
    };
    TechniqueDesc t;
    t.kind = TechniqueKind::Csm;
    const double c = mean_iterations(t);
    t.kind = TechniqueKind::Rcsm;
    const double rc = mean_iterations(t);
    t.kind = TechniqueKind::Relief;
    t.linear_steps = int(std::ceil(reach * depth_scale * heights.width));
    const double re = mean_iterations(t);
    csm += c;
    rcsm += rc;
    relief += re;
  }
  EXPECT_LT(csm, 0.8 * relief) << "csm " << csm << ", relief " << relief;
  EXPECT_LT(rcsm, 0.9 * relief) << "rcsm " << rcsm << ", relief " << relief;
}

}  // namespace
}  // namespace qdmr::test
