// A forced ISA holds for every stage of a frame: with the SSE4.2 kernel forced on a CPU that runs a wider one, the
// wider kernels' code runs neither in preparation (max mip chains, a blend's box values, baked AO, BC3 encoding, a
// dynamic height's rows) nor in the draw. Each kernel counts the calls into its own code (KernelCalls, counted inside
// the per-ISA functions, so a call that reaches a kernel around the Renderer's table counts too).
// isa.avx_only_in_kernels checks that no baseline code holds AVX instructions.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <utility>

#include "kernel/kernel.hpp"
#include "qdmr/render/render.hpp"
#include "support/frames.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

// The entries of KernelCalls, by name.
constexpr std::array<std::pair<const char*, std::atomic<std::uint64_t> KernelCalls::*>, 7> kEntries = {{
    {"programs", &KernelCalls::programs},
    {"tiles", &KernelCalls::tiles},
    {"mip_levels", &KernelCalls::mip_levels},
    {"box_values", &KernelCalls::box_values},
    {"ao_rows", &KernelCalls::ao_rows},
    {"bc3_encoders", &KernelCalls::bc3_encoders},
    {"height_row_tables", &KernelCalls::height_row_tables},
}};
static_assert(sizeof(KernelCalls) == kEntries.size() * sizeof(std::atomic<std::uint64_t>), "an entry left out");

using Counts = std::array<std::uint64_t, kEntries.size()>;

std::map<Isa, Counts> counts() {
  std::map<Isa, Counts> out;
  for (const Isa isa : built_isas()) {
    const KernelCalls& c = kernel_for(isa).calls();
    for (std::size_t e = 0; e < kEntries.size(); ++e) out[isa][e] = (c.*kEntries[e].second).load();
  }
  return out;
}

TEST(ForcedIsa, Sse42RunsNoWiderKernelInAnyStage) {
  if (usable_isas().size() < 2 || !cpu_supports(Isa::Sse42))
    GTEST_SKIP() << "needs a CPU and a build with SSE4.2 and a wider kernel";
  // QDM over four layers blended per pixel: the layers' max-quadtrees and the weights' max chain (mip_levels),
  // the combined quadtree with its box values (box_values), its baked AO (ao_rows), one layer stored as BC3
  // (bc3_encoders); small maps, a small frame.
  std::vector<SceneOverride> overrides = {{"/materials/blend/technique/name", "qdm"},
                                          {"/materials/blend/ao/mode", "baked"},
                                          {"/materials/blend/blend/weights/mode", "pixel"},
                                          {"/materials/blend/layers/0/height/compression", "bc3"}};
  for (int layer = 0; layer < 4; ++layer)
    for (const char* map : {"albedo", "height"})
      overrides.push_back({"/materials/blend/layers/" + std::to_string(layer) + "/" + map + "/size", "64"});
  const SceneDesc blend = small_scene("surface_blend_4layers", overrides, 64, 36);
  // The waves of scenes/water.json on a small map: a dynamic height, built by the rebuild's rows (height_row_tables).
  const SceneDesc water = small_scene("water", {{"/materials/water/layers/0/height/size", "64"}}, 64, 36);

  const TempDir dir;
  const ScopedCacheDir cache(dir / "cache");  // the AO map is baked, not read from an earlier run's cache
  const std::map<Isa, Counts> before = counts();
  RenderOptions options;
  options.isa = Isa::Sse42;
  Renderer renderer(options);
  renderer.set_scene(blend);
  const Frame& frame = renderer.draw();
  ASSERT_EQ(frame.width, 64);
  bool bc3 = false;
  for (const TextureStat& t : frame.stats.textures) bc3 = bc3 || t.bc3;
  EXPECT_TRUE(bc3) << "a height went through BC3";
  renderer.set_scene(water);
  ASSERT_EQ(renderer.draw().width, 64);
  const std::map<Isa, Counts> after = counts();

  for (const auto& [isa, now] : after) {
    SCOPED_TRACE(isa_name(isa));
    const Counts& was = before.at(isa);
    for (std::size_t e = 0; e < kEntries.size(); ++e) {
      SCOPED_TRACE(kEntries[e].first);
      if (isa == Isa::Sse42)
        EXPECT_GT(now[e], was[e]);  // every entry ran, so the scenes exercised every stage
      else
        EXPECT_EQ(now[e], was[e]);
    }
  }
}

}  // namespace
}  // namespace qdmr::test
