// The per-frame rebuild of scenes/water.json's 1024² dynamic height (texture/height_family.hpp): the waves' level
// 0, its R16 codes and decoded copy, the Box chain with wrap footprints, the max-quadtree, the from_height normals
// and their BoxNormal chain, refilling the previous-but-one frame's textures as the Renderer does (so no page is
// allocated or cleared in the loop). Each iteration is the next frame of the animation. Arguments: the rows (0: the
// baseline's, 1: the best kernel's), thread count, and whether the max-quadtree is among the textures (1) or not (0:
// the difference is the quadtree's part of the rebuild, its level 0 copy included).
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <string>
#include <vector>

#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/load/load.hpp"
#include "texture/height_family.hpp"

namespace {

using namespace qdmr;

void water_rebuild(benchmark::State& state) {
  const bool kernel_rows = state.range(0) != 0;
  const int threads = int(state.range(1));
  const bool quadtree = state.range(2) != 0;
  const SceneDesc scene = load_scene(std::string(QDMR_SOURCE_DIR) + "/scenes/water.json", {});
  const Kernel& kernel = kernel_for(resolve_isa(Isa::Auto));
  const HeightRows& rows = kernel_rows ? kernel.height_rows() : baseline_height_rows();
  // The members prepare makes for the water layer: heights (box, wrap footprints), the max-quadtree, normals.
  const auto members = [quadtree] {
    std::vector<HeightFamilyMember> m(3);
    m[0].wrap_footprints = true;
    m[1].reduce = MipReduce::Max;
    m[2].normals = true;
    m[2].normal_strength = 0.6f;
    if (!quadtree) m.erase(m.begin() + 1);
    return m;
  };
  std::vector<HeightFamilyMember> frames[2] = {members(), members()};
  int frame = 0;
  tbb::task_arena(threads).execute([&] {
    for (auto _ : state) {
      const SceneDesc at = scene_at_frame(scene, frame % scene.animation.frames);
      const LayerDesc& layer = at.materials[0].layers[0];
      build_height_family(layer, TexelFormat::R16, "water", frames[frame % 2], rows, kernel.mip_extremum());
      benchmark::DoNotOptimize(frames[frame % 2][0].texture.storage.data());
      ++frame;
    }
  });
  state.SetItemsProcessed(std::int64_t(state.iterations()) * 1024 * 1024);  // level-0 texels
}

BENCHMARK(water_rebuild)
    ->ArgsProduct({{0, 1}, {1, 2}, {1, 0}})
    ->ArgNames({"kernel", "threads", "quadtree"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
