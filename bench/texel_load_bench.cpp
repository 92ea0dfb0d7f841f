// What a lane's texel load costs in the AVX2 kernel, against the SSE4.2 kernel's 4 lanes: the bilinear samplers
// load a texel pair (8 bytes) per lane and row. Three ways for 8 lanes: the project's loads built by hand
// (simd::load_bytes8_at: a 64-bit load per lane, packed by shuffles), two `vpgatherdd` (the pair's low and high
// 4 bytes), two `vpgatherdq` (4 lanes of 8 bytes each); and the 4-lane portable path the SSE4.2 kernel takes, for
// the per-lane comparison. Offsets are random in tables of 16 KiB (L1), 256 KiB (L2) and 16 MiB (beyond), and do
// not depend on the loaded data (throughput, not latency).
// Name: BM_Pairs/<method>/<table KiB>; items/s = lanes loaded per second.
#include <benchmark/benchmark.h>

#include <immintrin.h>

#include <cstdint>
#include <vector>

#include "kernel/gather.hpp"

namespace {

using namespace qdmr;

enum class Method { ByHand, GatherDword, GatherQword, Portable4 };

// The next 8 offsets (multiples of 8 below `bytes`) of a linear congruential sequence, in a vector.
__m256i next_offsets(__m256i& state, int bytes) {
  state = _mm256_add_epi32(_mm256_mullo_epi32(state, _mm256_set1_epi32(1103515245)), _mm256_set1_epi32(12345));
  return _mm256_and_si256(_mm256_srli_epi32(state, 4), _mm256_set1_epi32((bytes - 1) & ~7));
}

// A table of `bytes` (a power of two) to load from, and `tail` bytes more for a load at its last offset.
std::vector<std::uint8_t> texel_table(int bytes, int tail) {
  std::vector<std::uint8_t> table(std::size_t(bytes + tail));
  for (std::size_t i = 0; i < table.size(); ++i) table[i] = std::uint8_t(i * 7);
  return table;
}

void BM_Pairs(benchmark::State& state, Method method) {
  const int bytes = int(state.range(0)) * 1024;
  const std::vector<std::uint8_t> table = texel_table(bytes, 8);
  const std::uint8_t* base = table.data();
  __m256i seed = _mm256_setr_epi32(1, 2, 3, 4, 5, 6, 7, 8), sum = _mm256_setzero_si256();
  for (auto _ : state) {
    for (int i = 0; i < 64; ++i) {
      const __m256i offsets = next_offsets(seed, bytes);
      __m256i first, second;
      switch (method) {
        case Method::ByHand: {
          alignas(32) std::int32_t o[8];
          _mm256_store_si256(reinterpret_cast<__m256i*>(o), offsets);
          simd::Int a, b;
          simd::load_bytes8_at(base, o, simd::FetchPath::Gather, a, b);
          first = a;
          second = b;
          break;
        }
        case Method::GatherDword:
          first = _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), offsets, 1);
          second = _mm256_i32gather_epi32(reinterpret_cast<const int*>(base + 4), offsets, 1);
          break;
        case Method::GatherQword: {  // lanes 0-3 and 4-7 as 64-bit elements, then split into low and high halves
          const auto* q = reinterpret_cast<const long long*>(base);
          const __m256i low = _mm256_i32gather_epi64(q, _mm256_castsi256_si128(offsets), 1);
          const __m256i high = _mm256_i32gather_epi64(q, _mm256_extracti128_si256(offsets, 1), 1);
          const __m256 x = _mm256_castsi256_ps(_mm256_permute2x128_si256(low, high, 0x20));
          const __m256 y = _mm256_castsi256_ps(_mm256_permute2x128_si256(low, high, 0x31));
          first = _mm256_castps_si256(_mm256_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0)));
          second = _mm256_castps_si256(_mm256_shuffle_ps(x, y, _MM_SHUFFLE(3, 1, 3, 1)));
          break;
        }
        case Method::Portable4: {  // what the SSE4.2 kernel does for its 4 lanes: 64-bit loads, 4-lane registers
          alignas(32) std::int32_t o[8];
          _mm256_store_si256(reinterpret_cast<__m256i*>(o), offsets);
          const auto two = [&](int lane) {
            return _mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + o[lane])),
                                      _mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + o[lane + 1])));
          };
          const __m128 x = _mm_castsi128_ps(two(0)), y = _mm_castsi128_ps(two(2));
          first = _mm256_castsi128_si256(_mm_castps_si128(_mm_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0))));
          second = _mm256_castsi128_si256(_mm_castps_si128(_mm_shuffle_ps(x, y, _MM_SHUFFLE(3, 1, 3, 1))));
          break;
        }
      }
      sum = _mm256_add_epi32(sum, _mm256_xor_si256(first, second));
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * 64 * (method == Method::Portable4 ? 4 : 8));
}

