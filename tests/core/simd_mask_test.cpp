// Mask conversions between float and integer lanes are reinterpretations of the register; they must keep every
// lane, and a converted mask must select and combine like one built by a comparison of its own type.
#include <gtest/gtest.h>

#include <cstdint>

#include "core/simd.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;
using simd::kLanes;

TEST(SimdMask, ConversionsKeepEveryLane) {
  const std::uint32_t all = (1u << kLanes) - 1u;
  for (std::uint32_t bits = 0; bits <= all; bits += kLanes >= 16 ? 7 : 1) {  // every pattern; with 16 lanes a spread
    alignas(64) std::int32_t flags[kLanes];
    for (int l = 0; l < kLanes; ++l) flags[l] = int((bits >> l) & 1u);
    const simd::IntMask from_compare = Int::load_aligned(flags) != Int(0);
    const simd::Mask as_float = simd::float_mask(from_compare);
    ASSERT_EQ(simd::to_bits(as_float), bits);
    ASSERT_EQ(simd::to_bits(simd::from_bits(bits)), bits);
    const simd::IntMask back = simd::int_mask(simd::from_bits(bits));
    alignas(64) std::int32_t picked[kLanes];
    xsimd::select(back, Int(7), Int(-3)).store_aligned(picked);
    for (int l = 0; l < kLanes; ++l) ASSERT_EQ(picked[l], (bits >> l) & 1u ? 7 : -3) << bits << " lane " << l;
    ASSERT_EQ(xsimd::any(back), bits != 0);
    ASSERT_EQ(xsimd::all(back & from_compare), bits == all);
  }
}

}  // namespace
}  // namespace qdmr
