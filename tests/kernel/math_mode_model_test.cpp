// Math modes: SM4 integer cell arithmetic is exact; SM3's fp32 emulation agrees where fp32 represents every
// cell boundary, and these tests find (and pin) where it stops doing so. docs/sampling.md quotes the numbers.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>

#include "kernel/math_mode_model.hpp"

namespace qdmr {
namespace {

template <class M>
int broken_edges(int n, std::int64_t first_cell = 0) {
  int broken = 0;
  for (std::int64_t c = first_cell; c <= first_cell + n; ++c) broken += M::cell_of(M::cell_start(c, n), n) != c;
  return broken;
}

TEST(MathMode, Sm4CellArithmeticIsExactForEverySize) {
  for (int n = 1; n <= 2048; ++n) {
    ASSERT_EQ(broken_edges<Sm4Math>(n), 0) << n;
    ASSERT_EQ(broken_edges<Sm4Math>(n, -3 * std::int64_t(n)), 0) << n;  // negative repeats floor correctly
    for (std::int64_t c : {std::int64_t(0), std::int64_t(n / 3), std::int64_t(n)})
      ASSERT_EQ(Sm4Math::cell_of(Sm4Math::cell_start(c, n) - 1, n), c - 1) << n;  // one step back is the previous cell
  }
  for (int n : {4096, 8191, 16384}) EXPECT_EQ(broken_edges<Sm4Math>(n, 9999 * std::int64_t(n)), 0);  // uv near 1e4
}

TEST(MathMode, Sm3AgreesWithSm4OnPowerOfTwoSizes) {
  // c / 2^m and u * 2^m are exact in fp32 while the cell index fits 24 bits.
  for (int m = 0; m <= 14; ++m) {
    const int n = 1 << m;
    EXPECT_EQ(broken_edges<Sm3Math>(n), 0) << n;
    for (std::int64_t c = 0; c < n; c += std::max(1, n / 512)) {
      const float u = float((double(c) + 0.5) / n);
      EXPECT_EQ(Sm3Math::cell_of(Sm3Math::from_uv(u), n), Sm4Math::cell_of(Sm4Math::from_uv(u), n));
    }
  }
}

TEST(MathMode, Sm3FirstBreaksOnNonPowerOfTwoSizeTwentyTwo) {
  // The first size whose fp32 cell edge c / n lands in the previous cell: n = 22, c = 13
  // (13 / 22 rounds down and floor(13/22 * 22) = 12). fp64 breaks at the same size: c / n is inexact in both.
  int first = 0;
  for (int n = 1; n <= 64 && first == 0; ++n)
    if (broken_edges<Sm3Math>(n) > 0) first = n;
  EXPECT_EQ(first, 22);
  EXPECT_EQ(Sm3Math::cell_of(Sm3Math::cell_start(13, 22), 22), 12);
  EXPECT_GT(broken_edges<ExactMath>(22), 0);
  int sizes_with_broken_edges = 0;
  for (int n = 1; n <= 4096; ++n) sizes_with_broken_edges += broken_edges<Sm3Math>(n) > 0;
  EXPECT_EQ(sizes_with_broken_edges, 3839);  // of 4096: every NPOT size but a few
}

TEST(MathMode, Fp32UvStopsAddressingTexelCentresFarFromTheOrigin) {
  // Both modes see the same fp32 uv; the uv itself cannot hold k + (i + 0.5)/n once log2(k) + log2(n) + 1 > 24.
  // Largest error in texels of the cell found for texel centres at repeat offset k, for n = 1024 and 16384.
  auto worst = [](int n, std::int64_t k) {
    std::int64_t worst_error = 0;
    for (std::int64_t i = 0; i < n; i += n > 1024 ? 7 : 1) {  // 7: a step that does not align with the fp32 spacing
      const float u = float(double(k) + (double(i) + 0.5) / n);
      const std::int64_t cell = Sm4Math::cell_of(Sm4Math::from_uv(u), n);
      EXPECT_EQ(cell, Sm3Math::cell_of(Sm3Math::from_uv(u), n)) << n << " " << k << " " << i;
      worst_error = std::max<std::int64_t>(worst_error, std::llabs(cell - (k * n + i)));
    }
    return worst_error;
  };
  EXPECT_EQ(worst(1024, 1000), 0);
  EXPECT_EQ(worst(1024, 10000), 1);  // |uv| ~ 1e4: off by one texel
  EXPECT_EQ(worst(16384, 100), 0);
  EXPECT_EQ(worst(16384, 1000), 1);
  EXPECT_EQ(worst(16384, 10000), 8);  // fp32 spacing at 1e4 is 2^-10 = 16 texels: half of it lost
}

}  // namespace
}  // namespace qdmr
