// The plan drives the frame: for every shipped scene, prepare() builds exactly the items the plan lists (and
// `qdmr plan` prints), in the plan's order; a second prepare with the first as `previous` builds nothing; a change
// that touches no asset (the camera) re-uses everything and one that does rebuilds only what depends on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "cli/cli_test_util.hpp"
#include "kernel/kernel.hpp"
#include "prepare/assets.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "texture/pattern_reuse.hpp"

namespace qdmr::test {
namespace {

// The scene as the shipped file says, data paths relocated like the CLI tests do.
SceneDesc load_shipped(const ShippedScene& scene, std::vector<SceneOverride> overrides = {}) {
  const std::vector<std::string> args = scene_args(scene);
  for (std::size_t i = 1; i + 1 < args.size(); i += 2) overrides.push_back(parse_override(args[i + 1]));
  overrides.push_back({"/output/width", "64"});
  overrides.push_back({"/output/height", "36"});
  return load_scene(args[0], overrides);
}

class PreparePlan : public testing::TestWithParam<ShippedScene> {};

TEST_P(PreparePlan, BuildsExactlyWhatThePlanLists) {
  const ShippedScene& shipped = GetParam();
  if (shipped.needs_data && !have_data()) GTEST_SKIP() << shipped.name << " needs QDMR_DATA_DIR=" << data_dir();
  const SceneDesc scene = load_shipped(shipped);
  // With the error AOVs the displacement materials also need their exact references (height fields, combined
  // surfaces): both plans must hold.
  std::set<std::string> shading_items[2];  // [with no AOVs]: the blends' trees and AO maps
  for (const std::vector<Aov>& aovs : {std::vector<Aov>{}, std::vector<Aov>{Aov::ErrorTexels}}) {
    const FramePlan plan = plan_frame(scene, PlanOptions{aovs});
    const std::vector<std::string> items = plan.items();
    EXPECT_EQ(std::set<std::string>(items.begin(), items.end()).size(), items.size()) << "an item is listed twice";
    const Assets assets = prepare(plan, kernel_for(resolve_isa(Isa::Auto)));
    EXPECT_EQ(assets.built, items) << shipped.name;
    EXPECT_TRUE(assets.reused.empty());
    ASSERT_EQ(assets.meshes.size(), plan.meshes.size());
    ASSERT_EQ(assets.textures.size(), plan.textures.size());
    ASSERT_EQ(assets.derived.size(), plan.derived.size());
    // Each texture holds what the plan counts for it: chain, decoded copy, wrap footprints.
    for (std::size_t i = 0; i < plan.textures.size(); ++i)
      EXPECT_EQ(plan.textures[i].bytes, assets.textures[i]->bytes()) << shipped.name << " " << plan.textures[i].where;
    for (std::size_t i = 0; i < plan.derived.size(); ++i) {
      const DerivedAsset& d = assets.derived[i];
      EXPECT_TRUE(d.texture || d.field || d.cones || d.twin_texels) << plan.derived[i].key << " was not built";
      if (plan.derived[i].kind == DerivedKind::TwinTexels) {
        // Interleaved albedo and normal map: as many floats as the albedo's decoded copy, none of them missing.
        ASSERT_TRUE(d.twin_texels) << plan.derived[i].key;
        EXPECT_FALSE(d.twin_texels->empty()) << plan.derived[i].key;
        EXPECT_EQ(plan.derived[i].bytes, d.twin_texels->size() * sizeof(float)) << plan.derived[i].key;
      }
      if (plan.derived[i].kind == DerivedKind::CombinedQuadtree) {
        // What the plan counts for it: the tree, the layers' level-0 heights side by side and the blended
        // level-0 values of the period (every shipped blend's layers keep decoded copies and are square, so it
        // has both), from which the tree and the AO map are made as floats: no fp64 field (and no separate fp64
        // combined surface: no shipped blend asks for error AOVs).
        ASSERT_TRUE(d.layer_heights) << plan.derived[i].key;
        ASSERT_TRUE(d.box_values) << plan.derived[i].key;
        EXPECT_FALSE(d.field) << plan.derived[i].key;
        EXPECT_EQ(plan.derived[i].inputs.size(), 1u) << plan.derived[i].key;  // the weights only
        EXPECT_EQ(plan.derived[i].bytes, d.texture->bytes() + d.layer_heights->texels.size() * sizeof(float) +
                                             d.box_values->size() * sizeof(float));
      }
      // The fp64 combined surface only for the exact reference; the tree and the AO map are the same items
      // either way, so error AOVs leave the colour's bits alone.
      if (aovs.empty()) {
        EXPECT_NE(plan.derived[i].kind, DerivedKind::CombinedSurface) << plan.derived[i].key;
      }
      if (plan.derived[i].kind == DerivedKind::CombinedQuadtree || plan.derived[i].kind == DerivedKind::BlendAoMap)
        shading_items[aovs.empty()].insert(plan.derived[i].key);
    }
    // Prepared again with the first assets as the previous ones: nothing is built, everything shared.
    const Assets again = prepare(plan, kernel_for(resolve_isa(Isa::Auto)), &assets, &plan);
    EXPECT_TRUE(again.built.empty());
    EXPECT_EQ(again.reused, items);
    for (std::size_t i = 0; i < assets.textures.size(); ++i) EXPECT_EQ(again.textures[i], assets.textures[i]);
  }
  EXPECT_EQ(shading_items[0], shading_items[1]) << shipped.name;
}

INSTANTIATE_TEST_SUITE_P(, PreparePlan, testing::ValuesIn(shipped_scenes()), scene_name);

TEST(PrepareReuse, ThePlanNamesThePatternsAskedForTwiceAndCountsThem) {
  // The terrain: each of the four layers' albedos is coloured by the pattern its heights are made of, and the blend
  // weights' terrain heights are the mesh's height map; the weights' own noise is asked for once.
  const FramePlan terrain = plan_frame(load_shipped(ShippedScene{"terrain", false}));
  EXPECT_EQ(terrain.reused_patterns.size(), 5u);
  EXPECT_EQ(terrain.reused_pattern_bytes, 5 * kept_pattern_bytes(512));
  const std::set<std::string> keys(terrain.reused_patterns.begin(), terrain.reused_patterns.end());
  EXPECT_TRUE(keys.count(procedural_key(terrain.scene.objects.at(0).mesh.height_map.procedural)));
  // Counted with the textures' working memory (held until they are built).
  EXPECT_GE(terrain.texture_working_bytes, terrain.reused_pattern_bytes);
  // A pattern larger than kMaxReusedPatternSide is never kept, so never counted; nor is a spec asked for once.
  const FramePlan big = plan_frame(load_shipped(
      ShippedScene{"terrain", false}, {{"/objects/0/mesh/height_map/size", "2048"},
                                       {"/materials/ground/blend/weights/height/size", "2048"}}));
  EXPECT_EQ(big.reused_patterns.size(), 4u);
  const FramePlan apart =
      plan_frame(load_shipped(ShippedScene{"terrain", false}, {{"/objects/0/mesh/height_map/seed", "12"}}));
  EXPECT_EQ(apart.reused_patterns.size(), 4u);
  EXPECT_EQ(apart.reused_pattern_bytes, 4 * kept_pattern_bytes(512));
}

TEST(PrepareReuse, ObjMaterialsAreKnownAfterLoad) {
  const SceneDesc scene = load_shipped({"objects", false});
  const FramePlan plan = plan_frame(scene);
  // The torus knot has no material of its own: its MTL material joins the plan, named after the object.
  const auto knot = std::find_if(plan.materials.begin(), plan.materials.end(),
                                 [](const MaterialPlan& m) { return m.name == "knot/knot"; });
  ASSERT_NE(knot, plan.materials.end()) << plan.describe();
  EXPECT_NE(knot->where.find("torus_knot.obj"), std::string::npos) << knot->where;
  EXPECT_GE(knot->layers.at(0).albedo, 0);
  const MeshPlan& mesh = plan.meshes.at(3);
  EXPECT_EQ(mesh.object, "knot");
  EXPECT_GT(mesh.triangles, 0u);  // counted from the mesh read at load, not estimated
  EXPECT_EQ(plan.materials.at(mesh.mtl_materials.at(0)).name, "knot/knot");
}

TEST(PrepareReuse, ACameraChangeRebuildsNothingADepthScaleChangeOnlyItsDerivedData) {
  const ShippedScene csm{"pom_vs_qdm_depth_1.0", false};
  const SceneDesc base = load_shipped(csm, {{"/materials/surface/technique/name", "\"csm\""}});
  const FramePlan plan = plan_frame(base);
  const Assets assets = prepare(plan, kernel_for(resolve_isa(Isa::Auto)));

  const SceneDesc moved = load_shipped(csm, {{"/materials/surface/technique/name", "\"csm\""}, {"/camera/fov_deg", "20"}});
  const FramePlan moved_plan = plan_frame(moved);
  EXPECT_EQ(moved_plan.items(), plan.items());
  EXPECT_TRUE(prepare(moved_plan, kernel_for(resolve_isa(Isa::Auto)), &assets, &plan).built.empty());

  // The cone map is baked from the heights alone: a new depth scale keeps it; new heights rebuild it.
  const SceneDesc deeper =
      load_shipped(csm, {{"/materials/surface/technique/name", "\"csm\""}, {"/materials/surface/technique/depth_scale", "0.2"}});
  const FramePlan deeper_plan = plan_frame(deeper);
  EXPECT_TRUE(prepare(deeper_plan, kernel_for(resolve_isa(Isa::Auto)), &assets, &plan).built.empty());
  const SceneDesc other = load_shipped(
      csm, {{"/materials/surface/technique/name", "\"csm\""}, {"/materials/surface/layers/0/height/seed", "77"}});
  const FramePlan other_plan = plan_frame(other);
  const Assets rebuilt = prepare(other_plan, kernel_for(resolve_isa(Isa::Auto)), &assets, &plan);
  ASSERT_FALSE(rebuilt.built.empty());
  // (The interleaved albedo and normal map hold the normal map, made from the heights.)
  for (const std::string& item : rebuilt.built)
    EXPECT_TRUE(item.find("texture height") == 0 || item.find("texture normal") == 0 || item.find("texture albedo") == 0 ||
                item.find("height_field") == 0 || item.find("cone_map") == 0 || item.find("twin_texels") == 0)
        << item;
}

}  // namespace
}  // namespace qdmr::test
