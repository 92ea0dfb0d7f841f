#include "qdmr/core/zeroed_buffer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "support/test_support.hpp"

namespace qdmr {
namespace {

using Floats = ZeroedBuffer<float>;

TEST(ZeroedBuffer, SmallAndLargeBuffersStartAtZero) {
  for (const std::size_t n : {std::size_t(1), std::size_t(1000), kFreshPagesBytes / sizeof(float) + 5}) {
    const Floats v(n);
    ASSERT_EQ(v.size(), n);
    for (std::size_t i = 0; i < n; i += 4093) EXPECT_EQ(v[i], 0.0f) << n << " " << i;
    EXPECT_EQ(v[n - 1], 0.0f);
  }
  EXPECT_TRUE(Floats().empty());
  EXPECT_TRUE(Floats(0).empty());
  EXPECT_EQ(Floats(0).data(), nullptr);
}

TEST(ZeroedBuffer, ValuesGivenAreWritten) {
  EXPECT_EQ(Floats(3, 2.5f), (Floats{2.5f, 2.5f, 2.5f}));
  EXPECT_TRUE(std::signbit(Floats(2, -0.0f)[1]));  // equal to 0, but not all zero bytes
  const std::vector<float> source{1.0f, -2.0f, 3.0f};
  const Floats copied(source.begin(), source.end());
  EXPECT_EQ(std::vector<float>(copied.begin(), copied.end()), source);
  Floats assigned(7);
  assigned.assign(source.begin(), source.end());
  EXPECT_EQ(assigned, copied);
  assigned.assign(2, 4.0f);
  EXPECT_EQ(assigned, (Floats{4.0f, 4.0f}));
  EXPECT_FALSE(assigned == (Floats{4.0f, 4.0f, 0.0f}));  // sizes differ
  EXPECT_FALSE(assigned == (Floats{4.0f, 5.0f}));
}

TEST(ZeroedBuffer, CopiesAreDeepAndMovesLeaveAnEmptyBuffer) {
  Floats a{1.0f, 2.0f};
  Floats b = a;
  b[0] = 9.0f;
  EXPECT_EQ(a, (Floats{1.0f, 2.0f}));
  const float* block = b.data();
  Floats c = std::move(b);
  EXPECT_EQ(c.data(), block);
  EXPECT_TRUE(b.empty());  // a moved-from buffer is empty (and may be reused)
  a = c;
  EXPECT_EQ(a, (Floats{9.0f, 2.0f}));
  const Floats& same = a;
  a = same;  // self-assignment keeps the values
  EXPECT_EQ(a, (Floats{9.0f, 2.0f}));
}

// The reason the buffer maps large blocks itself: a block freed after being written, then asked for again, must
// come back as zeros without being cleared by a write (a general-purpose allocator reuses it, and calloc must
// clear it).
TEST(ZeroedBuffer, ABlockWrittenAndFreedComesBackZero) {
  for (const std::size_t n : {std::size_t(1000), std::size_t(1) << 18, 2 * kFreshPagesBytes / sizeof(float)})
    for (int round = 0; round < 3; ++round) {
      Floats v(n);
      for (std::size_t i = 0; i < n; i += 1021) ASSERT_EQ(v[i], 0.0f) << n << " " << round << " " << i;
      for (float& x : v) x = 1.0f;
    }
}

// A gigabyte asked for and never written is not held in memory: only pages written are committed. The bound
// leaves 64 MB for whatever else the process touches meanwhile (a page table, the test framework), against the
// 1 GB the buffer would commit if its zeros were written.
TEST(ZeroedBuffer, ALargeBlockCostsOnlyThePagesWritten) {
  const std::uint64_t before = test::resident_bytes();
  Floats v(std::size_t(1) << 28);  // 1 GiB
  v[12345] = 1.0f;
  const std::uint64_t after = test::resident_bytes();
  EXPECT_LT(after, before + (std::uint64_t(64) << 20)) << "before " << before << ", after " << after;
  EXPECT_EQ(v[12345], 1.0f);
  EXPECT_EQ(v[v.size() - 1], 0.0f);
}

TEST(ZeroedBuffer, ASizeBeyondMemoryThrows) {
  EXPECT_THROW(Floats(std::size_t(-1) / 2), std::bad_alloc);
}

}  // namespace
}  // namespace qdmr
