// Lane compaction moves lanes and computes nothing: the working lanes of every batch fill the packed batches in
// order, each comes back from unpack() with its own bits (NaN payloads and signed zeros included), the lanes past
// the packed ones repeat packed lane 0, and no more packed batches are made than the lanes need.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <random>
#include <vector>

#include "kernel/lane_compaction.hpp"
#include "support/lane_values.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using simd::LaneCompaction;

using test::bits_of;
using test::lanes_of;

void expect_round_trip(const std::vector<std::uint32_t>& lanes) {
  const int count = int(lanes.size());
  Float values[LaneCompaction::kMaxBatches];
  alignas(64) float in[LaneCompaction::kMaxBatches][kLanes];
  std::vector<std::uint32_t> expected;  // the working lanes' bits in packing order
  for (int k = 0; k < count; ++k) {
    values[k] = lanes_of(k + 1);
    values[k].store_aligned(in[k]);
    for (int l = 0; l < kLanes; ++l)
      if ((lanes[std::size_t(k)] >> l) & 1u) expected.push_back(bits_of(in[k][l]));
  }
  const LaneCompaction compaction(lanes.data(), count);
  const int total = int(expected.size());
  ASSERT_EQ(compaction.batches(), count);
  ASSERT_EQ(compaction.packed_batches(), std::max(1, (total + kLanes - 1) / kLanes));
  Float packed[LaneCompaction::kMaxBatches];
  for (int w = 0; w < compaction.packed_batches(); ++w) {
    packed[w] = compaction.pack(w, [&](int k) -> const Float& { return values[k]; });
    alignas(64) float p[kLanes];
    packed[w].store_aligned(p);
    const int used = std::clamp(total - w * kLanes, 0, kLanes);
    EXPECT_EQ(simd::to_bits(compaction.used(w)), (1u << used) - 1u) << "packed batch " << w;
    for (int l = 0; l < used; ++l)
      ASSERT_EQ(bits_of(p[l]), expected[std::size_t(w * kLanes + l)]) << "packed batch " << w << " lane " << l;
    if (used > 0) {
      for (int l = used; l < kLanes; ++l) ASSERT_EQ(bits_of(p[l]), bits_of(p[0])) << "packed batch " << w;
    }
  }
  for (int k = 0; k < count; ++k) {
    alignas(64) float back[kLanes];
    compaction.unpack(k, [&](int w) -> const Float& { return packed[w]; }).store_aligned(back);
    for (int l = 0; l < kLanes; ++l) {
      if ((lanes[std::size_t(k)] >> l) & 1u) {
        ASSERT_EQ(bits_of(back[l]), bits_of(in[k][l])) << "batch " << k << " lane " << l;
      }
    }
  }
}

TEST(LaneCompaction, EveryWorkingLaneComesBackWithItsBits) {
  const std::uint32_t all = (1u << kLanes) - 1u;
  std::mt19937 rng(21);
  for (int round = 0; round < 4000; ++round) {
    // Sparse masks as small triangles leave them, full and empty batches among them.
    std::vector<std::uint32_t> lanes(std::size_t(1 + round % LaneCompaction::kMaxBatches));
    for (std::uint32_t& m : lanes) {
      const std::uint32_t kind = rng() % 8;
      m = kind == 0 ? 0u : kind == 1 ? all : (rng() & rng() & all);
    }
    expect_round_trip(lanes);
  }
  expect_round_trip({0});
  expect_round_trip({all});
  expect_round_trip({all, 0, 0});
  expect_round_trip({0, 0, 1u << (kLanes - 1)});
  expect_round_trip(std::vector<std::uint32_t>(LaneCompaction::kMaxBatches, all));
}

}  // namespace
}  // namespace qdmr
