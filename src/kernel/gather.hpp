#pragma once
// Per-lane loads for texel fetch. On the Gather path the AVX-512 build uses the hardware gathers (xsimd 8.1 never
// emits them), except where loads built by hand were measured faster (texel pairs, load_bytes8 and load_f32x4_pair);
// the AVX2 build builds its loads of single 4-byte values by hand too (avx2_loads4: Zen 3's gathers are microcoded).
// The portable versions load lane by lane. All return the same bits; FetchPath picks one at run time so they can be
// measured side by side.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/simd.hpp"

#if defined(__AVX2__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace qdmr::QDMR_ISA_NAMESPACE::simd {

enum class FetchPath : std::uint8_t { Gather, Portable };

// The gather instructions of this build: 16 lanes with AVX-512, 8 with AVX2, none before. Scale: bytes per index.
#if defined(__AVX512F__)
inline constexpr bool kHasHardwareGather = true;
template <int Scale>
Int gather_i32(const void* base, const Int& index) { return _mm512_i32gather_epi32(__m512i(index), base, Scale); }
template <int Scale>
Float gather_f32(const float* base, const Int& index) { return _mm512_i32gather_ps(__m512i(index), base, Scale); }
#elif defined(__AVX2__)
inline constexpr bool kHasHardwareGather = true;
template <int Scale>
Int gather_i32(const void* base, const Int& index) {
  return _mm256_i32gather_epi32(static_cast<const int*>(base), __m256i(index), Scale);
}
template <int Scale>
Float gather_f32(const float* base, const Int& index) { return _mm256_i32gather_ps(base, __m256i(index), Scale); }
#else
inline constexpr bool kHasHardwareGather = false;
#endif

#if defined(__AVX2__)
// A lane's offset from its table's base, for the AVX2 loads built by hand. Offsets are never negative (texels of a
// texture, entries of a table): as unsigned, the 32 bits a vpextrd or a 32-bit load leaves zero-extended in its
// register serve as they are, where a signed offset took a cdqe or movsxd per lane (about 40 of a twin sample's
// 870 instructions, 16 of a QDM pair step's 330).
[[gnu::always_inline]] inline std::size_t lane_offset(std::int32_t o) { return std::uint32_t(o); }
#endif

#if defined(__AVX2__) && !defined(__AVX512F__)
// The AVX2 build's load_bytes4, load_i32 and load_f32: eight scalar loads instead of one vpgatherdd / vgatherdps.
// On Zen 3 (AMD family 25, the AVX2-only machines issue #53 is judged on) a ymm gather is microcoded: 39 uops, one
// per 8 cycles, latency up to 28 cycles (uops.info), against 8 loads and 7 inserts here. qdmr_texel_load_bench
// (single/*, Zen 3): independent vectors alike (L1 1.84 G lanes/s gathered, 1.71 by hand; L2 1.22, 1.49), a chain
// of dependent loads 1.29-1.35x faster by hand; frames in docs/performance-history.md. On Zen 5, whose gathers are
// fast, hand-built loads measured 0.976-1.002x (sessions 33-37); the AVX-512 build keeps its gathers.
// The 4 bytes at base + Scale * o[lane] for lanes a..a+3 in one 128-bit register: vmovd and three vpinsrd from memory.
template <int Scale>
[[gnu::always_inline]] inline __m128i load_four4(const void* base, const std::int32_t* o, int a) {
  std::int32_t v[4];
  for (int i = 0; i < 4; ++i)
    std::memcpy(&v[i], static_cast<const std::uint8_t*>(base) + lane_offset(o[a + i]) * Scale, 4);
  __m128i r = _mm_cvtsi32_si128(v[0]);
  r = _mm_insert_epi32(r, v[1], 1);
  r = _mm_insert_epi32(r, v[2], 2);
  return _mm_insert_epi32(r, v[3], 3);
}

