#pragma once
// Triangle setup: integer edge functions with the top-left fill rule, and the per-vertex values
// the rasterizer interpolates. Everything a tile needs to rasterize a triangle, computed by the tile: a frame of
// small triangles would spend more writing a million setups to memory and reading them back than making them.
#include <algorithm>
#include <array>
#include <cstdint>

#include "qdmr/core/limits.hpp"
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

// Fixed-point coordinate of the centre of pixel p.
inline std::int64_t pixel_centre_fixed(int p) { return std::int64_t(p) * 256 + 128; }
static_assert(limits::kSubpixelScale == 256, "pixel_centre_fixed and triangle_bounds assume 8 sub-pixel bits");

// Both functions below are inline: each tile calls them for every triangle it draws, in the ISA kernels.

// The pixels whose centres the triangle may cover, clamped to the viewport (empty: none). The first pixel whose
// centre is at or after v is ceil((v - 128) / 256), the last at or before it floor((v - 128) / 256); an
// arithmetic shift floors.
inline PixelRect triangle_bounds(const ScreenTriangle& t, const Viewport& viewport) {
  const auto first_pixel_at_or_after = [](std::int32_t v) { return -((128 - v) >> 8); };
  const auto last_pixel_at_or_before = [](std::int32_t v) { return (v - 128) >> 8; };
  PixelRect r;
  r.x0 = std::max(0, first_pixel_at_or_after(std::min({t.x[0], t.x[1], t.x[2]})));
  r.y0 = std::max(0, first_pixel_at_or_after(std::min({t.y[0], t.y[1], t.y[2]})));
  r.x1 = std::min(viewport.width - 1, last_pixel_at_or_before(std::max({t.x[0], t.x[1], t.x[2]})));
  r.y1 = std::min(viewport.height - 1, last_pixel_at_or_before(std::max({t.y[0], t.y[1], t.y[2]})));
  return r;
}

inline TriangleSetup setup_triangle(const ScreenTriangle& t, const GeometryResult& geometry,
                                    const Viewport& viewport) {
  TriangleSetup s;
  for (int i = 0; i < 3; ++i) {
    const int a = (i + 1) % 3, b = (i + 2) % 3;
    s.dx[i] = t.x[b] - t.x[a];
    s.dy[i] = t.y[b] - t.y[a];
    s.c[i] = std::int64_t(s.dy[i]) * t.x[a] - std::int64_t(s.dx[i]) * t.y[a];
    // Positive orientation in y-down screen space is clockwise on screen: the interior lies to the right of
    // each edge, so a top edge runs in +x with dy == 0 and a left edge runs upwards (dy < 0).
    const bool top = s.dy[i] == 0 && s.dx[i] > 0;
    const bool left = s.dy[i] < 0;
    s.bias[i] = (top || left) ? 0 : -1;
  }
  s.area2 = s.edge(0, t.x[0], t.y[0]);
  s.bounds = triangle_bounds(t, viewport);
  const float inv_area2 = 1.0f / float(s.area2);
  for (int i = 0; i < 3; ++i) {
    const ScreenVertex& v = geometry.vertices[t.vertex[i]];
    s.inv_w[i] = v.inv_w;
    s.z_over_area[i] = v.z * inv_area2;
  }
  s.vertex = t.vertex;
  s.material = t.material;
  return s;
}

}  // namespace qdmr
