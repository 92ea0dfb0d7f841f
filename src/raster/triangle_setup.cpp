#include "raster/triangle_setup.hpp"

#include <algorithm>

#include "qdmr/core/limits.hpp"

namespace qdmr {
namespace {

static_assert(limits::kSubpixelScale == 256, "pixel_centre_fixed assumes 8 sub-pixel bits");

// Smallest pixel whose centre is >= v, largest whose centre is <= v (v in fixed point).
int first_pixel_at_or_after(std::int64_t v) {
  const std::int64_t s = v - limits::kSubpixelScale / 2;
  return int(s >= 0 ? (s + limits::kSubpixelScale - 1) / limits::kSubpixelScale : -((-s) / limits::kSubpixelScale));
}
int last_pixel_at_or_before(std::int64_t v) {
  const std::int64_t s = v - limits::kSubpixelScale / 2;
  return int(s >= 0 ? s / limits::kSubpixelScale : -((-s + limits::kSubpixelScale - 1) / limits::kSubpixelScale));
}

}  // namespace

PixelRect triangle_bounds(const ScreenTriangle& t, const Viewport& viewport) {
  const int min_x = std::min({t.x[0], t.x[1], t.x[2]}), max_x = std::max({t.x[0], t.x[1], t.x[2]});
  const int min_y = std::min({t.y[0], t.y[1], t.y[2]}), max_y = std::max({t.y[0], t.y[1], t.y[2]});
  PixelRect r;
  r.x0 = std::max(0, first_pixel_at_or_after(min_x));
  r.y0 = std::max(0, first_pixel_at_or_after(min_y));
  r.x1 = std::min(viewport.width - 1, last_pixel_at_or_before(max_x));
  r.y1 = std::min(viewport.height - 1, last_pixel_at_or_before(max_y));
  return r;
}

TriangleSetup setup_triangle(const ScreenTriangle& t, const GeometryResult& geometry, const Viewport& viewport) {
  TriangleSetup s;
  std::int64_t area2 = 0;
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
  area2 = s.edge(0, t.x[0], t.y[0]);
  s.area2 = area2;
  s.bounds = triangle_bounds(t, viewport);
  const float inv_area2 = 1.0f / float(area2);
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
