#pragma once
// Several sparse batches' working lanes in as few batches as hold them. Small triangles leave many batches a few
// covered pixels (the other lanes of their quads only feed derivatives); the work that is lane by lane can run on
// full batches instead: the working lanes of batches 0 .. count - 1, in that order, fill packed batch 0, then 1,
// and so on (ceil(lanes / kLanes) of them). pack() gives a packed batch's lanes of a value, unpack() a batch's
// lanes back from the packed batches. Lanes are moved, never computed, so every packed lane's result has the
// bits it would have had in its own batch. (simd::LanePacking is the two-into-one case, built for it.)
#include <algorithm>
#include <bit>
#include <cstdint>

#include "core/simd.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace qdmr::QDMR_ISA_NAMESPACE::simd {

class LaneCompaction {
public:
  static constexpr int kMaxBatches = 8;

  // lanes[k]: the working lanes of batch k (bit i: lane i); 1 <= count <= kMaxBatches.
  LaneCompaction(const std::uint32_t* lanes, int count) : count_(count) {
    int total = 0;
    for (int k = 0; k < count; ++k) {
      first_packed_[k] = total / kLanes;
      std::fill_n(to_lane_[k], kLanes, 0);  // a lane that does not work: any lane of a packed batch
      for (std::uint32_t bits = lanes[k]; bits != 0; bits &= bits - 1) {
        const int l = std::countr_zero(bits), w = total / kLanes, p = total % kLanes;
        from_batch_[w][p] = k;
        from_lane_[w][p] = l;
        to_batch_[k][l] = w;
        to_lane_[k][l] = p;
        ++total;
      }
      last_packed_[k] = std::max(first_packed_[k], (total - 1) / kLanes);
    }
    packed_ = std::max(1, (total + kLanes - 1) / kLanes);
    for (int k = 0; k < count; ++k) {
      // A batch without working lanes after the last packed lane reads that one.
      first_packed_[k] = std::min(first_packed_[k], packed_ - 1);
      last_packed_[k] = std::min(last_packed_[k], packed_ - 1);
      for (int l = 0; l < kLanes; ++l)
        if (((lanes[k] >> l) & 1u) == 0) to_batch_[k][l] = first_packed_[k];
    }
    for (int w = 0; w < packed_; ++w) {
      used_[w] = std::clamp(total - w * kLanes, 0, kLanes);
      if (used_[w] == 0) {  // no working lane at all: batch 0's lane 0
        from_batch_[w][0] = 0;
        from_lane_[w][0] = 0;
      }
      // The lanes after the last one repeat packed lane 0 (a lane left zero costs more than a live lane:
      // simd::LanePacking).
      for (int p = std::max(used_[w], 1); p < kLanes; ++p) {
        from_batch_[w][p] = from_batch_[w][0];
        from_lane_[w][p] = from_lane_[w][0];
      }
      first_source_[w] = from_batch_[w][0];
      last_source_[w] = from_batch_[w][std::max(used_[w], 1) - 1];
    }
  }

  int batches() const { return count_; }
  int packed_batches() const { return packed_; }
  // The batch packed batch w's first lane comes from.
  int first_source(int w) const { return first_source_[w]; }
  // The lanes of packed batch w that hold a working lane.
  Mask used(int w) const { return from_bits((1u << used_[w]) - 1u); }

  // Packed batch w of a value, value(k) being batch k's.
  template <class Value>
  Float pack(int w, const Value& value) const {
    return gather(from_lane_[w], from_batch_[w], first_source_[w], last_source_[w], value);
  }

  // Batch k's working lanes of a value, packed(w) being packed batch w's; its other lanes are undefined.
  template <class Packed>
  Float unpack(int k, const Packed& packed) const {
    return gather(to_lane_[k], to_batch_[k], first_packed_[k], last_packed_[k], packed);
  }

private:
  // Lane i of the result: lane lanes[i] of source(sources[i]), sources[i] in [first, last].
  template <class Source>
  static Float gather(const std::int32_t* lanes, const std::int32_t* sources, int first, int last,
                      const Source& source) {
    const Int lane = Int::load_aligned(lanes), from = Int::load_aligned(sources);
    const Int control = shuffle_control(lane);
    Float result = permute(source(first), control);
    for (int k = first + 1; k <= last; ++k)
      result = xsimd::select(float_mask(from == Int(k)), permute(source(k), control), result);
    return result;
  }
  // What permute() takes for lane indices: the indices (AVX2, AVX-512), or pshufb's byte indices (SSE4.2).
  static Int shuffle_control(const Int& lane) {
#if defined(__AVX2__)
    return lane;
#else
    return (lane << 2) * Int(0x01010101) + Int(0x03020100);
#endif
  }
  // Lane i of the result: lane control[i] of x (raw intrinsics: xsimd 8 has no permutation by a run-time index).
  static Float permute(const Float& x, const Int& control) {
#if defined(__AVX512F__)
    return _mm512_permutexvar_ps(control, x);
#elif defined(__AVX2__)
    return _mm256_permutevar8x32_ps(x, control);
#else
    return _mm_castsi128_ps(_mm_shuffle_epi8(_mm_castps_si128(x), control));
#endif
  }

  int count_, packed_ = 0;
  int used_[kMaxBatches] = {};
  int first_source_[kMaxBatches] = {}, last_source_[kMaxBatches] = {};  // of each packed batch
  int first_packed_[kMaxBatches] = {}, last_packed_[kMaxBatches] = {};  // of each batch
  alignas(64) std::int32_t from_batch_[kMaxBatches][kLanes] = {}, from_lane_[kMaxBatches][kLanes] = {};
  alignas(64) std::int32_t to_batch_[kMaxBatches][kLanes] = {}, to_lane_[kMaxBatches][kLanes] = {};
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE::simd
