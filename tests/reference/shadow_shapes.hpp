#pragma once
// Analytic height fields for the self-shadowing tests: a step, a pillar and a spherical cap rasterised to
// level-0 texels, with what their closed forms need. Texel units throughout: x = u W, and a depth d in UV
// units is d W.
#include <cmath>
#include <cstddef>
#include <vector>

#include "qdmr/texture/heightfield.hpp"

namespace qdmr::test {

inline HeightField flat_field(int size, double h) {
  return HeightField{size, size, ZeroedBuffer<double>(std::size_t(size) * std::size_t(size), h), AddressMode::Wrap};
}

// Texels x < size / 2 at `low`, the others at `high` (a wall at x = size / 2 and, wrapping, at x = 0).
inline HeightField step_field(int size, double low, double high) {
  HeightField f = flat_field(size, low);
  for (int j = 0; j < size; ++j)
    for (int i = size / 2; i < size; ++i) f.h[std::size_t(j) * std::size_t(size) + std::size_t(i)] = high;
  return f;
}

// One texel (i, i) at `height` on a floor at 0.
inline HeightField pillar_field(int size, int i, double height) {
  HeightField f = flat_field(size, 0.0);
  f.h[std::size_t(i) * std::size_t(size) + std::size_t(i)] = height;
  return f;
}

// A ball of radius `radius` centred `sink` texels below the floor (depth D = depth_scale * size) at the map's
// centre; the part above the floor is the cap. Each texel's height is the ball's top at the texel centre
// (0 outside the cap), so the box surface over the floor lies between the balls of radius
// radius -+ sqrt(2)/2 (a texel's half diagonal) above the floor.
struct Cap {
  int size = 64;
  double depth_scale = 0.25;  // D = 16 texels
  double radius = 20.0, sink = 8.0;  // the cap rises radius - sink = 12 texels: heights up to 0.75

  double floor_depth() const { return depth_scale * size; }
  double centre_depth() const { return floor_depth() + sink; }
  HeightField field() const {
    HeightField f = flat_field(size, 0.0);
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        const double rx = i + 0.5 - size / 2.0, ry = j + 0.5 - size / 2.0, r2 = rx * rx + ry * ry;
        if (r2 >= radius * radius) continue;
        const double top = centre_depth() - std::sqrt(radius * radius - r2);
        if (top < floor_depth()) f.h[std::size_t(j) * std::size_t(size) + std::size_t(i)] = 1.0 - top / floor_depth();
      }
    return f;
  }
  // Whether the open ray from floor point (x0, y0), climbing along (a, b, -1) in texel units, passes through
  // the open ball of radius r.
  bool ray_meets_ball(double x0, double y0, double a, double b, double r) const {
    const double ox = x0 - size / 2.0, oy = y0 - size / 2.0, oz = floor_depth() - centre_depth();
    // |o + t e|^2 = r^2 with e = (a, b, -1): q2 t^2 + 2 q1 t + q0 = 0
    const double q2 = a * a + b * b + 1.0, q1 = ox * a + oy * b - oz, q0 = ox * ox + oy * oy + oz * oz - r * r;
    const double disc = q1 * q1 - q2 * q0;
    if (disc <= 0) return false;
    return (-q1 + std::sqrt(disc)) / q2 > 0;  // the far root ahead: some t > 0 lies inside
  }
};

}  // namespace qdmr::test
