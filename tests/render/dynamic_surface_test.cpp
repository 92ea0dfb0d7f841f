// Dynamic surfaces (issue #58): a height that changes with time. The plan marks exactly the items made from it as
// dynamic (a still scene has none), a warm frame rebuilds exactly those, and what it rebuilds equals a build from
// scratch; one frame of a dynamic height equals the same height as a still texture; a frame of a sequence equals
// the frame rendered alone, on any thread count.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "cli/cli_test_util.hpp"
#include "kernel/kernel.hpp"
#include "prepare/assets.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "support/frames.hpp"

namespace qdmr::test {
namespace {

// scenes/water.json small: 64² waves (its shortest wave has 17 cycles per repeat, below 64's Nyquist of 32).
SceneDesc water(std::vector<SceneOverride> overrides = {}) {
  overrides.insert(overrides.begin(), {"/materials/water/layers/0/height/size", "64"});
  return small_scene("water", std::move(overrides), 96, 54);
}

// The same waves standing still (every speed 0): a still texture.
SceneDesc still_water() {
  std::vector<SceneOverride> still;
  for (int i = 0; i < 4; ++i) still.push_back({"/materials/water/layers/0/height/waves/" + std::to_string(i) + "/speed", "0"});
  return water(still);
}

TEST(DynamicSurface, TheWavesAreTimeDependentAndTheirStillTwinIsNot) {
  EXPECT_TRUE(water().time_dependent());
  EXPECT_FALSE(still_water().time_dependent());
  EXPECT_FALSE(small_scene("plane", {}, 8, 8).time_dependent());
}

TEST(DynamicSurface, OneFrameEqualsTheSameHeightAsAStillTexture) {
  // Frame 0 is t = 0: the moving waves are where the still ones are, and so are every derived item and pixel.
  const Frame dynamic = render_with_threads(scene_at_frame(water(), 0), 2);
  const Frame still = render_with_threads(still_water(), 2);
  EXPECT_TRUE(same_bits(dynamic.color, still.color));
  // The textures too, byte for byte (a dynamic height's level 0 is made once for all its textures; a still one's
  // once per texture).
  const FramePlan dynamic_plan = plan_frame(scene_at_frame(water(), 0)), still_plan = plan_frame(still_water());
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  const Assets a = prepare(dynamic_plan, kernel), b = prepare(still_plan, kernel);
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (std::size_t i = 0; i < a.textures.size(); ++i) {
    EXPECT_EQ(a.textures[i]->storage, b.textures[i]->storage) << still_plan.textures[i].where;
    EXPECT_EQ(a.textures[i]->linear, b.textures[i]->linear) << still_plan.textures[i].where;
    EXPECT_EQ(a.textures[i]->wrap_footprints, b.textures[i]->wrap_footprints) << still_plan.textures[i].where;
  }
  // And a later frame is another image (the test can fail).
  EXPECT_FALSE(same_bits(render_with_threads(scene_at_frame(water(), 5), 2).color, still.color));
}

TEST(DynamicSurface, AScrollAtTimeZeroReadsTheStillPattern) {
  ProceduralDesc cobbles;
  cobbles.pattern = ProceduralPattern::Cobbles;
  cobbles.size = 64;
  ProceduralDesc scrolled = cobbles;
  scrolled.scroll = {0.25f, -0.1f};
  ASSERT_TRUE(time_dependent(scrolled));
  const Image a = generate_procedural(cobbles), b = generate_procedural(scrolled);
  EXPECT_TRUE(std::equal(a.texels.begin(), a.texels.end(), b.texels.begin()));
  // A quarter repeat later along u at 1 repeat/s... 0.25 s with 0.25 repeats/s moves the pattern 1/16 repeat =
  // 4 texels exactly (a power-of-two fraction: the texel centres land on texel centres, so the values are equal).
  scrolled.scroll = {0.25f, 0.0f};
  scrolled.time = 0.25;
  const Image moved = generate_procedural(scrolled);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) ASSERT_EQ(moved.at(x, y, 0), a.at((x + 64 - 4) % 64, y, 0)) << x << "," << y;
}

// Frames 0 .. last of `scene` drawn one after the other by one renderer on two threads, as `qdmr render --frames`
// draws them; the renderer, its last frame drawn.
std::unique_ptr<Renderer> draw_sequence(const SceneDesc& scene, int last) {
  RenderOptions options;
  options.threads = 2;
  auto renderer = std::make_unique<Renderer>(options);
  for (int n = 0; n <= last; ++n) {
    renderer->set_scene(scene_at_frame(scene, n));
    renderer->draw();
  }
  return renderer;
}

TEST(DynamicSurface, AFrameOfASequenceEqualsTheFrameAloneOnAnyThreadCount) {
  const SceneDesc scene = water();
  const std::unique_ptr<Renderer> sequence = draw_sequence(scene, 3);
  const Frame& third = sequence->frame();
  for (int threads : {1, 2, 3})
    EXPECT_TRUE(same_bits(third.color, render_with_threads(scene_at_frame(scene, 3), threads).color)) << threads;
}

// The items of `plan` whose lines are in `lines`, as "purpose where" / "kind where" for messages.
std::set<std::string> described(const FramePlan& plan, const std::vector<std::string>& lines) {
  std::set<std::string> out;
  for (const std::string& line : lines) {
    for (const TextureRequest& t : plan.textures)
      if (line == "texture " + t.key) out.insert(std::string(purpose_name(t.purpose)) + (t.reduce == MipReduce::Max ? " max" : ""));
    for (const DerivedPlan& d : plan.derived)
      if (line == d.key) out.insert(derived_kind_name(d.kind));
  }
  return out;
}

TEST(DynamicSurface, ThePlanMarksExactlyTheTimeDependentItems) {
  // The waves' heights, their max-quadtree and the normals from them; not the constant albedo nor the plane.
  const FramePlan plan = plan_frame(water());
  EXPECT_EQ(described(plan, plan.dynamic_items()), (std::set<std::string>{"height", "height max", "normal"}));
  // Baked AO and error AOVs add the fp64 field and the AO map made from the heights.
  const FramePlan with_ao = plan_frame(water({{"/materials/water/ao", R"({"mode": "baked"})"}}), PlanOptions{{Aov::ErrorTexels}});
  EXPECT_EQ(described(with_ao, with_ao.dynamic_items()),
            (std::set<std::string>{"height", "height max", "normal", "height_field", "layer_ao_map"}));
  EXPECT_TRUE(plan_frame(still_water()).dynamic_items().empty());
}

TEST(DynamicSurface, StillScenesHaveNoDynamicItems) {
  for (const ShippedScene& shipped : shipped_scenes()) {
    if (shipped.name == "water" || (shipped.needs_data && !have_data())) continue;
    const std::vector<std::string> args = scene_args(shipped);
    std::vector<SceneOverride> overrides;
    for (std::size_t i = 1; i + 1 < args.size(); i += 2) overrides.push_back(parse_override(args[i + 1]));
    EXPECT_TRUE(plan_frame(load_scene(args[0], overrides)).dynamic_items().empty()) << shipped.name;
  }
}

TEST(DynamicSurface, AWarmFrameRebuildsExactlyTheDynamicItemsAsFromScratch) {
  const SceneDesc scene = water({{"/materials/water/ao", R"({"mode": "baked"})"}});
  const FramePlan first = plan_frame(scene_at_frame(scene, 0)), second = plan_frame(scene_at_frame(scene, 1));
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  const Assets warm0 = prepare(first, kernel);
  const Assets warm1 = prepare(second, kernel, &warm0, &first);
  EXPECT_EQ(warm1.built, second.dynamic_items());
  // Everything the warm frame holds (rebuilt or kept) equals a build of frame 1 from scratch: the quadtree's
  // levels, the decoded copies and footprints, the normals and the AO map, byte for byte.
  const Assets scratch = prepare(second, kernel);
  for (std::size_t i = 0; i < second.textures.size(); ++i) {
    const Texture &a = *warm1.textures[i], &b = *scratch.textures[i];
    EXPECT_EQ(a.storage, b.storage) << second.textures[i].where;
    EXPECT_EQ(a.linear, b.linear) << second.textures[i].where;
    EXPECT_EQ(a.wrap_footprints, b.wrap_footprints) << second.textures[i].where;
  }
  for (std::size_t i = 0; i < second.derived.size(); ++i) {
    const DerivedAsset &a = warm1.derived[i], &b = scratch.derived[i];
    if (a.texture) {
      EXPECT_EQ(a.texture->storage, b.texture->storage) << second.derived[i].key;
    }
    if (a.field) {
      EXPECT_EQ(a.field->h, b.field->h) << second.derived[i].key;
    }
  }
}

TEST(DynamicSurface, ConeSteppingOnADynamicHeightIsRefusedUnlessRebaked) {
  try {
    plan_frame(water({{"/materials/water/technique/name", "rcsm"}}));
    FAIL() << "planned";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/materials/water/technique/name: 'rcsm' marches a cone map"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("use qdm or pom for dynamic surfaces"), std::string::npos) << e.what();
  }
  const FramePlan rebaked = plan_frame(water({{"/materials/water/technique/name", "csm"},
                                              {"/animation/rebake_cones", "true"},
                                              {"/materials/water/ao", R"({"mode": "baked"})"}}));
  EXPECT_EQ(described(rebaked, rebaked.dynamic_items()),
            (std::set<std::string>{"height", "height max", "normal", "height_field", "cone_map", "layer_ao_map"}));
  // (coarse AO taps read the max-quadtree.) Baked every frame and kept out of the bake cache (it would fill with frames).
  const std::filesystem::path cache = std::filesystem::temp_directory_path() / ("qdmr-dynamic-cache-" + std::to_string(::getpid()));
  std::filesystem::create_directories(cache);
  const char* before = std::getenv("QDMR_CACHE_DIR");
  const std::string saved = before ? before : "";
  ::setenv("QDMR_CACHE_DIR", cache.c_str(), 1);
  const Assets assets = prepare(rebaked, kernel_for(resolve_isa(Isa::Auto)));
  before ? ::setenv("QDMR_CACHE_DIR", saved.c_str(), 1) : ::unsetenv("QDMR_CACHE_DIR");
  EXPECT_TRUE(std::filesystem::is_empty(cache));
  std::filesystem::remove_all(cache);
  // While a still height's maps are kept there.
  ::setenv("QDMR_CACHE_DIR", cache.c_str(), 1);
  std::filesystem::create_directories(cache);
  std::vector<SceneOverride> still_csm{{"/materials/water/technique/name", "csm"}, {"/materials/water/ao", R"({"mode": "baked"})"}};
  for (int i = 0; i < 4; ++i) still_csm.push_back({"/materials/water/layers/0/height/waves/" + std::to_string(i) + "/speed", "0"});
  prepare(plan_frame(water(still_csm)), kernel_for(resolve_isa(Isa::Auto)));
  before ? ::setenv("QDMR_CACHE_DIR", saved.c_str(), 1) : ::unsetenv("QDMR_CACHE_DIR");
  EXPECT_FALSE(std::filesystem::is_empty(cache));
  std::filesystem::remove_all(cache);
}

// Baked AO amortized over frames (issue #58): frame N's map holds row j as frame N - ((N - j) mod K) baked it
// (frame 0 bakes every row), and frame N rendered alone replays the frames it needs: the same bits as frame N of
// a sequence, whatever the route and the thread count.
SceneDesc water_ao(int frames) {
  return water({{"/materials/water/ao", R"({"mode": "baked", "amortize_frames": )" + std::to_string(frames) + "}"}});
}

// The stored level 0 of the layer AO map, row j (R16 codes).
std::vector<std::uint8_t> ao_row(const FramePlan& plan, const Assets& assets, int j) {
  for (std::size_t i = 0; i < plan.derived.size(); ++i)
    if (plan.derived[i].kind == DerivedKind::LayerAoMap) {
      const Texture& t = *assets.derived[i].texture;
      const std::uint8_t* row = t.texel_address(0, 0, j);
      return {row, row + std::size_t(t.width()) * 2};
    }
  ADD_FAILURE() << "no layer AO map";
  return {};
}

TEST(DynamicSurface, AnAmortizedAoMapHoldsEachRowAsTheFrameThatLastBakedItBakedIt) {
  constexpr int kWindow = 3, kFrame = 5;
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  std::vector<FramePlan> plans;
  std::vector<Assets> frames;
  for (int n = 0; n <= kFrame; ++n) {
    plans.push_back(plan_frame(scene_at_frame(water_ao(kWindow), n)));
    frames.push_back(n == 0 ? prepare(plans[0], kernel) : prepare(plans[n], kernel, &frames[n - 1], &plans[n - 1]));
  }
  std::vector<FramePlan> full_plans;
  std::vector<Assets> full;  // every frame baked whole
  for (int n = 0; n <= kFrame; ++n) {
    full_plans.push_back(plan_frame(scene_at_frame(water_ao(1), n)));
    full.push_back(prepare(full_plans[n], kernel));
  }
  int from_earlier = 0;
  for (int n : {1, kFrame})
    for (int j = 0; j < 64; ++j) {
      const int baked_at = std::max(0, n - (n - j % kWindow + kWindow) % kWindow);
      EXPECT_EQ(ao_row(plans[n], frames[n], j), ao_row(full_plans[baked_at], full[baked_at], j)) << n << " row " << j;
      from_earlier += baked_at != n && ao_row(full_plans[baked_at], full[baked_at], j) != ao_row(full_plans[n], full[n], j);
    }
  EXPECT_GT(from_earlier, 0);  // the rows of earlier frames are not those of the frame itself (the test can fail)
}

TEST(DynamicSurface, AnAmortizedFrameAloneEqualsTheFrameOfASequence) {
  const SceneDesc scene = water_ao(3);
  const std::unique_ptr<Renderer> sequence = draw_sequence(scene, 5);
  const Frame fifth = sequence->take_frame();
  for (int threads : {1, 2, 3})
    EXPECT_TRUE(same_bits(fifth.color, render_with_threads(scene_at_frame(scene, 5), threads).color)) << threads;
  Renderer by_frames;  // set_frame from the scene as loaded
  by_frames.set_scene(scene);
  by_frames.set_frame(5);
  EXPECT_TRUE(same_bits(fifth.color, by_frames.draw().color));
  sequence->set_frame(2);  // back: replays frames 0 to 2
  EXPECT_TRUE(same_bits(sequence->draw().color, render_with_threads(scene_at_frame(scene, 2), 1).color));
  // And the amortized frame is not the frame baked whole (the test can fail).
  EXPECT_FALSE(same_bits(fifth.color, render_with_threads(scene_at_frame(water_ao(1), 5), 2).color));
}

}  // namespace
}  // namespace qdmr::test
