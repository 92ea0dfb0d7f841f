// The max/min reducers of one ISA (compiled once per ISA, like the draw kernels): whole vectors of texel pairs
// with SSE4.1 or AVX2 intrinsics (xsimd 8 has no byte/word pack or lane permute), the rest scalar.
#include "texture/mip_reduce.hpp"

#include <type_traits>

#include <immintrin.h>

#include "qdmr/core/isa.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::mip {
namespace {

// ---- SIMD primitives: the same names on 256-bit (AVX2) or 128-bit (SSE4.1) vectors ----
#if defined(__AVX2__)
#define QDMR_MIP_SIMD 1
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
#elif defined(__SSE4_1__)
#define QDMR_MIP_SIMD 1
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

// The scalar forms return what MAXPS / MINPS return (the second operand unless the first wins), so the
// vector body and the scalar tail agree even on NaN and signed zeros.
struct MaxOp {
  template <class T>
  static T scalar(T a, T b) { return a > b ? a : b; }
#ifdef QDMR_MIP_SIMD
  static VecI u8(VecI a, VecI b) { return max_u8(a, b); }
  static VecI u16(VecI a, VecI b) { return max_u16(a, b); }
  static VecF f32(VecF a, VecF b) { return max_f(a, b); }
#endif
};

struct MinOp {
  template <class T>
  static T scalar(T a, T b) { return a < b ? a : b; }
#ifdef QDMR_MIP_SIMD
  static VecI u8(VecI a, VecI b) { return min_u8(a, b); }
  static VecI u16(VecI a, VecI b) { return min_u16(a, b); }
  static VecF f32(VecF a, VecF b) { return min_f(a, b); }
#endif
};

// out texel i = op over texels 2i and 2i+1 of rows a and b (vertical first, then horizontal), for the first
// pairs that fill whole vectors; returns how many were done. T is the channel type, C the channel count.
template <class Op, class T, int C>
int reduce_pairs_simd([[maybe_unused]] const std::uint8_t* a, [[maybe_unused]] const std::uint8_t* b,
                      [[maybe_unused]] std::uint8_t* out, [[maybe_unused]] int pairs) {
#ifdef QDMR_MIP_SIMD
  constexpr int kTexelBytes = C * int(sizeof(T));
  constexpr int kStep = kVecBytes / kTexelBytes;  // output texels per iteration
  int i = 0;
  for (; i + kStep <= pairs; i += kStep) {
    const std::uint8_t* pa = a + std::size_t(i) * 2 * kTexelBytes;
    const std::uint8_t* pb = b + std::size_t(i) * 2 * kTexelBytes;
    std::uint8_t* po = out + std::size_t(i) * kTexelBytes;
    if constexpr (std::is_same_v<T, float>) {
      const VecF v0 = Op::f32(load_f(pa), load_f(pb));
      const VecF v1 = Op::f32(load_f(pa + kVecBytes), load_f(pb + kVecBytes));
      store_f(po, lane_order(Op::f32(even_f(v0, v1), odd_f(v0, v1))));
    } else {
      const auto op = [](VecI x, VecI y) {
        if constexpr (sizeof(T) == 1) return Op::u8(x, y);
        else return Op::u16(x, y);
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
#else
  return 0;
#endif
}

// One output row from input rows a and b (b == a for a single row) of in_width texels.
template <class Op, class T, int C>
void reduce_two_rows(const std::uint8_t* a, const std::uint8_t* b, int in_width, std::uint8_t* out, int out_width) {
  if (in_width == 1) {
    for (int c = 0; c < C; ++c) store<T>(out, c, Op::scalar(load<T>(a, c), load<T>(b, c)));
    return;
  }
  for (int i = reduce_pairs_simd<Op, T, C>(a, b, out, out_width); i < out_width; ++i)
    for (int c = 0; c < C; ++c) {
      const std::size_t left = std::size_t(2 * i) * C + c, right = left + C;
      const T l = Op::scalar(load<T>(a, left), load<T>(b, left));
      const T r = Op::scalar(load<T>(a, right), load<T>(b, right));
      store<T>(out, std::size_t(i) * C + c, Op::scalar(l, r));
    }
  if (in_width & 1)  // the last texel also covers the leftover column
    for (int c = 0; c < C; ++c) {
      const std::size_t last = std::size_t(in_width - 1) * C + c, o = std::size_t(out_width - 1) * C + c;
      store<T>(out, o, Op::scalar(load<T>(out, o), Op::scalar(load<T>(a, last), load<T>(b, last))));
    }
}

template <class Op, class T, int C>
void reduce_extremum(const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w, int out_h) {
  const std::size_t in_row = std::size_t(in_w) * C * sizeof(T), out_row = std::size_t(out_w) * C * sizeof(T);
  for_rows(out_h, out_row, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const Taps ty = taps(y, in_h, out_h);
      const std::uint8_t* r0 = in + std::size_t(ty.first) * in_row;
      std::uint8_t* o = out + std::size_t(y) * out_row;
      reduce_two_rows<Op, T, C>(r0, ty.count > 1 ? r0 + in_row : r0, in_w, o, out_w);
      if (ty.count == 3) {  // the leftover row of an odd height: once per level, scalar
        const std::uint8_t* r2 = r0 + 2 * in_row;
        for (int x = 0; x < out_w; ++x) {
          const Taps tx = taps(x, in_w, out_w);
          for (int c = 0; c < C; ++c) {
            T v = load<T>(r2, std::size_t(tx.first) * C + c);
            for (int i = 1; i < tx.count; ++i) v = Op::scalar(v, load<T>(r2, std::size_t(tx.first + i) * C + c));
            const std::size_t oi = std::size_t(x) * C + c;
            store<T>(o, oi, Op::scalar(load<T>(o, oi), v));
          }
        }
      }
    }
  });
}

template <class Op>
void reduce_format(TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out, int out_w,
                   int out_h) {
  switch (format) {
    case TexelFormat::R8: reduce_extremum<Op, std::uint8_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RG8: reduce_extremum<Op, std::uint8_t, 2>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::RGBA8: reduce_extremum<Op, std::uint8_t, 4>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R16: reduce_extremum<Op, std::uint16_t, 1>(in, in_w, in_h, out, out_w, out_h); break;
    case TexelFormat::R32F: reduce_extremum<Op, float, 1>(in, in_w, in_h, out, out_w, out_h); break;
  }
}

}  // namespace

void reduce_extremum(bool max, TexelFormat format, const std::uint8_t* in, int in_w, int in_h, std::uint8_t* out,
                     int out_w, int out_h) {
  if (max)
    reduce_format<MaxOp>(format, in, in_w, in_h, out, out_w, out_h);
  else
    reduce_format<MinOp>(format, in, in_w, in_h, out, out_w, out_h);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::mip
