// A forced ISA holds for every stage of a frame: with the SSE4.2 kernel forced on a CPU that runs a wider one, the
// wider kernels' code runs neither in preparation (max mip chains, a blend's box values, baked AO) nor in the draw. Each
// kernel counts the calls into its own code (KernelCalls, counted inside the per-ISA functions, so a call that
// reaches a kernel around the Renderer's table counts too). BC3 encoding is baseline code (SSE2):
// isa.avx_only_in_kernels checks that no baseline code holds AVX instructions.
#include <gtest/gtest.h>

#include <map>

#include "kernel/kernel.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

struct Counts {
  std::uint64_t programs, tiles, mip_levels, box_values, ao_rows;
};

std::map<Isa, Counts> counts() {
  std::map<Isa, Counts> out;
  for (const Isa isa : built_isas()) {
    const KernelCalls& c = kernel_for(isa).calls();
    out[isa] = {c.programs.load(), c.tiles.load(), c.mip_levels.load(), c.box_values.load(), c.ao_rows.load()};
  }
  return out;
}

TEST(ForcedIsa, Sse42RunsNoWiderKernelInAnyStage) {
  if (usable_isas().size() < 2 || !cpu_supports(Isa::Sse42))
    GTEST_SKIP() << "needs a CPU and a build with SSE4.2 and a wider kernel";
  // QDM over four layers blended per pixel: the layers' max-quadtrees and the weights' max chain (mip_levels),
  // the combined quadtree with its box values (box_values), its baked AO (ao_rows), one layer stored as BC3; small
  // maps, a small frame.
  std::vector<SceneOverride> overrides = {{"/materials/blend/technique/name", "qdm"},
                                          {"/materials/blend/ao/mode", "baked"},
                                          {"/materials/blend/blend/weights/mode", "pixel"},
                                          {"/materials/blend/layers/0/height/compression", "bc3"}};
  for (int layer = 0; layer < 4; ++layer)
    for (const char* map : {"albedo", "height"})
      overrides.push_back({"/materials/blend/layers/" + std::to_string(layer) + "/" + map + "/size", "64"});
  const SceneDesc scene = small_scene("surface_blend_4layers", overrides, 64, 36);

  const TempDir dir;
  const ScopedCacheDir cache(dir / "cache");  // the AO map is baked, not read from an earlier run's cache
  const std::map<Isa, Counts> before = counts();
  RenderOptions options;
  options.isa = Isa::Sse42;
  Renderer renderer(options);
  renderer.set_scene(scene);
  const Frame& frame = renderer.draw();
  ASSERT_EQ(frame.width, 64);
  bool bc3 = false;
  for (const TextureStat& t : frame.stats.textures) bc3 = bc3 || t.bc3;
  EXPECT_TRUE(bc3) << "a height went through BC3";
  const std::map<Isa, Counts> after = counts();

  for (const auto& [isa, now] : after) {
    SCOPED_TRACE(isa_name(isa));
    const Counts& was = before.at(isa);
    if (isa == Isa::Sse42) {  // every entry ran, so the scene exercised every stage
      EXPECT_GT(now.programs, was.programs);
      EXPECT_GT(now.tiles, was.tiles);
      EXPECT_GT(now.mip_levels, was.mip_levels);
      EXPECT_GT(now.box_values, was.box_values);
      EXPECT_GT(now.ao_rows, was.ao_rows);
    } else {
      EXPECT_EQ(now.programs, was.programs);
      EXPECT_EQ(now.tiles, was.tiles);
      EXPECT_EQ(now.mip_levels, was.mip_levels);
      EXPECT_EQ(now.box_values, was.box_values);
      EXPECT_EQ(now.ao_rows, was.ao_rows);
    }
  }
}

}  // namespace
}  // namespace qdmr::test
