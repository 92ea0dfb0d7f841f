// Max-quadtree build (levels 1.. of a MAX-reduced mip chain, QDM's quadtree) from a random level 0, on one
// thread and on two (oneTBB arena). Arguments: side of the square level 0, thread count.
// For comparison, the GDC 2009 QDM talk builds it on a GeForce 8800 in 0.15 / 0.25 / 1.15 / 2.09 ms for
// 256² / 512² / 1024² / 2048².
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cstddef>
#include <random>

#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace {

using namespace qdmr;

void max_build(benchmark::State& state, TexelFormat format) {
  const int side = int(state.range(0)), threads = int(state.range(1));
  Image level0(side, side, 1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& v : level0.texels) v = u(rng);
  // The reducer of the kernel a frame would run here (as preparation does).
  const MipExtremum extremum = kernel_for(resolve_isa(Isa::Auto)).mip_extremum();
  Texture texture = make_mip_texture(level0, format, false, MipReduce::Max, extremum);

  tbb::task_arena(threads).execute([&] {
    for (auto _ : state) {
      build_mip_levels(texture, MipReduce::Max, extremum);
      benchmark::DoNotOptimize(texture.storage.data());
      benchmark::ClobberMemory();
    }
  });
  // Bytes read: every level but the last.
  std::size_t read = 0;
  for (int k = 0; k + 1 < texture.level_count(); ++k)
    read += std::size_t(texture.levels[std::size_t(k)].width) * std::size_t(texture.levels[std::size_t(k)].height) *
            std::size_t(bytes_per_texel(format));
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(read));
}

void max_build_r8(benchmark::State& state) { max_build(state, TexelFormat::R8); }
void max_build_r16(benchmark::State& state) { max_build(state, TexelFormat::R16); }

BENCHMARK(max_build_r8)
    ->ArgsProduct({{256, 512, 1024, 2048, 4096}, {1, 2}})
    ->ArgNames({"side", "threads"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK(max_build_r16)
    ->ArgsProduct({{256, 512, 1024, 2048, 4096}, {1, 2}})
    ->ArgNames({"side", "threads"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
