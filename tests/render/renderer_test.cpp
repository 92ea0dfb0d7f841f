// The persistent renderer: frames equal the one-shot render bit for bit, drawing again changes nothing, a new
// camera or output size re-prepares nothing, the variant each material runs is the one the plan names,
// memory does not grow over many frames, and a recycled frame's buffers are drawn into.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "cli/cli_test_util.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"

namespace qdmr::test {
namespace {

SceneDesc renderer_scene(const std::string& name, std::vector<SceneOverride> overrides = {}) {
  return test::small_scene(name, std::move(overrides), 96, 54);
}

TEST(Renderer, FramesEqualTheOneShotRenderAndRepeat) {
  const SceneDesc scene = renderer_scene("surface_blend_4layers");
  RenderOptions options;
  options.aovs = {Aov::Depth, Aov::Iterations};
  const Frame one_shot = render_frame(scene, options);
  Renderer renderer(options);
  renderer.set_scene(scene);
  for (int i = 0; i < 3; ++i) {
    const Frame& frame = renderer.draw();
    EXPECT_TRUE(same_bits(frame.color, one_shot.color)) << "frame " << i;
    ASSERT_EQ(frame.aovs.size(), 2u);
    for (std::size_t a = 0; a < 2; ++a) EXPECT_TRUE(same_bits(frame.aovs[a].pixels, one_shot.aovs[a].pixels));
  }
}

// A frame taken out and handed back (as the Python module does with frames nobody holds any more): the next draw
// draws into its buffers, the same bits as before; a taken frame that is kept is not touched by later draws.
TEST(Renderer, DrawsIntoARecycledFrame) {
  const SceneDesc scene = renderer_scene("plane");
  RenderOptions options;
  options.aovs = {Aov::Depth};
  Renderer renderer(options);
  renderer.set_scene(scene);
  renderer.draw();
  Frame kept = renderer.take_frame();
  const PixelBuffer kept_color = kept.color;
  renderer.draw();  // into new buffers: `kept` stays as it was
  EXPECT_TRUE(same_bits(kept.color, kept_color));
  Frame spare = renderer.take_frame();
  const float* spare_color = spare.color.data();
  const float* spare_depth = spare.aovs.at(0).pixels.data();
  renderer.recycle_frame(std::move(spare));
  const Frame& frame = renderer.draw();
  EXPECT_EQ(frame.color.data(), spare_color);
  EXPECT_EQ(frame.aovs.at(0).pixels.data(), spare_depth);
  EXPECT_TRUE(same_bits(frame.color, kept_color));
  EXPECT_TRUE(same_bits(frame.aovs.at(0).pixels, kept.aovs.at(0).pixels));
}

TEST(Renderer, CameraAndSizeChangesRePrepareNothing) {
  SceneDesc scene = renderer_scene("terrain");
  Renderer renderer;
  renderer.set_scene(scene);
  const RenderStats first = renderer.draw().stats;
  EXPECT_GT(first.items_built, 0u);
  EXPECT_EQ(first.items_reused, 0u);
  EXPECT_GT(first.prepare_ms, 0.0);

  scene.camera.position.x += 0.5f;
  scene.output.width = 128;
  scene.output.height = 64;
  renderer.set_scene(scene);
  const Frame& moved = renderer.draw();
  EXPECT_EQ(moved.stats.items_built, 0u);
  EXPECT_EQ(moved.stats.items_reused, first.items_built);
  EXPECT_EQ(moved.width, 128);
  EXPECT_EQ(moved.color.size(), std::size_t(128 * 64 * 3));
  // The moved frame is the one-shot render of the moved scene.
  EXPECT_TRUE(same_bits(moved.color, render_frame(scene, {}).color));

  // Without a new scene the next draw reports no planning or preparing at all.
  const RenderStats& again = renderer.draw().stats;
  EXPECT_EQ(again.prepare_ms, 0.0);
  EXPECT_EQ(again.items_built + again.items_reused, 0u);
}

// The stats name every item prepare built, once, in the plan's order, with its build time; the progress callback
// sees the fraction of the plan's items grow to 1, one call at a time; a re-prepare that builds nothing has no steps.
TEST(Renderer, StatsListEachBuiltItemAndProgressGrowsToOne) {
  SceneDesc scene = renderer_scene("terrain");
  const FramePlan plan = plan_frame(scene, {});
  std::vector<double> fractions;
  RenderOptions options;
  options.progress = [&](const char* stage, double fraction) {
    if (std::string(stage) == "prepare") fractions.push_back(fraction);
  };
  Renderer renderer(options);
  renderer.set_scene(scene);
  const RenderStats first = renderer.draw().stats;
  ASSERT_EQ(first.prepare_steps.size(), first.items_built);
  ASSERT_EQ(first.items_built, plan.meshes.size() + plan.textures.size() + plan.derived.size());
  std::vector<std::string> expected;
  for (std::size_t i = 0; i < plan.meshes.size(); ++i) expected.push_back("mesh " + std::to_string(i));
  for (std::size_t i = 0; i < plan.textures.size(); ++i) expected.push_back("texture " + std::to_string(i));
  for (std::size_t i = 0; i < plan.derived.size(); ++i) expected.push_back("derived " + std::to_string(i));
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const PrepareStep& step = first.prepare_steps[i];
    EXPECT_EQ(step.item, expected[i]);
    EXPECT_GE(step.ms, 0.0) << step.item;
    EXPECT_LE(step.ms, first.prepare_ms) << step.item;  // each step lies inside prepare
    EXPECT_GE(step.start_ms, 0.0) << step.item;
    EXPECT_LE(step.start_ms + step.ms, first.prepare_ms) << step.item;
    EXPECT_FALSE(step.what.empty()) << step.item;
    EXPECT_NE(step.where.find(scene.file.string()), std::string::npos) << step.item;
  }
  EXPECT_EQ(first.prepare_steps.back().what, "blend_ao_map");
  // The AO map is baked from the combined quadtree's field: it begins once that has been built.
  const auto built = [&](const std::string& what) {
    return std::find_if(first.prepare_steps.begin(), first.prepare_steps.end(),
                        [&](const PrepareStep& s) { return s.what == what; });
  };
  ASSERT_NE(built("combined_quadtree"), first.prepare_steps.end());
  EXPECT_GE(built("blend_ao_map")->start_ms, built("combined_quadtree")->start_ms + built("combined_quadtree")->ms);
  // 0 first, then one call per item built with the fraction done, then 1 when prepare is over.
  ASSERT_EQ(fractions.size(), expected.size() + 2);
  EXPECT_EQ(fractions.front(), 0.0);
  for (std::size_t i = 1; i + 1 < fractions.size(); ++i) EXPECT_DOUBLE_EQ(fractions[i], double(i) / double(expected.size()));
  EXPECT_EQ(fractions.back(), 1.0);

