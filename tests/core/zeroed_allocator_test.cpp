#include "qdmr/core/zeroed_allocator.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "support/test_support.hpp"

namespace qdmr {
namespace {

using Floats = std::vector<float, ZeroedAllocator<float>>;

TEST(ZeroedAllocator, SmallAndLargeVectorsStartAtZero) {
  for (const std::size_t n : {std::size_t(1), std::size_t(1000), kFreshPagesBytes / sizeof(float) + 5}) {
    const Floats v(n);
    ASSERT_EQ(v.size(), n);
    for (std::size_t i = 0; i < n; i += 4093) EXPECT_EQ(v[i], 0.0f) << n << " " << i;
    EXPECT_EQ(v.back(), 0.0f);
  }
  EXPECT_EQ(Floats(3, 2.5f), (Floats{2.5f, 2.5f, 2.5f}));  // a value given is written
}

// The reason the allocator exists: a block freed after being written, then asked for again, must come back as
// zeros without being cleared by a write (a general-purpose allocator reuses it, and calloc must clear it).
TEST(ZeroedAllocator, ABlockWrittenAndFreedComesBackZero) {
  for (const std::size_t n : {std::size_t(1000), std::size_t(1) << 18, 2 * kFreshPagesBytes / sizeof(float)})
    for (int round = 0; round < 3; ++round) {
      Floats v(n);
      for (std::size_t i = 0; i < n; i += 1021) ASSERT_EQ(v[i], 0.0f) << n << " " << round << " " << i;
      for (float& x : v) x = 1.0f;
    }
}

// A gigabyte asked for and never written is not held in memory: only pages written are committed. The bound
// leaves 64 MB for whatever else the process touches meanwhile (a page table, the test framework), against the
// 1 GB the vector would commit if its zeros were written.
TEST(ZeroedAllocator, ALargeBlockCostsOnlyThePagesWritten) {
  const std::uint64_t before = test::resident_bytes();
  Floats v(std::size_t(1) << 28);  // 1 GiB
  v[12345] = 1.0f;
  const std::uint64_t after = test::resident_bytes();
  EXPECT_LT(after, before + (std::uint64_t(64) << 20)) << "before " << before << ", after " << after;
  EXPECT_EQ(v[12345], 1.0f);
  EXPECT_EQ(v[v.size() - 1], 0.0f);
}

}  // namespace
}  // namespace qdmr
