// A kernel's max/min reducer (Kernel::mip_extremum): the scalar reduction of texture/mip_reduce.hpp around a loop
// over whole vectors of texel pairs with SSE4.1 or AVX2 intrinsics (xsimd 8 has no byte/word pack or lane
// permute; the AVX-512 kernel runs the AVX2 loop).
#include <type_traits>

#include <immintrin.h>

#include "kernel/kernel_calls.hpp"
#include "texture/mip_reduce.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::mip {
namespace {

// ---- SIMD primitives: the same names on 256-bit (AVX2) or 128-bit (SSE4.1) vectors ----
#if defined(__AVX2__)
using VecI = __m256i;
using VecF = __m256;
constexpr int kVecBytes = 32;
VecI load_i(const std::uint8_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
void store_i(std::uint8_t* p, VecI v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
VecF load_f(const std::uint8_t* p) { return _mm256_loadu_ps(reinterpret_cast<const float*>(p)); }
void store_f(std::uint8_t* p, VecF v) { _mm256_storeu_ps(reinterpret_cast<float*>(p), v); }
VecI max_u8(VecI a, VecI b) { return _mm256_max_epu8(a, b); }
VecI min_u8(VecI a, VecI b) { return _mm256_min_epu8(a, b); }
VecI max_u16(VecI a, VecI b) { return _mm256_max_epu16(a, b); }
VecI min_u16(VecI a, VecI b) { return _mm256_min_epu16(a, b); }
VecF max_f(VecF a, VecF b) { return _mm256_max_ps(a, b); }
VecF min_f(VecF a, VecF b) { return _mm256_min_ps(a, b); }
VecI shift_right_16(VecI v) { return _mm256_srli_epi16(v, 8); }
VecI shift_right_32(VecI v) { return _mm256_srli_epi32(v, 16); }
VecI shift_right_64(VecI v) { return _mm256_srli_epi64(v, 32); }
VecI low_bytes_mask() { return _mm256_set1_epi16(0x00FF); }
VecI low_words_mask() { return _mm256_set1_epi32(0xFFFF); }
VecI and_i(VecI a, VecI b) { return _mm256_and_si256(a, b); }
// pack and shuffle work within 128-bit lanes: put the 64-bit quarters back in order.
VecI lane_order(VecI v) { return _mm256_permute4x64_epi64(v, 0xD8); }
VecF lane_order(VecF v) { return _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(v), 0xD8)); }
VecI pack_u16(VecI a, VecI b) { return _mm256_packus_epi16(a, b); }
VecI pack_u32(VecI a, VecI b) { return _mm256_packus_epi32(a, b); }
VecF even_f(VecF a, VecF b) { return _mm256_shuffle_ps(a, b, 0x88); }
VecF odd_f(VecF a, VecF b) { return _mm256_shuffle_ps(a, b, 0xDD); }
VecF as_f(VecI v) { return _mm256_castsi256_ps(v); }
VecI as_i(VecF v) { return _mm256_castps_si256(v); }
#else  // SSE4.2: every kernel has SSE4.1 at least
using VecI = __m128i;
using VecF = __m128;
constexpr int kVecBytes = 16;
VecI load_i(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
void store_i(std::uint8_t* p, VecI v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
VecF load_f(const std::uint8_t* p) { return _mm_loadu_ps(reinterpret_cast<const float*>(p)); }
void store_f(std::uint8_t* p, VecF v) { _mm_storeu_ps(reinterpret_cast<float*>(p), v); }
VecI max_u8(VecI a, VecI b) { return _mm_max_epu8(a, b); }
VecI min_u8(VecI a, VecI b) { return _mm_min_epu8(a, b); }
VecI max_u16(VecI a, VecI b) { return _mm_max_epu16(a, b); }
VecI min_u16(VecI a, VecI b) { return _mm_min_epu16(a, b); }
VecF max_f(VecF a, VecF b) { return _mm_max_ps(a, b); }
VecF min_f(VecF a, VecF b) { return _mm_min_ps(a, b); }
VecI shift_right_16(VecI v) { return _mm_srli_epi16(v, 8); }
VecI shift_right_32(VecI v) { return _mm_srli_epi32(v, 16); }
VecI shift_right_64(VecI v) { return _mm_srli_epi64(v, 32); }
VecI low_bytes_mask() { return _mm_set1_epi16(0x00FF); }
VecI low_words_mask() { return _mm_set1_epi32(0xFFFF); }
VecI and_i(VecI a, VecI b) { return _mm_and_si128(a, b); }
VecI lane_order(VecI v) { return v; }
VecF lane_order(VecF v) { return v; }
VecI pack_u16(VecI a, VecI b) { return _mm_packus_epi16(a, b); }
VecI pack_u32(VecI a, VecI b) { return _mm_packus_epi32(a, b); }
VecF even_f(VecF a, VecF b) { return _mm_shuffle_ps(a, b, 0x88); }
VecF odd_f(VecF a, VecF b) { return _mm_shuffle_ps(a, b, 0xDD); }
VecF as_f(VecI v) { return _mm_castsi128_ps(v); }
VecI as_i(VecF v) { return _mm_castps_si128(v); }
#endif

// out texel i = op over texels 2i and 2i+1 of rows a and b (vertical first, then horizontal), for the first
// pairs that fill whole vectors; returns how many were done. T is the channel type, C the channel count.
struct Vectors {
  template <class Op, class T, int C>
  static int pairs(const std::uint8_t* a, const std::uint8_t* b, std::uint8_t* out, int pairs) {
    constexpr int kTexelBytes = C * int(sizeof(T));
    constexpr int kStep = kVecBytes / kTexelBytes;  // output texels per iteration
    int i = 0;
    for (; i + kStep <= pairs; i += kStep) {
      const std::uint8_t* pa = a + std::size_t(i) * 2 * kTexelBytes;
      const std::uint8_t* pb = b + std::size_t(i) * 2 * kTexelBytes;
      std::uint8_t* po = out + std::size_t(i) * kTexelBytes;
      if constexpr (std::is_same_v<T, float>) {
        const auto op = [](VecF x, VecF y) { return Op::kMax ? max_f(x, y) : min_f(x, y); };
        const VecF v0 = op(load_f(pa), load_f(pb));
        const VecF v1 = op(load_f(pa + kVecBytes), load_f(pb + kVecBytes));
        store_f(po, lane_order(op(even_f(v0, v1), odd_f(v0, v1))));
      } else {
        const auto op = [](VecI x, VecI y) {
          if constexpr (sizeof(T) == 1) return Op::kMax ? max_u8(x, y) : min_u8(x, y);
          else return Op::kMax ? max_u16(x, y) : min_u16(x, y);
        };
        const VecI v0 = op(load_i(pa), load_i(pb));
        const VecI v1 = op(load_i(pa + kVecBytes), load_i(pb + kVecBytes));
        // Bring texel 2i+1 onto texel 2i, combine, then keep the low texel of each pair.
        if constexpr (kTexelBytes == 1) {
          const VecI h0 = and_i(op(v0, shift_right_16(v0)), low_bytes_mask());
          const VecI h1 = and_i(op(v1, shift_right_16(v1)), low_bytes_mask());
          store_i(po, lane_order(pack_u16(h0, h1)));
        } else if constexpr (kTexelBytes == 2) {
          const VecI h0 = and_i(op(v0, shift_right_32(v0)), low_words_mask());
          const VecI h1 = and_i(op(v1, shift_right_32(v1)), low_words_mask());
          store_i(po, lane_order(pack_u32(h0, h1)));
        } else {
          static_assert(kTexelBytes == 4);
          const VecI h0 = op(v0, shift_right_64(v0)), h1 = op(v1, shift_right_64(v1));
          store_i(po, as_i(lane_order(even_f(as_f(h0), as_f(h1)))));
        }
      }
    }
    return i;
  }
};

}  // namespace
}  // namespace qdmr::QDMR_ISA_NAMESPACE::mip

namespace qdmr::QDMR_ISA_NAMESPACE {

void mip_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                  int out_w, int out_h) {
  kernel_calls.mip_levels.fetch_add(1, std::memory_order_relaxed);
  mip::extremum<mip::Vectors>(max, format, in, in_w, in_h, out, out_w, out_h);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
