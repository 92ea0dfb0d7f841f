#pragma once
// Two sparse batches' working lanes in one batch. Where small triangles leave a batch a few covered pixels (the
// other lanes of their quads only feed derivatives), the work that is lane by lane can run once for two batches:
// pack() moves the lanes set in `first` of one value, then those set in `second` of the other, side by side from
// lane 0; first() and second() give each batch its lanes back. Lanes are moved, never computed, so every packed
// lane's result has the bits it would have had in its own batch. Raw intrinsics: xsimd 8 has no compress or expand
// and no permutation by a run-time index vector.
#include <bit>
#include <cstdint>

#include "core/simd.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace qdmr::QDMR_ISA_NAMESPACE::simd {

class LanePacking {
public:
  // Whether the lanes set in `first` and `second` fit in one batch.
  static bool fits(std::uint32_t first, std::uint32_t second) {
    return std::popcount(first) + std::popcount(second) <= kLanes;
  }

  // fits(first, second) must hold.
  LanePacking(std::uint32_t first, std::uint32_t second) {
    const int count_first = std::popcount(first), count_second = std::popcount(second);
#if defined(__AVX512F__)
    first_ = __mmask16(first);
    second_ = __mmask16(second);
    packed_second_ = __mmask16(((1u << count_second) - 1u) << count_first);
    used_ = __mmask16((1u << (count_first + count_second)) - 1u);
#else
    // Lane indices: where each packed lane comes from (packed_second_: from b), and where each batch's lanes went.
    int packed = 0;
    for (int l = 0; l < kLanes; ++l)
      if ((first >> l) & 1u) {
        first_lane_[l] = packed;
        source_[packed++] = l;
      }
    for (int l = 0; l < kLanes; ++l)
      if ((second >> l) & 1u) {
        second_lane_[l] = packed;
        source_[packed++] = l;
      }
    packed_second_ = ((1u << count_second) - 1u) << count_first;
    for (int l = packed; l < kLanes; ++l) {  // lane 0 again
      source_[l] = source_[0];
      if (packed_second_ & 1u) packed_second_ |= 1u << l;
    }
#endif
  }

  // a's lanes set in `first`, then b's set in `second`; the lanes after them repeat packed lane 0. (A lane left
  // zero costs more than a live lane: with zero coordinates and a zero frame, a grid frame's packed sampling and
  // lighting took 1.1x as long as without packing.)
  Float pack(const Float& a, const Float& b) const {
#if defined(__AVX512F__)
    const __m512 packed = _mm512_mask_expand_ps(_mm512_maskz_compress_ps(first_, a), packed_second_,
                                                _mm512_maskz_compress_ps(second_, b));
    return _mm512_mask_broadcastss_ps(packed, __mmask16(~used_), _mm512_castps512_ps128(packed));
#elif defined(__AVX2__)
    const __m256i source = _mm256_load_si256(reinterpret_cast<const __m256i*>(source_));
    return _mm256_blendv_ps(_mm256_permutevar8x32_ps(a, source), _mm256_permutevar8x32_ps(b, source),
                            _mm256_castsi256_ps(lane_bits_mask(packed_second_)));
#else
    alignas(64) float from_a[kLanes], from_b[kLanes], packed[kLanes];
    a.store_aligned(from_a);
    b.store_aligned(from_b);
    for (int l = 0; l < kLanes; ++l) packed[l] = ((packed_second_ >> l) & 1u ? from_b : from_a)[source_[l]];
    return Float::load_aligned(packed);
#endif
  }

  // The lanes set in `first` as they were packed; the other lanes are undefined.
  Float first(const Float& packed) const {
#if defined(__AVX512F__)
    return _mm512_maskz_expand_ps(first_, packed);
#else
    return from_packed(packed, first_lane_);
#endif
  }

  // The lanes set in `second` as they were packed; the other lanes are undefined.
  Float second(const Float& packed) const {
#if defined(__AVX512F__)
    return _mm512_maskz_expand_ps(second_, _mm512_maskz_compress_ps(packed_second_, packed));
#else
    return from_packed(packed, second_lane_);
#endif
  }

private:
#if defined(__AVX512F__)
  __mmask16 first_, second_, packed_second_, used_;
#else
  Float from_packed(const Float& packed, const std::int32_t* lane) const {
#if defined(__AVX2__)
    return _mm256_permutevar8x32_ps(packed, _mm256_load_si256(reinterpret_cast<const __m256i*>(lane)));
#else
    alignas(64) float from[kLanes], to[kLanes];
    packed.store_aligned(from);
    for (int l = 0; l < kLanes; ++l) to[l] = from[lane[l]];
    return Float::load_aligned(to);
#endif
  }
#if defined(__AVX2__)
  // All-ones in the lanes whose bit is set.
  static __m256i lane_bits_mask(std::uint32_t bits) {
    const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    return _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(bits)), bit), bit);
  }
#endif
  alignas(32) std::int32_t source_[kLanes] = {}, first_lane_[kLanes] = {}, second_lane_[kLanes] = {};
  std::uint32_t packed_second_;
#endif
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
