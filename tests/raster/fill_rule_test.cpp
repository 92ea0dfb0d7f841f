// The fill rule: triangles that share edges cover every pixel of their union exactly once.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>

#include "raster/raster_test_util.hpp"

namespace qdmr::test {
namespace {

// Deterministic jitter in [-amplitude, amplitude] from a hash of (i, j).
double jitter(int i, int j, double amplitude) {
  std::uint32_t h = std::uint32_t(i) * 0x9E3779B1u ^ std::uint32_t(j) * 0x85EBCA77u;
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  return (double(h & 0xFFFFu) / 65535.0 * 2.0 - 1.0) * amplitude;
}

// Checks the rasterizer against the reference coverage and that no pixel is hit twice.
void expect_exact_single_coverage(const ScreenScene& scene, int tile_size) {
  const std::vector<int> counts = scene.raster_counts(tile_size);
  int double_hits = 0, mismatches = 0;
  for (int y = 0; y < scene.height; ++y)
    for (int x = 0; x < scene.width; ++x) {
      int expected = 0;
      for (const ScreenTriangle& t : scene.geometry.triangles) expected += reference_covers(t, x, y);
      const int got = counts[std::size_t(y * scene.width + x)];
      double_hits += got > 1;
      mismatches += got != expected;
    }
  EXPECT_EQ(double_hits, 0);
  EXPECT_EQ(mismatches, 0);
}

TEST(FillRule, JitteredGridSharingEdgesCoversEachPixelOnce) {
  ScreenScene scene(160, 120);
  // Vertices on a 12x9 lattice with sub-pixel jitter inside; the outer border stays on pixel edges, so the
  // union is exactly the rectangle [8, 152) x [6, 114) and every pixel centre in it must be hit once.
  const int nx = 12, ny = 9;
  auto vx = [&](int i, int j) { return 8.0 + i * (144.0 / nx) + ((i > 0 && i < nx) ? jitter(i, j, 4.0) : 0.0); };
  auto vy = [&](int i, int j) { return 6.0 + j * (108.0 / ny) + ((j > 0 && j < ny) ? jitter(j, i + 100, 4.0) : 0.0); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const bool flip = (i + j) % 2 == 0;  // both diagonal directions
      if (flip) {
        scene.add(vx(i, j), vy(i, j), vx(i + 1, j), vy(i + 1, j), vx(i + 1, j + 1), vy(i + 1, j + 1));
        scene.add(vx(i, j), vy(i, j), vx(i + 1, j + 1), vy(i + 1, j + 1), vx(i, j + 1), vy(i, j + 1));
      } else {
        scene.add(vx(i, j), vy(i, j), vx(i + 1, j), vy(i + 1, j), vx(i, j + 1), vy(i, j + 1));
        scene.add(vx(i + 1, j), vy(i + 1, j), vx(i + 1, j + 1), vy(i + 1, j + 1), vx(i, j + 1), vy(i, j + 1));
      }
    }
  const std::vector<int> counts = scene.raster_counts();
  for (int y = 0; y < scene.height; ++y)
    for (int x = 0; x < scene.width; ++x) {
      const bool inside = x >= 8 && x < 152 && y >= 6 && y < 114;
      ASSERT_EQ(counts[std::size_t(y * scene.width + x)], inside ? 1 : 0) << "pixel " << x << "," << y;
    }
  expect_exact_single_coverage(scene, 16);
}

TEST(FillRule, FanAroundOneVertexIncludingSliversCoversOnce) {
  ScreenScene scene(128, 128);
  // 40 triangles around a centre on a pixel corner (centres exactly on shared edges test the tie rule),
  // with uneven angles so some are slivers a fraction of a degree wide.
  const double cx = 64.0, cy = 64.0, r = 55.0;
  std::vector<double> angles;
  for (int k = 0; k < 40; ++k) angles.push_back(2.0 * std::numbers::pi * (k + (k % 3 == 0 ? 0.02 : 0.5 * (k % 2))) / 40.0);
  angles.push_back(angles.front() + 2.0 * std::numbers::pi);
  for (std::size_t k = 0; k + 1 < angles.size(); ++k)
    scene.add(cx, cy, cx + r * std::cos(angles[k]), cy + r * std::sin(angles[k]), cx + r * std::cos(angles[k + 1]),
              cy + r * std::sin(angles[k + 1]));
  expect_exact_single_coverage(scene, 64);
  expect_exact_single_coverage(scene, 8);
}

TEST(FillRule, AxisAlignedEdgesThroughPixelCentresFollowTopLeft) {
  ScreenScene scene(32, 32);
  // A square from centre to centre split into two triangles: its edges run exactly through pixel centres.
  scene.add(4.5, 4.5, 20.5, 4.5, 20.5, 20.5);
  scene.add(4.5, 4.5, 20.5, 20.5, 4.5, 20.5);
  const std::vector<int> counts = scene.raster_counts();
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      // Top and left edges are in, bottom and right are out: columns 4..19, rows 4..19.
      const bool inside = x >= 4 && x <= 19 && y >= 4 && y <= 19;
      ASSERT_EQ(counts[std::size_t(y * 32 + x)], inside ? 1 : 0) << x << "," << y;
    }
}

TEST(FillRule, ThinSliversAndTinyTrianglesMatchReference) {
  ScreenScene scene(96, 64);
  for (int k = 0; k < 60; ++k) {
    const double x = 2.0 + k * 1.5 + jitter(k, 1, 0.3), y = 3.0 + jitter(k, 2, 0.3);
    scene.add(x, y, x + 0.05 + jitter(k, 3, 0.02), y + 55.0, x + 0.7, y + 54.0);  // long, a fraction of a pixel wide
    scene.add(x + 0.3, 60.2, x + 0.9, 60.4, x + 0.5, 61.1);                      // smaller than a pixel
  }
  expect_exact_single_coverage(scene, 32);
}

TEST(FillRule, CoverageIsIndependentOfTileSize) {
  ScreenScene scene(200, 150);
  for (int k = 0; k < 300; ++k) {
    const double x = jitter(k, 7, 100.0) + 100.0, y = jitter(k, 8, 75.0) + 75.0;
    scene.add(x, y, x + jitter(k, 9, 30.0), y + jitter(k, 10, 30.0), x + jitter(k, 11, 30.0), y + jitter(k, 12, 30.0));
  }
  const std::vector<int> reference = scene.raster_counts(64);
  for (int tile : {8, 16, 32, 128, 1024}) EXPECT_EQ(scene.raster_counts(tile), reference) << "tile " << tile;
}

}  // namespace
}  // namespace qdmr::test
