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

// and_not(a, b) is a & ~b lane by lane (not ~a & b, the other order of the andnot instructions), for float and
// integer masks.
TEST(SimdMask, AndNotKeepsTheFirstWithoutTheSecond) {
  const std::uint32_t all = (1u << kLanes) - 1u;
  const std::uint32_t stride_a = kLanes >= 16 ? 251 : 1, stride_b = kLanes >= 16 ? 241 : 1;  // 16 lanes: a spread
  for (std::uint32_t a = 0; a <= all; a += stride_a)
    for (std::uint32_t b = 0; b <= all; b += stride_b) {
      const simd::Mask ma = simd::from_bits(a), mb = simd::from_bits(b);
      ASSERT_EQ(simd::to_bits(simd::and_not(ma, mb)), a & ~b & all) << a << " " << b;
      const simd::IntMask ia = simd::int_mask(ma), ib = simd::int_mask(mb);
      ASSERT_EQ(simd::to_bits(simd::float_mask(simd::and_not(ia, ib))), a & ~b & all) << a << " " << b;
    }
}

// plus_one_where / minus_one_where change exactly the lanes of the mask, by one.
TEST(SimdMask, PlusAndMinusOneWhereTheMaskIsSet) {
  alignas(64) std::int32_t start[kLanes], plus[kLanes], minus[kLanes];
  for (int l = 0; l < kLanes; ++l) start[l] = 1000 * l - 3;
  const Int n = Int::load_aligned(start);
  const std::uint32_t bits = 0x5A3Cu & ((1u << kLanes) - 1u);
  const simd::IntMask m = simd::int_mask(simd::from_bits(bits));
  simd::plus_one_where(n, m).store_aligned(plus);
  simd::minus_one_where(n, m).store_aligned(minus);
  for (int l = 0; l < kLanes; ++l) {
    const int d = (bits >> l) & 1u ? 1 : 0;
    ASSERT_EQ(plus[l], start[l] + d) << "lane " << l;
    ASSERT_EQ(minus[l], start[l] - d) << "lane " << l;
  }
}

}  // namespace
}  // namespace qdmr
