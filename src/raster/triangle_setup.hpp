#pragma once
// Triangle setup: integer edge functions with the top-left fill rule, and the per-vertex values
// the rasterizer interpolates. Everything a tile needs to rasterize a triangle, computed by the tile: a frame of
// small triangles would spend more writing a million setups to memory and reading them back than making them.
#include <array>
#include <cstdint>

#include "raster/geometry.hpp"

namespace qdmr {

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive
  bool empty() const { return x1 < x0 || y1 < y0; }
};

struct TriangleSetup {
  // Edge i lies opposite vertex i: w_i(X, Y) = dx_i * Y - dy_i * X + c_i at fixed-point sample (X, Y);
  // w_i >= 0 inside. bias_i is 0 on top and left edges, -1 elsewhere (the top-left rule).
  std::array<std::int32_t, 3> dx, dy;
  std::array<std::int64_t, 3> c;
  std::array<std::int64_t, 3> bias;
  PixelRect bounds;  // pixels whose centres may be covered, clamped to the viewport
  std::int64_t area2;                // doubled signed area (> 0), the sum of the three edge values
  std::array<float, 3> inv_w;       // 1 / w per vertex
  std::array<float, 3> z_over_area; // window depth / doubled area, so depth = sum(w_i * z_over_area_i)
  std::array<std::uint32_t, 3> vertex;
  std::uint32_t material;

  std::int64_t edge(int i, std::int64_t X, std::int64_t Y) const { return std::int64_t(dx[i]) * Y - std::int64_t(dy[i]) * X + c[i]; }
};

// The pixels whose centres the triangle may cover, clamped to the viewport (empty: none).
PixelRect triangle_bounds(const ScreenTriangle& t, const Viewport& viewport);

TriangleSetup setup_triangle(const ScreenTriangle& t, const GeometryResult& geometry, const Viewport& viewport);

// Fixed-point coordinate of the centre of pixel p.
inline std::int64_t pixel_centre_fixed(int p) { return std::int64_t(p) * 256 + 128; }

}  // namespace qdmr