// gather_i32<Scale> of 8 lanes from 8 scalar loads, o: the lanes' indices in memory.
template <int Scale>
[[gnu::always_inline]] inline __m256i avx2_loads4(const void* base, const std::int32_t* o) {
  return _mm256_inserti128_si256(_mm256_castsi128_si256(load_four4<Scale>(base, o, 0)), load_four4<Scale>(base, o, 4),
                                 1);
}

// avx2_loads4 with the indices in a vector.
template <int Scale>
[[gnu::always_inline]] inline __m256i avx2_loads4(const void* base, const Int& index) {
  alignas(32) std::int32_t o[kLanes];
  index.store_aligned(o);
  return avx2_loads4<Scale>(base, o);
}
#endif

// 4 bytes at base + byte_offset[lane] (unaligned), as a little-endian int32 per lane.
inline Int load_bytes4(const std::uint8_t* base, const Int& byte_offset, FetchPath path) {
#if defined(__AVX512F__)
  if (path == FetchPath::Gather) return gather_i32<1>(base, byte_offset);
#elif defined(__AVX2__)
  if (path == FetchPath::Gather) return Int(avx2_loads4<1>(base, byte_offset));
#endif
  (void)path;
  alignas(64) std::int32_t offset[kLanes], value[kLanes];
  byte_offset.store_aligned(offset);
  for (int lane = 0; lane < kLanes; ++lane) std::memcpy(&value[lane], base + offset[lane], 4);
  return Int::load_aligned(value);
}

#if defined(__AVX2__)
// The 8 bytes at base + o[a], then those at base + o[a + 1]: two lanes of load_bytes8 in one 128-bit register
// (a function, not a lambda: GCC outlined such lambdas).
[[gnu::always_inline]] inline __m128i load_two_pairs(const std::uint8_t* base, const std::int32_t* o, int a) {
  return _mm_unpacklo_epi64(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + lane_offset(o[a]))),
                            _mm_loadl_epi64(reinterpret_cast<const __m128i*>(base + lane_offset(o[a + 1]))));
}
#endif

#if defined(__AVX512F__)
// The AVX-512 halves of load_bytes8 and load_f32x4_pair.
// 128-bit segment j of the result: load_two_pairs(base, o, lane + 4j).
[[gnu::always_inline]] inline __m512 avx512_pairs(const std::uint8_t* base, const std::int32_t* o, int lane) {
  __m512i v = _mm512_castsi128_si512(load_two_pairs(base, o, lane));  // insert positions: immediates, even at -O0
  v = _mm512_inserti32x4(v, load_two_pairs(base, o, lane + 4), 1);
  v = _mm512_inserti32x4(v, load_two_pairs(base, o, lane + 8), 2);
  return _mm512_castsi512_ps(_mm512_inserti32x4(v, load_two_pairs(base, o, lane + 12), 3));
}

// Floats at..at+3 of each lane's texel (base + o[lane]), one vector per float: per 128-bit segment j, a 4x4
// transpose of the texels of lanes 4j..4j+3.
[[gnu::always_inline]] inline void avx512_transpose(const float* base, const std::int32_t* o, int at, Float* out) {
  __m512 r[4];
  for (int lane = 0; lane < 4; ++lane) {  // segment j of r[lane]: the texel of lane + 4j (immediate positions)
    r[lane] = _mm512_castps128_ps512(_mm_loadu_ps(base + o[lane] + at));
    r[lane] = _mm512_insertf32x4(r[lane], _mm_loadu_ps(base + o[lane + 4] + at), 1);
    r[lane] = _mm512_insertf32x4(r[lane], _mm_loadu_ps(base + o[lane + 8] + at), 2);
    r[lane] = _mm512_insertf32x4(r[lane], _mm_loadu_ps(base + o[lane + 12] + at), 3);
  }
  const __m512 t0 = _mm512_unpacklo_ps(r[0], r[1]), t1 = _mm512_unpackhi_ps(r[0], r[1]);
  const __m512 t2 = _mm512_unpacklo_ps(r[2], r[3]), t3 = _mm512_unpackhi_ps(r[2], r[3]);
  out[0] = Float(_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)));
  out[1] = Float(_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)));
  out[2] = Float(_mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)));
  out[3] = Float(_mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2)));
}
#endif

