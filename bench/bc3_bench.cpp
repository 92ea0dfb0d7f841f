// BC3 alpha encode and decode throughput (MB/s of 8-bit texels, one thread) on 2048² procedural height maps: the
// encode by the definition (encode_bc3_alpha) and by each kernel's encoder (Kernel::bc3_encode, what preparation
// uses); bc3_roundtrip of each procedural pattern with the best kernel's encoder, its error (max, RMS in 8-bit
// steps) as counters. The argument of the roundtrip is the thread count.
#include <benchmark/benchmark.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/texture/bc3.hpp"
#include "qdmr/texture/texture_level0.hpp"

namespace {

using namespace qdmr;

constexpr int kSize = 2048;

// The pattern's heights in [0,1] quantised to 8 bits, row-major; built once per pattern.
const std::vector<std::uint8_t>& height_map(ProceduralPattern pattern) {
  static std::map<ProceduralPattern, std::vector<std::uint8_t>> cache;
  auto [it, inserted] = cache.try_emplace(pattern);
  if (inserted) {
    ProceduralDesc desc;
    desc.pattern = pattern;
    desc.size = kSize;
    const Image image = generate_procedural(desc);
    it->second.resize(image.texels.size());
    for (std::size_t i = 0; i < image.texels.size(); ++i)
      it->second[i] = std::uint8_t(std::lround(std::clamp(image.texels[i], 0.0f, 1.0f) * 255.0f));
  }
  return it->second;
}

// The 4x4 blocks of the map, texel i = (x + 4y) of each block.
std::vector<std::array<std::uint8_t, 16>> blocks_of(const std::vector<std::uint8_t>& map) {
  std::vector<std::array<std::uint8_t, 16>> blocks;
  blocks.reserve(map.size() / 16);
  for (int by = 0; by < kSize; by += 4)
    for (int bx = 0; bx < kSize; bx += 4) {
      std::array<std::uint8_t, 16>& block = blocks.emplace_back();
      for (int i = 0; i < 16; ++i) block[std::size_t(i)] = map[std::size_t(by + i / 4) * kSize + std::size_t(bx + i % 4)];
    }
  return blocks;
}

// `isa` Auto: the definition.
void BM_Bc3Encode(benchmark::State& state, ProceduralPattern pattern, Isa isa) {
  const std::vector<Isa> usable = usable_isas();
  if (isa != Isa::Auto && std::find(usable.begin(), usable.end(), isa) == usable.end()) {
    state.SkipWithError("kernel not usable here");
    return;
  }
  const Bc3Encode encode = isa == Isa::Auto ? &encode_bc3_alpha : kernel_for(isa).bc3_encode();
  const auto blocks = blocks_of(height_map(pattern));
  std::vector<Bc3AlphaBlock> encoded(blocks.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < blocks.size(); ++i) encoded[i] = encode(blocks[i].data());
    benchmark::DoNotOptimize(encoded.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * kSize * kSize);
}

void BM_Bc3Decode(benchmark::State& state, ProceduralPattern pattern) {
  const auto blocks = blocks_of(height_map(pattern));
  std::vector<Bc3AlphaBlock> encoded(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) encoded[i] = encode_bc3_alpha(blocks[i].data());
  std::vector<std::array<std::uint8_t, 16>> decoded(blocks.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < encoded.size(); ++i) decode_bc3_alpha(encoded[i], decoded[i].data());
    benchmark::DoNotOptimize(decoded.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * kSize * kSize);
}

void BM_Bc3Roundtrip(benchmark::State& state, ProceduralPattern pattern) {
  const std::vector<std::uint8_t>& map = height_map(pattern);
  std::vector<std::uint8_t> texels;
  Bc3Report report;
  tbb::task_arena arena(int(state.range(0)));
  const Bc3Encode encode = kernel_for(resolve_isa(Isa::Auto)).bc3_encode();
  for (auto _ : state) {
    state.PauseTiming();
    texels = map;
    state.ResumeTiming();
    arena.execute([&] { report = bc3_roundtrip(texels.data(), kSize, kSize, encode); });
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * kSize * kSize);
  state.counters["max_error"] = report.max_error;
  state.counters["rms_error"] = report.rms_error;
}

}  // namespace

BENCHMARK_CAPTURE(BM_Bc3Encode, noise/definition, ProceduralPattern::Noise, Isa::Auto)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Encode, noise/sse4.2, ProceduralPattern::Noise, Isa::Sse42)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Encode, noise/avx2, ProceduralPattern::Noise, Isa::Avx2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Encode, noise/avx512, ProceduralPattern::Noise, Isa::Avx512)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Encode, sine/avx2, ProceduralPattern::Sine, Isa::Avx2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Decode, noise, ProceduralPattern::Noise)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Decode, sine, ProceduralPattern::Sine)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, noise, ProceduralPattern::Noise)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, sine, ProceduralPattern::Sine)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, bricks, ProceduralPattern::Bricks)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, cobbles, ProceduralPattern::Cobbles)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, steps, ProceduralPattern::Steps)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, spikes, ProceduralPattern::Spikes)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Bc3Roundtrip, checker, ProceduralPattern::Checker)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
