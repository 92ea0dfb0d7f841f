// TileCounters (raster/raster_context.hpp): a tile's counters are kept from draw to draw and zeroed by the tile,
// and zeroing and summing touch only the iteration histogram's bins in use. Summed or zeroed that way, they must
// equal a sum over every bin, and a reset must leave nothing behind.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "raster/raster_context.hpp"

namespace qdmr {
namespace {

constexpr std::size_t kBins = TileCounters::kIterationBins + 1;

TEST(TileCounters, SumsAndZeroesTheBinsInUse) {
  TileCounters a, b;
  a.count_iterations(0, 16);
  a.count_iterations(7, 3);
  b.count_iterations(3, 5);
  b.count_iterations(5000, 2);  // beyond the last bin: counted in it
  b.pixels_shaded = 9;
  EXPECT_EQ(a.histogram_bins, 8);
  EXPECT_EQ(b.histogram_bins, TileCounters::kIterationBins + 1);

  std::array<std::uint64_t, kBins> expected{};
  expected[0] = 16;
  expected[7] = 3;
  expected[3] = 5;
  expected[TileCounters::kIterationBins] = 2;
  TileCounters total;
  total += a;
  total += b;
  for (std::size_t i = 0; i < kBins; ++i) EXPECT_EQ(total.iteration_histogram[i], expected[i]) << "bin " << i;
  EXPECT_EQ(total.histogram_bins, TileCounters::kIterationBins + 1);
  EXPECT_EQ(total.pixels_shaded, 9u);

  // A reset leaves every bin and counter at zero, and the counters count again from there.
  b.reset();
  for (std::size_t i = 0; i < kBins; ++i) EXPECT_EQ(b.iteration_histogram[i], 0u) << "bin " << i;
  EXPECT_EQ(b.histogram_bins, 0);
  EXPECT_EQ(b.pixels_shaded, 0u);
  b.count_iterations(2, 1);
  TileCounters again;
  again += b;
  for (std::size_t i = 0; i < kBins; ++i) EXPECT_EQ(again.iteration_histogram[i], i == 2 ? 1u : 0u) << "bin " << i;
}

}  // namespace
}  // namespace qdmr