// 8 bytes at base + o[lane] (unaligned), o: the lanes' byte offsets in memory: bytes 0-3 as `first`, bytes 4-7 as
// `second` (two adjacent 4-byte texels from one load). AVX2 and AVX-512 build them from 64-bit loads by hand:
// measured on this project's machines, a pair costs what one 8-lane vpgatherdd of single texels does, where two
// 4-lane vpgatherdq take 1.2-1.4x that.
[[gnu::always_inline]] inline void load_bytes8_at(const std::uint8_t* base, const std::int32_t* o, FetchPath path,
                                                  Int& first, Int& second) {
#if defined(__AVX512F__)
  if (path == FetchPath::Gather) {
    const __m512 x = avx512_pairs(base, o, 0), y = avx512_pairs(base, o, 2);
    first = Int(_mm512_castps_si512(_mm512_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0))));
    second = Int(_mm512_castps_si512(_mm512_shuffle_ps(x, y, _MM_SHUFFLE(3, 1, 3, 1))));
    return;
  }
#elif defined(__AVX2__)
  if (path == FetchPath::Gather) {
    const auto halves = [&](int lane) {  // low half: lanes lane, lane + 1; high half: lanes lane + 4, lane + 5
      return _mm256_castsi256_ps(_mm256_inserti128_si256(_mm256_castsi128_si256(load_two_pairs(base, o, lane)),
                                                         load_two_pairs(base, o, lane + 4), 1));
    };
    const __m256 x = halves(0), y = halves(2);
    first = Int(_mm256_castps_si256(_mm256_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0))));
    second = Int(_mm256_castps_si256(_mm256_shuffle_ps(x, y, _MM_SHUFFLE(3, 1, 3, 1))));
    return;
  }
#endif
  (void)path;
  alignas(64) std::int32_t a[kLanes], b[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    std::memcpy(&a[lane], base + o[lane], 4);
    std::memcpy(&b[lane], base + o[lane] + 4, 4);
  }
  first = Int::load_aligned(a);
  second = Int::load_aligned(b);
}

// load_bytes8_at() with the offsets in a vector.
[[gnu::always_inline]] inline void load_bytes8(const std::uint8_t* base, const Int& byte_offset, FetchPath path,
                                               Int& first, Int& second) {
  alignas(64) std::int32_t o[kLanes];
  byte_offset.store_aligned(o);
  load_bytes8_at(base, o, path, first, second);
}

// Floats at..at+3 of each lane's texel of 4 floats at base + o[lane] (unaligned), o: the lanes' float indices in
// memory, into out[0..3], one vector per float. AVX2 and AVX-512 transpose them from 128-bit loads (4x4 per 128-bit
// segment); the 4-lane builds transpose four 128-bit loads (a lane-by-lane loop through memory costs a
// store-forwarding stall per vector).
[[gnu::always_inline]] inline void load_f32x4_at(const float* base, const std::int32_t* o, int at, FetchPath path,
                                                 Float* out) {
#if defined(__AVX512F__)
  if (path == FetchPath::Gather) {
    avx512_transpose(base, o, at, out);
    return;
  }
#elif defined(__AVX2__)
  if (path == FetchPath::Gather) {
    const auto row = [&](int lane) {  // lane's texel in the low half, lane + 4's in the high half
      return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(base + lane_offset(o[lane]) + at)),
                                  _mm_loadu_ps(base + lane_offset(o[lane + 4]) + at), 1);
    };
    const __m256 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
    const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
    out[0] = Float(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)));
    out[1] = Float(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)));
    out[2] = Float(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)));
    out[3] = Float(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2)));
    return;
  }
#elif defined(__SSE2__) && !defined(__AVX__)
  static_assert(kLanes == 4);
  (void)path;
  const auto row = [&](int lane) { return _mm_loadu_ps(base + o[lane] + at); };
  __m128 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out[0] = Float(r0);
  out[1] = Float(r1);
  out[2] = Float(r2);
  out[3] = Float(r3);
  return;
