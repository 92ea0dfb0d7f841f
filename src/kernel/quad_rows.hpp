#pragma once
// A batch's lanes and the two framebuffer rows it covers. A batch holds kQuadsPerBatch 2x2 quads side by side:
// lane 4q + 2r + c is pixel (2q + c, r), so each row's 2 * kQuadsPerBatch pixels are pairs of lanes. These move
// a batch's lanes from and to two rows of floats with register shuffles (pixel pairs as 64-bit elements): a
// round trip through an array of lanes (scalar stores, then a vector load) stalls on store forwarding. Raw
// intrinsics: xsimd 8 has no two-source shuffle (shufps, vpermt2ps) and no permutation by an index vector.
#include "core/simd.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace qdmr::QDMR_ISA_NAMESPACE::simd {

// The lanes of pixels row0[0 .. 2 * kQuadsPerBatch) and row1[...] (unaligned).
[[gnu::always_inline]] inline Float load_quad_rows(const float* row0, const float* row1) {
#if defined(__AVX512F__)
  const __m512i a = _mm512_castsi256_si512(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row0)));
  const __m512i b = _mm512_castsi256_si512(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(row1)));
  return Float(_mm512_castsi512_ps(_mm512_permutex2var_epi64(a, _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11), b)));
#elif defined(__AVX2__)
  const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row0));
  const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row1));
  return Float(_mm256_castsi256_ps(_mm256_set_m128i(_mm_unpackhi_epi64(a, b), _mm_unpacklo_epi64(a, b))));
#elif defined(__SSE2__)
  const __m128i a = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(row0));
  const __m128i b = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(row1));
  return Float(_mm_castsi128_ps(_mm_unpacklo_epi64(a, b)));
#else
  alignas(64) float lanes[kLanes];
  for (int l = 0; l < kLanes; ++l) lanes[l] = ((l % 4) / 2 == 0 ? row0 : row1)[(l / 4) * 2 + l % 2];
  return Float::load_aligned(lanes);
#endif
}

// The inverse: writes the lanes of v to their pixels of row0 and row1.
[[gnu::always_inline]] inline void store_quad_rows(const Float& v, float* row0, float* row1) {
#if defined(__AVX512F__)
  const __m512i rows = _mm512_permutexvar_epi64(_mm512_setr_epi64(0, 2, 4, 6, 1, 3, 5, 7), _mm512_castps_si512(v));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(row0), _mm512_castsi512_si256(rows));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(row1), _mm512_extracti64x4_epi64(rows, 1));
#elif defined(__AVX2__)
  const __m256i lanes = _mm256_castps_si256(v);
  const __m128i low = _mm256_castsi256_si128(lanes), high = _mm256_extracti128_si256(lanes, 1);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(row0), _mm_unpacklo_epi64(low, high));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(row1), _mm_unpackhi_epi64(low, high));
#elif defined(__SSE2__)
  const __m128i lanes = _mm_castps_si128(v);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(row0), lanes);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(row1), _mm_unpackhi_epi64(lanes, lanes));
#else
  alignas(64) float lanes[kLanes];
  v.store_aligned(lanes);
  for (int l = 0; l < kLanes; ++l) ((l % 4) / 2 == 0 ? row0 : row1)[(l / 4) * 2 + l % 2] = lanes[l];
#endif
}

#if defined(__AVX512F__)
namespace quad_rows_detail {

// The permutations that interleave a 16-lane batch's three channels into its two rows of RGB floats. The rows'
// 48 floats, row 0's 24 then row 1's, are three vectors; float k of vector j is channel c of pixel p of row r
// (16 j + k = 24 r + 3 p + c), which is lane 4 (p / 2) + 2 r + p % 2. First, r and g into place (index 16 + lane
// picks g); then b into the floats of channel 2 (index 16 + lane picks b, index k keeps the first result's).
struct RgbPermutes {
  alignas(64) int red_green[3][16];
  alignas(64) int add_blue[3][16];
};

constexpr RgbPermutes make_rgb_permutes() {
  RgbPermutes t{};
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 16; ++k) {
      const int s = 16 * j + k, r = s / 24, p = (s % 24) / 3, c = s % 3;
      const int lane = 4 * (p / 2) + 2 * r + p % 2;
      t.red_green[j][k] = c == 1 ? 16 + lane : lane;
      t.add_blue[j][k] = c == 2 ? 16 + lane : k;
    }
  return t;
}

inline constexpr RgbPermutes kRgbPermutes = make_rgb_permutes();

}  // namespace quad_rows_detail
#endif

