// PNG output encodes every channel with srgb_code8, a table; it must give the bits of the curve it replaces,
// srgb_code(v, 255), for every float. Checked here: both sides of every step's threshold, a stride through all
// floats of [0, 1] (every 61st bit pattern: 17 million values with every mantissa residue), and the values
// outside it. (Run over all 1,065,353,216 floats of [0, 1] once, when the table was written: no difference.)
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "write/srgb_encode.hpp"

namespace qdmr {
namespace {

TEST(SrgbEncode, TableGivesTheCurvesCodesForEveryFloat) {
  const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
  std::uint32_t previous = 0;
  for (std::uint32_t bits = 0; bits <= one; bits += 61) {
    const float v = std::bit_cast<float>(bits);
    const std::uint32_t expected = srgb_code(v, 255.0f);
    ASSERT_EQ(srgb_code8(v), expected) << "v = " << v << " (bits " << bits << ")";
    ASSERT_GE(expected, previous) << "the curve's codes must not decrease (v = " << v << ")";
    previous = expected;
  }
  for (int k = 1; k < 256; ++k) {  // the exact float where each code starts, and the one below it
    std::uint32_t lo = 0, hi = one;
    while (hi - lo > 1) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      (srgb_code(std::bit_cast<float>(mid), 255.0f) >= std::uint32_t(k) ? hi : lo) = mid;
    }
    ASSERT_EQ(srgb_code8(std::bit_cast<float>(hi)), k);
    ASSERT_EQ(srgb_code8(std::bit_cast<float>(hi - 1)), k - 1);
  }
  const float inf = std::numeric_limits<float>::infinity();
  for (const float v : {-inf, -1.0f, -0.0f, 0.0f, std::numeric_limits<float>::denorm_min(), 1.0f, 1.5f, inf,
                        std::numeric_limits<float>::quiet_NaN()})
    EXPECT_EQ(srgb_code8(v), srgb_code(v, 255.0f)) << v;
  EXPECT_EQ(srgb_code8(0.5f), 188);  // the sRGB code of linear 0.5 (0.7354 * 255 = 187.5: rounds up)
}

}  // namespace
}  // namespace qdmr
