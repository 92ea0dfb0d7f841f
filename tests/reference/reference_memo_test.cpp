// The remembered exact reference: a hit from the memo is the hit intersect_reference computes, bit for bit, for
// fields of the same content, whatever the memo forgot; frames drawn with a memo equal frames drawn without.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <memory>
#include <random>

#include "qdmr/reference/reference_memo.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"

namespace qdmr {
namespace {

bool same(const ReferenceHit& a, const ReferenceHit& b) {
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  return a.hit == b.hit && bits(a.t) == bits(b.t) && bits(a.point.x) == bits(b.point.x) &&
         bits(a.point.y) == bits(b.point.y) && bits(a.point.z) == bits(b.point.z) &&
         a.inside_at_start == b.inside_at_start && a.cells_visited == b.cells_visited;
}

std::shared_ptr<const HeightField> random_field(std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto field = std::make_shared<HeightField>();
  field->width = 37;
  field->height = 23;
  field->h = ZeroedBuffer<double>(std::size_t(field->width) * std::size_t(field->height));
  for (double& h : field->h) h = unit(random);
  return field;
}

std::vector<SurfaceRay> random_rays(int count) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uv(-2.0, 2.0), slope(-3.0, 3.0);
  std::vector<SurfaceRay> rays;
  for (int i = 0; i < count; ++i) rays.push_back({{uv(random), uv(random), 0.0}, {slope(random), slope(random), 1.0}});
  rays.push_back({{0.25, 0.5, 0.0}, {0.0, 0.0, 1.0}});
  rays.push_back({{0.25, 0.5, 0.0}, {-0.0, 0.0, 1.0}});  // -0 is another ray to the traversal: its own entry
  return rays;
}

TEST(ReferenceMemo, HitsAreTheFunctionsBitForBit) {
  const auto field = random_field(1);
  ReferenceMemo memo;
  const std::uint64_t id = memo.field_id(field);
  const std::vector<SurfaceRay> rays = random_rays(400);
  for (int pass = 0; pass < 2; ++pass)
    for (ReferenceSurface surface : {ReferenceSurface::Box, ReferenceSurface::Bilinear})
      for (const SurfaceRay& ray : rays)
        for (double depth : {0.05, 0.3})
          ASSERT_TRUE(same(memo.intersect(id, *field, depth, ray, surface, 1 << 16),
                           intersect_reference(*field, depth, ray, surface, 1 << 16)));
  const std::uint64_t calls = 2 * rays.size() * 2;
  EXPECT_EQ(memo.misses(), calls);  // the first pass computed every one (the -0 ray too) ...
  EXPECT_EQ(memo.hits(), calls);    // ... the second remembered every one
}

TEST(ReferenceMemo, FieldsShareHitsByContent) {
  ReferenceMemo memo;
  const auto a = random_field(1), same_content = random_field(1), other = random_field(2);
  const std::uint64_t id = memo.field_id(a);
  EXPECT_EQ(memo.field_id(a), id);
  EXPECT_EQ(memo.field_id(same_content), id);
  EXPECT_NE(memo.field_id(other), id);
  auto clamped = std::make_shared<HeightField>(*a);
  clamped->address = AddressMode::Clamp;
  EXPECT_NE(memo.field_id(clamped), id);
  // Registered again after it was forgotten (the memo holds the last 8 fields): a new id, never an old one.
  for (std::uint32_t seed = 10; seed < 20; ++seed) memo.field_id(random_field(seed));
  const std::uint64_t again = memo.field_id(a);
  EXPECT_NE(again, id);
  const SurfaceRay ray{{0.3, 0.7, 0.0}, {1.5, -0.5, 1.0}};
  EXPECT_TRUE(same(memo.intersect(again, *a, 0.2, ray, ReferenceSurface::Bilinear, 1 << 16),
                   intersect_reference(*a, 0.2, ray, ReferenceSurface::Bilinear, 1 << 16)));
}

TEST(ReferenceMemo, AFullMemoForgetsAndStaysRight) {
  const auto field = random_field(3);
  ReferenceMemo memo(4096);  // a few entries per shard
  const std::uint64_t id = memo.field_id(field);
  const std::vector<SurfaceRay> rays = random_rays(300);
  for (int pass = 0; pass < 2; ++pass)
    for (const SurfaceRay& ray : rays)
      ASSERT_TRUE(same(memo.intersect(id, *field, 0.2, ray, ReferenceSurface::Box, 1 << 16),
                       intersect_reference(*field, 0.2, ray, ReferenceSurface::Box, 1 << 16)));
  EXPECT_GT(memo.misses(), rays.size());  // it forgot some between the passes
}

// A study's untimed frames: the error AOVs, then the image at the exact hits, for techniques that trace the box and
// the bilinear surface, through one memo shared by two renderers; the same bits as renderers without it.
TEST(ReferenceMemo, FramesEqualFramesWithoutIt) {
  RenderOptions plain, memoised;
  plain.threads = memoised.threads = 2;
  memoised.reference_memo = std::make_shared<ReferenceMemo>();
  Renderer with(memoised), also_with(memoised), without(plain);
  const std::vector<Aov> aovs = {Aov::ErrorTexels, Aov::Missed};
  for (const char* technique : {"qdm", "pom", "relief"}) {
    SceneDesc scene = test::small_scene("plane", {{"/materials/bricks/technique/name", technique}}, 96, 54);
    with.set_scene(scene, aovs);
    without.set_scene(scene, aovs);
    const Frame& a = with.draw();
    const Frame& b = without.draw();
    ASSERT_EQ(a.aovs.size(), 2u);
    EXPECT_TRUE(test::same_bits(a.color, b.color)) << technique;
    for (std::size_t i = 0; i < 2; ++i) EXPECT_TRUE(test::same_bits(a.aovs[i].pixels, b.aovs[i].pixels)) << technique;
    const std::uint64_t hits = memoised.reference_memo->hits();
    for (MaterialDesc& material : scene.materials) material.technique.exact_hits = true;
    also_with.set_scene(scene, {});
    without.set_scene(scene, {});
    EXPECT_TRUE(test::same_bits(also_with.draw().color, without.draw().color)) << technique;
    EXPECT_GT(memoised.reference_memo->hits(), hits) << technique;  // the exact hits came from the error frame's
  }
}

}  // namespace
}  // namespace qdmr
