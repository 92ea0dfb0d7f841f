// Lane packing moves lanes and computes nothing: every lane set in either mask comes back from first() or second()
// with its own bits (NaN payloads and signed zeros included), and the lanes past the packed ones repeat lane 0.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <random>

#include "kernel/lane_packing.hpp"
#include "support/lane_values.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using simd::LanePacking;

using test::bits_of;
using test::lanes_of;

void expect_round_trip(std::uint32_t first, std::uint32_t second) {
  const Float a = lanes_of(1), b = lanes_of(2);
  alignas(64) float in_a[kLanes], in_b[kLanes], packed[kLanes], back_a[kLanes], back_b[kLanes];
  a.store_aligned(in_a);
  b.store_aligned(in_b);
  const LanePacking packing(first, second);
  const Float p = packing.pack(a, b);
  p.store_aligned(packed);
  packing.first(p).store_aligned(back_a);
  packing.second(p).store_aligned(back_b);
  int next = 0;
  for (int l = 0; l < kLanes; ++l)
    if ((first >> l) & 1u) {
      ASSERT_EQ(bits_of(packed[next++]), bits_of(in_a[l])) << first << " " << second << " lane " << l;
      ASSERT_EQ(bits_of(back_a[l]), bits_of(in_a[l])) << first << " " << second << " lane " << l;
    }
  for (int l = 0; l < kLanes; ++l)
    if ((second >> l) & 1u) {
      ASSERT_EQ(bits_of(packed[next++]), bits_of(in_b[l])) << first << " " << second << " lane " << l;
      ASSERT_EQ(bits_of(back_b[l]), bits_of(in_b[l])) << first << " " << second << " lane " << l;
    }
  for (int l = next; l < kLanes; ++l) ASSERT_EQ(bits_of(packed[l]), bits_of(packed[0])) << first << " " << second;
}

TEST(LanePacking, EveryLaneComesBackWithItsBits) {
  const std::uint32_t all = (1u << kLanes) - 1u;
  if (kLanes <= 8) {  // every pair of masks that fits
    for (std::uint32_t first = 0; first <= all; ++first)
      for (std::uint32_t second = 0; second <= all; ++second)
        if (LanePacking::fits(first, second)) expect_round_trip(first, second);
    return;
  }
  std::mt19937 rng(12);
  int tested = 0;
  while (tested < 20000) {
    // Sparse masks as small triangles leave them, and every count up to a full batch on one side.
    const std::uint32_t first = rng() & rng() & all, second = rng() & rng() & rng() & all;
    if (!LanePacking::fits(first, second)) continue;
    expect_round_trip(first, second);
    ++tested;
  }
  expect_round_trip(all, 0);
  expect_round_trip(0, all);
  expect_round_trip(1, 1u << (kLanes - 1));
}

TEST(LanePacking, FitsCountsBothBatchesLanes) {
  const std::uint32_t all = (1u << kLanes) - 1u;
  EXPECT_TRUE(LanePacking::fits(all, 0));
  EXPECT_TRUE(LanePacking::fits(all >> (kLanes / 2), all >> (kLanes / 2)));
  EXPECT_FALSE(LanePacking::fits(all, 1));
  EXPECT_FALSE(LanePacking::fits(all >> 1, 3));
}

}  // namespace
}  // namespace qdmr