// Single 4-byte texels (load_bytes4, load_f32): one `vpgatherdd` against 8 scalar loads packed by vpinsrd
// (simd::avx2_loads4), and 8 scalar loads through memory (the portable path). `Chained`: each vector's offsets
// depend on the previous vector's loaded values (a walk that waits on its loads, as QDM's traversal does), else
// independent (throughput). Name: BM_Single/<method>/<chained 0|1>/<table KiB>; items/s = lanes loaded per second.
enum class Single { Gather, ByHand, Portable };

void BM_Single(benchmark::State& state, Single method) {
  const int bytes = int(state.range(1)) * 1024;
  const bool chained = state.range(0) != 0;
  const std::vector<std::uint8_t> table = texel_table(bytes, 4);
  const std::uint8_t* base = table.data();
  __m256i seed = _mm256_setr_epi32(1, 2, 3, 4, 5, 6, 7, 8), sum = _mm256_setzero_si256();
  for (auto _ : state) {
    for (int i = 0; i < 64; ++i) {
      __m256i offsets = next_offsets(seed, bytes);
      if (chained) offsets = _mm256_and_si256(_mm256_xor_si256(offsets, sum), _mm256_set1_epi32((bytes - 1) & ~7));
      __m256i value;
      switch (method) {
        case Single::Gather: value = _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), offsets, 1); break;
        case Single::ByHand: {
          alignas(32) std::int32_t o[8];
          _mm256_store_si256(reinterpret_cast<__m256i*>(o), offsets);
          value = simd::avx2_loads4<1>(base, o);
          break;
        }
        case Single::Portable: value = simd::load_bytes4(base, simd::Int(offsets), simd::FetchPath::Portable); break;
      }
      sum = _mm256_add_epi32(sum, value);
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * 64 * 8);
}

void single_args(benchmark::internal::Benchmark* b) {
  for (const int chained : {0, 1})
    for (const int kib : {16, 256, 16384}) b->Args({chained, kib});
}

BENCHMARK_CAPTURE(BM_Single, gather, Single::Gather)->Apply(single_args);
BENCHMARK_CAPTURE(BM_Single, by_hand, Single::ByHand)->Apply(single_args);
BENCHMARK_CAPTURE(BM_Single, portable, Single::Portable)->Apply(single_args);

void table_sizes(benchmark::internal::Benchmark* b) { b->Arg(16)->Arg(256)->Arg(16384); }

BENCHMARK_CAPTURE(BM_Pairs, by_hand, Method::ByHand)->Apply(table_sizes);
BENCHMARK_CAPTURE(BM_Pairs, gather_dword, Method::GatherDword)->Apply(table_sizes);
BENCHMARK_CAPTURE(BM_Pairs, gather_qword, Method::GatherQword)->Apply(table_sizes);
BENCHMARK_CAPTURE(BM_Pairs, portable_4_lanes, Method::Portable4)->Apply(table_sizes);

}  // namespace

BENCHMARK_MAIN();
