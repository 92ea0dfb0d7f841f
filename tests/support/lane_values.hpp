#pragma once
// Lane values for the tests of code that moves lanes between batches: each lane's bits are its own.
#include <bit>
#include <cstdint>

#include "core/simd.hpp"

namespace qdmr::test {

inline std::uint32_t bits_of(float f) { return std::bit_cast<std::uint32_t>(f); }

// Distinct bit patterns per lane and per batch, among them a NaN with a payload and a negative zero.
inline simd::Float lanes_of(int batch) {
  alignas(64) float v[simd::kLanes];
  for (int l = 0; l < simd::kLanes; ++l) v[l] = float(100 * batch + l) + 0.25f;
  v[1] = -0.0f;
  v[simd::kLanes - 1] = std::bit_cast<float>(0x7fc01234u + std::uint32_t(batch));
  return simd::Float::load_aligned(v);
}

}  // namespace qdmr::test