#endif
  (void)path;
  alignas(64) float value[4][kLanes];
  for (int lane = 0; lane < kLanes; ++lane)
    for (int i = 0; i < 4; ++i) value[i][lane] = base[o[lane] + at + i];
  for (int i = 0; i < 4; ++i) out[i] = Float::load_aligned(value[i]);
}

// Two texels of 4 floats at base + o[lane]: floats 0-3 into first[0..3], floats 4-7 into second[0..3].
[[gnu::always_inline]] inline void load_f32x4_pair_at(const float* base, const std::int32_t* o, FetchPath path,
                                                      Float* first, Float* second) {
  load_f32x4_at(base, o, 0, path, first);
  load_f32x4_at(base, o, 4, path, second);
}

// load_f32x4_at() of one texel (at 0) with the indices in a vector.
[[gnu::always_inline]] inline void load_f32x4(const float* base, const Int& index, FetchPath path, Float* out) {
  alignas(64) std::int32_t o[kLanes];
  index.store_aligned(o);
#if defined(__AVX512F__)
  // Read back through memory: else GCC extracts the 16 indices from the register (vpextrd, valignd, vmovd), which
  // cost relief's and POM's footprint loads more than one store and 16 scalar loads (1.03-1.04x their frames).
  asm volatile("" : "+m"(o));
#endif
  load_f32x4_at(base, o, 0, path, out);
}

// load_f32x4_pair_at() with the indices in a vector.
[[gnu::always_inline]] inline void load_f32x4_pair(const float* base, const Int& index, FetchPath path, Float* first,
                                                   Float* second) {
  alignas(64) std::int32_t o[kLanes];
  index.store_aligned(o);
  load_f32x4_pair_at(base, o, path, first, second);
}

// table[index[lane]] for int32 and float tables.
inline Int load_i32(const std::int32_t* table, const Int& index, FetchPath path) {
#if defined(__AVX512F__)
  if (path == FetchPath::Gather) return gather_i32<4>(table, index);
#elif defined(__AVX2__)
  if (path == FetchPath::Gather) return Int(avx2_loads4<4>(table, index));
#endif
  (void)path;
  alignas(64) std::int32_t i[kLanes], value[kLanes];
  index.store_aligned(i);
  for (int lane = 0; lane < kLanes; ++lane) value[lane] = table[i[lane]];
  return Int::load_aligned(value);
}

// table[index[lane]] for a table of 16 int32 and index in [0, 16), such as a texture's per-level sizes: a register
// permute where the ISA has one (AVX2: two, AVX-512: one), far cheaper than a gather.
inline Int lookup16(const std::int32_t* table, const Int& index) {
#if defined(__AVX512F__)
  return _mm512_permutexvar_epi32(__m512i(index), _mm512_loadu_si512(table));
#elif defined(__AVX2__)
  const __m256i i = __m256i(index);
  const __m256i low = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(table)), i);
  const __m256i high = _mm256_permutevar8x32_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(table + 8)), i);
  return _mm256_blendv_epi8(low, high, _mm256_cmpgt_epi32(i, _mm256_set1_epi32(7)));
#else
  return load_i32(table, index, FetchPath::Portable);
#endif
}

inline Float load_f32(const float* table, const Int& index, FetchPath path) {
#if defined(__AVX512F__)
  if (path == FetchPath::Gather) return gather_f32<4>(table, index);
#elif defined(__AVX2__)
  if (path == FetchPath::Gather) return Float(_mm256_castsi256_ps(avx2_loads4<4>(table, index)));
#endif
  (void)path;
  alignas(64) std::int32_t i[kLanes];
  alignas(64) float value[kLanes];
  index.store_aligned(i);
  for (int lane = 0; lane < kLanes; ++lane) value[lane] = table[i[lane]];
  return Float::load_aligned(value);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