  scene.camera.position.x += 0.5f;
  renderer.set_scene(scene);
  EXPECT_TRUE(renderer.draw().stats.prepare_steps.empty());
}

// A stop request (the command's SIGINT or SIGTERM handler calls request_stop) ends a draw at its next tile with
// qdmr::Interrupted; once the request is cleared the renderer draws the same frame as before.
TEST(Renderer, AStopRequestEndsTheDrawAtTheNextTile) {
  const SceneDesc scene = renderer_scene("plane");
  Renderer renderer;
  renderer.set_scene(scene);
  const PixelBuffer before = renderer.draw().color;
  request_stop();
  EXPECT_THROW(renderer.draw(), Interrupted);
  clear_stop_request();
  EXPECT_TRUE(same_bits(renderer.draw().color, before));
}

// Whatever changes a texture's content changes its key: a persistent renderer must never re-use the texture of
// the previous scene for a new storage (BC3, a format) or a float that differs in its last bit. Each new scene's
// frame is its one-shot render.
TEST(Renderer, ANewTextureSettingIsANewTexture) {
  Renderer renderer;
  const std::vector<std::vector<SceneOverride>> scenes = {
      {},
      {{"/materials/bricks/layers/0/height/compression", "bc3"}},
      {{"/materials/bricks/layers/0/height/format", "r8"}},
      {{"/materials/bricks/layers/0/albedo/variation", "0.15000002"}},
  };
  std::vector<PixelBuffer> frames;
  for (const auto& overrides : scenes) {
    const SceneDesc scene = renderer_scene("plane", overrides);
    renderer.set_scene(scene);
    const Frame& frame = renderer.draw();
    EXPECT_TRUE(same_bits(frame.color, render_frame(scene, {}).color)) << overrides.size();
    if (!overrides.empty()) {
      EXPECT_GT(frame.stats.items_built, 0u) << overrides[0].pointer;
    }
    frames.push_back(frame.color);
  }
  EXPECT_FALSE(same_bits(frames[0], frames[1]));  // BC3 moves heights by up to 3/255
}

TEST(Renderer, StatsNameTheVariantThePlanPicked) {
  for (const std::string name : {"terrain", "objects", "surface_blend_4layers", "pom_vs_qdm_depth_5.0"}) {
    Renderer renderer;
    renderer.set_scene(renderer_scene(name));
    const Frame& frame = renderer.draw();
    const FramePlan& plan = renderer.plan();
    ASSERT_EQ(frame.stats.materials.size(), plan.materials.size()) << name;
    for (std::size_t i = 0; i < plan.materials.size(); ++i) {
      EXPECT_EQ(frame.stats.materials[i].name, plan.materials[i].name);
      EXPECT_EQ(frame.stats.materials[i].variant, plan.materials[i].variant) << name << " / " << plan.materials[i].name;
    }
  }
}

// Every trace variant (qdmr/program/program_key.hpp): the instantiation the program runs, named from its template
// arguments, is the one the plan picked from the material.
TEST(Renderer, EveryTraceVariantRunsTheInstantiationThePlanNames) {
  int checked = 0;
  Renderer renderer;  // one renderer: the textures are prepared once and shared by every combination
  for (const std::string technique : {"normal", "relief", "pom", "csm", "rcsm", "qdm"})
    for (const std::string math : {"sm4", "sm3", "exact"})
      for (const std::string fetch : {"point", "trilinear"})
        for (const std::string level_up : {"stay", "one", "aligned"}) {
          if (technique != "qdm" && (math != "sm4" || fetch != "point" || level_up != "one")) continue;
          const SceneDesc scene = renderer_scene(
              "pom_vs_qdm_depth_5.0", {{"/materials/surface/technique/name", technique},
                                       {"/materials/surface/sampling/math", math},
                                       {"/materials/surface/technique/height_fetch", fetch},
                                       {"/materials/surface/technique/level_up", level_up}});
          renderer.set_scene(scene);
          const Frame& frame = renderer.draw();
          const FramePlan& plan = renderer.plan();
          for (std::size_t i = 0; i < plan.materials.size(); ++i) {
            if (plan.materials[i].name != "surface") continue;
            const std::string& ran = frame.stats.materials.at(i).variant;
            EXPECT_EQ(ran, plan.materials[i].variant);
            const std::string expected =
                technique == "normal" ? "normal_mapping"
                : technique != "qdm"  ? "displacement:" + technique + " "
                                      : "displacement:qdm<" +
                                             std::string(math == "sm3"     ? "sm3_cells"
                                                         : math == "exact" ? "fp64_walls"
                                                                           : "int_cells") +
                                             "," +
                                           (fetch == "trilinear" ? "filtered_max" : "max_fetch") + ",level_up_" +
                                           level_up + ">";
            EXPECT_EQ(ran.rfind(expected, 0), 0u) << ran << " does not start with " << expected;
            ++checked;
          }
        }
  EXPECT_EQ(checked, 5 + 3 * 2 * 3);
}

TEST(Renderer, MemoryDoesNotGrowOverAThousandFrames) {
  Renderer renderer;
  renderer.set_scene(renderer_scene("plane"), {Aov::Depth, Aov::Normal});
  for (int i = 0; i < 50; ++i) renderer.draw();  // sizes settle, allocator pools fill
  const std::uint64_t before = test::resident_bytes();
  for (int i = 0; i < 1000; ++i) renderer.draw();
  const std::uint64_t after = test::resident_bytes();
  // One frame's buffers are 96x54x(3+1+3) floats = 145 KB; a leak of even one small allocation per frame
  // would add 1000 of them. 512 KiB of slack covers allocator and oneTBB bookkeeping noise.
  EXPECT_LT(after, before + 512 * 1024) << "resident set grew from " << before << " to " << after << " bytes";
}

// The tiles test depth in planes of their own; the framebuffer keeps a frame-sized depth plane only where
// something reads depth after its tile (the reference summary's covered pixels), and the plan counts exactly
// what the renderer holds: colour (3 floats a pixel), the AOVs asked for, and then depth (1).
TEST(Renderer, FramebufferKeepsADepthPlaneOnlyWhereItIsRead) {
  const SceneDesc scene = renderer_scene("terrain");
  const std::uint64_t pixels = 96 * 54;
  struct Case {
    std::vector<Aov> aovs;
    std::uint64_t floats_per_pixel;
  };
  for (const Case& c : {Case{{}, 3}, Case{{Aov::Depth}, 3 + 1}, Case{{Aov::ErrorTexels}, 3 + 1 + 1},
                        Case{{Aov::Missed, Aov::Normal}, 3 + 1 + 3 + 1}}) {
    const FramePlan plan = plan_frame(scene, PlanOptions{c.aovs});
    EXPECT_EQ(plan.framebuffer_bytes, pixels * c.floats_per_pixel * sizeof(float)) << c.aovs.size() << " AOVs";
    Renderer renderer;
    renderer.set_scene(scene, c.aovs);
    EXPECT_EQ(renderer.draw().stats.framebuffer_bytes, plan.framebuffer_bytes) << c.aovs.size() << " AOVs";
  }
}

TEST(Renderer, RefusesAnIsaTheCpuOrBinaryLacks) {
  RenderOptions options;
  for (Isa isa : {Isa::Sse42, Isa::Avx2, Isa::Avx512}) {
    options.isa = isa;
    const std::vector<Isa> usable = usable_isas();
    if (std::find(usable.begin(), usable.end(), isa) != usable.end()) {
      Renderer renderer(options);
      EXPECT_EQ(renderer.isa(), isa);
    } else {
      EXPECT_THROW(Renderer{options}, Error) << isa_name(isa);
    }
  }
}

}  // namespace
}  // namespace qdmr::test
