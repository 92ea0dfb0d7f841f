#include "qdmr/texture/heightfield.hpp"

#include <algorithm>
#include <cmath>

namespace qdmr {

double surface_depth(const HeightField& field, double depth_scale, double u, double v, ReferenceSurface surface) {
  if (surface == ReferenceSurface::Box) {
    // The texel holding (u, v), and on an edge or corner also the texels before it: the highest one counts.
    const double x = u * field.width, y = v * field.height;
    const double fx = std::floor(x), fy = std::floor(y);
    const auto i = std::int64_t(fx), j = std::int64_t(fy);
    double top = field.at(i, j);
    if (x == fx) top = std::max(top, field.at(i - 1, j));
    if (y == fy) top = std::max(top, field.at(i, j - 1));
    if (x == fx && y == fy) top = std::max(top, field.at(i - 1, j - 1));
    return depth_scale * (1.0 - top);
  }
  return bilinear_surface_depth(field, depth_scale, u, v);
}

Image bilinear_upper_bound(const HeightField& field) {
  Image bound(field.width, field.height, 1);
  for (int y = 0; y < field.height; ++y)
    for (int x = 0; x < field.width; ++x) {
      double m = 0.0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) m = std::max(m, field.at(x + dx, y + dy));
      float f = float(m);
      if (double(f) < m) f = std::nextafter(f, 2.0f);  // never below the bound
      bound.at(x, y, 0) = f;
    }
  return bound;
}

}  // namespace qdmr