// Writes the lanes of three channels to their pixels of two rows of interleaved RGB floats (pixel x of a row at
// row[3x .. 3x + 2]; unaligned), by in-register shuffles instead of a scalar store per channel and lane:
// AVX-512: each row's 8 pixels are 24 consecutive floats, the two rows three vectors of two permutations each,
// written as 512- and 256-bit stores; AVX2: each row's 4 pixels are 12 consecutive floats, written as three 128-bit
// stores per row after an in-register 4 x 3 transpose (both rows at once, one per 128-bit half). SSE4.2 stores
// per lane.
[[gnu::always_inline]] inline void store_quad_rows_rgb(const Float& r, const Float& g, const Float& b, float* row0,
                                                       float* row1) {
#if defined(__AVX512F__)
  using quad_rows_detail::kRgbPermutes;
  __m512 out[3];
  for (int j = 0; j < 3; ++j) {
    const __m512i red_green = _mm512_load_si512(kRgbPermutes.red_green[j]);
    const __m512i add_blue = _mm512_load_si512(kRgbPermutes.add_blue[j]);
    out[j] = _mm512_permutex2var_ps(_mm512_permutex2var_ps(r, red_green, g), add_blue, b);
  }
  // Row 0: floats 0-15 and 16-23; row 1: floats 24-31 and 32-47.
  _mm512_storeu_ps(row0, out[0]);
  _mm256_storeu_ps(row0 + 16, _mm512_castps512_ps256(out[1]));
  _mm256_storeu_ps(row1, _mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(out[1]), 1)));
  _mm512_storeu_ps(row1 + 8, out[2]);
#elif defined(__AVX2__)
  // Row 0's pixels (lanes 0, 1, 4, 5) in the low half, row 1's (lanes 2, 3, 6, 7) in the high half.
  const auto rows = [](const Float& v) { return _mm256_permute4x64_pd(_mm256_castps_pd(v), 0xd8); };
  const __m256 rr = _mm256_castpd_ps(rows(r)), gg = _mm256_castpd_ps(rows(g)), bb = _mm256_castpd_ps(rows(b));
  // Per half, pixels p0..p3: out0 = r0 g0 b0 r1, out1 = g1 b1 r2 g2, out2 = b2 r3 g3 b3.
  const __m256 rg_low = _mm256_unpacklo_ps(rr, gg);   // r0 g0 r1 g1
  const __m256 rg_high = _mm256_unpackhi_ps(rr, gg);  // r2 g2 r3 g3
  const __m256 b0_r1 = _mm256_shuffle_ps(bb, rg_low, _MM_SHUFFLE(2, 2, 0, 0));    // b0 b0 r1 r1
  const __m256 g1_b1 = _mm256_shuffle_ps(rg_low, bb, _MM_SHUFFLE(1, 1, 3, 3));    // g1 g1 b1 b1
  const __m256 b2_r3g3 = _mm256_shuffle_ps(bb, rg_high, _MM_SHUFFLE(3, 2, 2, 2));  // b2 b2 r3 g3
  const __m256 g3_b3 = _mm256_shuffle_ps(rg_high, bb, _MM_SHUFFLE(3, 3, 3, 3));   // g3 g3 b3 b3
  const __m256 out0 = _mm256_shuffle_ps(rg_low, b0_r1, _MM_SHUFFLE(2, 0, 1, 0));
  const __m256 out1 = _mm256_shuffle_ps(g1_b1, rg_high, _MM_SHUFFLE(1, 0, 2, 0));
  const __m256 out2 = _mm256_shuffle_ps(b2_r3g3, g3_b3, _MM_SHUFFLE(2, 0, 2, 0));
  _mm_storeu_ps(row0, _mm256_castps256_ps128(out0));
  _mm_storeu_ps(row0 + 4, _mm256_castps256_ps128(out1));
  _mm_storeu_ps(row0 + 8, _mm256_castps256_ps128(out2));
  _mm_storeu_ps(row1, _mm256_extractf128_ps(out0, 1));
  _mm_storeu_ps(row1 + 4, _mm256_extractf128_ps(out1, 1));
  _mm_storeu_ps(row1 + 8, _mm256_extractf128_ps(out2, 1));
#else
  alignas(64) float lanes[3][kLanes];
  r.store_aligned(lanes[0]);
  g.store_aligned(lanes[1]);
  b.store_aligned(lanes[2]);
  for (int l = 0; l < kLanes; ++l)
    for (int c = 0; c < 3; ++c) ((l % 4) / 2 == 0 ? row0 : row1)[3 * ((l / 4) * 2 + l % 2) + c] = lanes[c][l];
#endif
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
