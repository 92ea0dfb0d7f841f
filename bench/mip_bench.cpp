// Mip chains of the colour and normal maps, as preparation builds them (make_mip_texture): level 0 quantised
// from a float image, then Box levels (an sRGB albedo, a linear RGBA8 map, R16 heights) or BoxNormal levels
// (a normal map), and the decoded float copy the samplers read (add_linear_copy). Random texels: the cost per
// texel does not depend on the content. Arguments: side of the square level 0, thread count.
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cstddef>
#include <random>

#include "qdmr/texture/mip_texture.hpp"

namespace {

using namespace qdmr;

Image random_image(int side, int channels) {
  Image image(side, side, channels);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& v : image.texels) v = u(rng);
  return image;
}

void chain(benchmark::State& state, TexelFormat format, bool srgb, MipReduce reduce) {
  const int side = int(state.range(0)), threads = int(state.range(1));
  const Image level0 = random_image(side, channel_count(format));
  tbb::task_arena(threads).execute([&] {
    for (auto _ : state) {
      Texture texture = make_mip_texture(level0, format, srgb, reduce);
      benchmark::DoNotOptimize(texture.storage.data());
    }
  });
  state.SetItemsProcessed(std::int64_t(state.iterations()) * side * side);  // level-0 texels
}

void decoded_copy(benchmark::State& state, TexelFormat format, bool srgb) {
  const int side = int(state.range(0)), threads = int(state.range(1));
  const Texture built = make_mip_texture(random_image(side, channel_count(format)), format, srgb, MipReduce::Box);
  tbb::task_arena(threads).execute([&] {
    for (auto _ : state) {
      Texture texture = built;
      add_linear_copy(texture);
      benchmark::DoNotOptimize(texture.linear.data());
    }
  });
  state.SetItemsProcessed(std::int64_t(state.iterations()) * side * side);
}

void albedo_srgb(benchmark::State& state) { chain(state, TexelFormat::RGBA8, true, MipReduce::Box); }
void rgba8_box(benchmark::State& state) { chain(state, TexelFormat::RGBA8, false, MipReduce::Box); }
void normal_map(benchmark::State& state) { chain(state, TexelFormat::RGBA8, false, MipReduce::BoxNormal); }
void height_r16(benchmark::State& state) { chain(state, TexelFormat::R16, false, MipReduce::Box); }
void albedo_srgb_decoded_copy(benchmark::State& state) { decoded_copy(state, TexelFormat::RGBA8, true); }

#define QDMR_MIP_BENCH(f)                                  \
  BENCHMARK(f)                                             \
      ->ArgsProduct({{512, 2048}, {1, 2}})                 \
      ->ArgNames({"side", "threads"})                      \
      ->Unit(benchmark::kMillisecond)                      \
      ->UseRealTime()
QDMR_MIP_BENCH(albedo_srgb);
QDMR_MIP_BENCH(rgba8_box);
QDMR_MIP_BENCH(normal_map);
QDMR_MIP_BENCH(height_r16);
QDMR_MIP_BENCH(albedo_srgb_decoded_copy);

}  // namespace

BENCHMARK_MAIN();
