// PixelBuffer's allocator: large blocks on 2 MiB boundaries with the kernel's transparent-huge-page advice, so a
// fresh frame's first touch faults once per 2 MiB (docs/performance.md, "cold frames"); small blocks as usual.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

#include "qdmr/core/pixel_buffer.hpp"

namespace qdmr {
namespace {

constexpr std::uintptr_t kHugePage = std::uintptr_t(2) << 20;

// The "THPeligible" line of the /proc/self/smaps mapping that holds `address`, or "" when not found.
std::string thp_eligible(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const auto a = reinterpret_cast<std::uintptr_t>(address);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= a && a < hi;
      continue;
    }
    if (inside && line.rfind("THPeligible:", 0) == 0) return line;
  }
  return "";
}

TEST(PixelBuffer, LargeBlocksAreHugePageAlignedAndAdvised) {
  PixelBuffer large(std::size_t(3) << 20);  // 12 MiB
  ASSERT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % kHugePage, 0u);
  large.assign(large.size(), 1.0f);  // every page written once
  EXPECT_EQ(large.back(), 1.0f);
  std::ifstream enabled("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(enabled, modes);
  if (modes.empty() || modes.find("[never]") != std::string::npos)
    GTEST_SKIP() << "no transparent huge pages on this system: the blocks keep ordinary pages";
  // In both the `always` and the `madvise` mode an advised mapping is eligible (the kernel may still fall back to
  // small pages when memory is fragmented; eligibility is what the allocator controls).
  EXPECT_NE(thp_eligible(large.data()).find('1'), std::string::npos) << thp_eligible(large.data());
}

TEST(PixelBuffer, SmallBlocksAndGrowthKeepTheirValues) {
  PixelBuffer small(100, 2.0f);
  EXPECT_EQ(small[99], 2.0f);
  small.resize(std::size_t(1) << 20, 3.0f);  // grows past 2 MiB: moved into a large block
  EXPECT_EQ(small[0], 2.0f);
  EXPECT_EQ(small[99], 2.0f);
  EXPECT_EQ(small.back(), 3.0f);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(small.data()) % kHugePage, 0u);
}

}  // namespace
}  // namespace qdmr
