// Height layers read from a frame-numbered sequence of files (`"file": "h_%04d.exr"`, issue #58): frame N of the
// animation reads file N (or the numbers `frames` gives), the plan marks what is made from it as dynamic, frame N
// equals the same file as a still height bit for bit, and frame N of a sequence equals frame N rendered alone on
// any thread count. The EXR frames are written by the test (32x32 floats), none is stored.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kernel/kernel.hpp"
#include "prepare/assets.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/write/write.hpp"
#include "support/frames.hpp"

namespace qdmr::test {
namespace {

constexpr int kSide = 32, kFrames = 4;

// Frame n of a travelling wave, heights in [0.1, 0.9].
std::vector<float> wave(int n) {
  std::vector<float> h(std::size_t(kSide) * kSide);
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x)
      h[std::size_t(y) * kSide + std::size_t(x)] =
          0.5f + 0.4f * float(std::sin(6.283185307179586 * (double(x) / kSide + double(n) / 8.0)) *
                              std::cos(6.283185307179586 * double(y) / kSide));
  return h;
}

// h_0000.exr .. h_0003.exr, and still.exr holding frame 2's heights.
struct Files {
  TempDir dir;
  Files() {
    char name[32];
    for (int n = 0; n < kFrames; ++n) {
      std::snprintf(name, sizeof name, "h_%04d.exr", n);
      write_image(dir / name, kSide, kSide, 1, wave(n), false);
    }
    write_image(dir / "still.exr", kSide, kSide, 1, wave(2), false);
  }
};

// scenes/water.json at 96x54 with its height from `height` (a JSON value), animated over `frames` frames.
SceneDesc water_from(const nlohmann::json& height, int frames = kFrames) {
  return small_scene("water",
                     {{"/animation/frames", std::to_string(frames)},
                      {"/materials/water/layers/0/height", height.dump()}},
                     96, 54);
}

SceneDesc sequence(const Files& files) { return water_from({{"file", (files.dir / "h_%04d.exr").string()}}); }

// The kinds of the plan's dynamic items ("height", "height max", "normal", ...).
std::set<std::string> dynamic_kinds(const FramePlan& plan) {
  std::set<std::string> out;
  for (const std::string& line : plan.dynamic_items())
    for (const TextureRequest& t : plan.textures)
      if (line == "texture " + t.key) out.insert(std::string(purpose_name(t.purpose)) + (t.reduce == MipReduce::Max ? " max" : ""));
  return out;
}

TEST(FileSequence, EachFrameReadsItsFile) {
  const Files files;
  const SceneDesc scene = sequence(files);
  EXPECT_TRUE(scene.time_dependent());
  const auto height_file = [](const SceneDesc& s) { return s.materials[0].layers[0].height.file; };
  EXPECT_EQ(height_file(scene), files.dir / "h_0000.exr");  // the scene as loaded is frame 0
  EXPECT_EQ(height_file(scene_at_frame(scene, 3)), files.dir / "h_0003.exr");
  // `frames` numbers the files: FIRST for frame 0, then every STEP.
  const SceneDesc numbered = water_from({{"file", (files.dir / "h_%04d.exr").string()}, {"frames", "1:3"}}, 3);
  EXPECT_EQ(height_file(scene_at_frame(numbered, 2)), files.dir / "h_0003.exr");
  const SceneDesc stepped = water_from({{"file", (files.dir / "h_%04d.exr").string()}, {"frames", "0:2:2"}}, 2);
  EXPECT_EQ(height_file(scene_at_frame(stepped, 1)), files.dir / "h_0002.exr");
}

TEST(FileSequence, AFrameEqualsTheSameFileAsAStillHeight) {
  const Files files;
  const SceneDesc still = water_from({{"file", (files.dir / "still.exr").string()}});
  const SceneDesc frame2 = scene_at_frame(sequence(files), 2);
  EXPECT_TRUE(same_bits(render_with_threads(frame2, 2).color, render_with_threads(still, 2).color));
  // The plan marks what is made from the sequence as dynamic: the heights, their max-quadtree, the normals; the
  // still file has none.
  EXPECT_EQ(dynamic_kinds(plan_frame(frame2)), (std::set<std::string>{"height", "height max", "normal"}));
  EXPECT_TRUE(plan_frame(still).dynamic_items().empty());
}

TEST(FileSequence, AFrameOfASequenceEqualsTheFrameAloneOnAnyThreadCount) {
  const Files files;
  const SceneDesc scene = sequence(files);
  RenderOptions options;
  options.threads = 2;
  Renderer renderer(options);
  renderer.set_scene(scene);
  renderer.draw();
  for (int n = 1; n < kFrames; ++n) {
    renderer.set_frame(n);
    renderer.draw();
  }
  for (int threads : {1, 2, 3})
    EXPECT_TRUE(same_bits(renderer.frame().color,
                          render_with_threads(scene_at_frame(scene, kFrames - 1), threads).color))
        << threads;
}

TEST(FileSequence, AWarmFrameRebuildsExactlyTheDynamicItems) {
  const Files files;
  const SceneDesc scene = sequence(files);
  const FramePlan first = plan_frame(scene_at_frame(scene, 0)), second = plan_frame(scene_at_frame(scene, 1));
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  const Assets warm0 = prepare(first, kernel);
  const Assets warm1 = prepare(second, kernel, &warm0, &first);
  EXPECT_EQ(warm1.built, second.dynamic_items());
  EXPECT_FALSE(second.dynamic_items().empty());
}

}  // namespace
}  // namespace qdmr::test
