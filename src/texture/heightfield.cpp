#include "qdmr/texture/heightfield.hpp"

#include <algorithm>
#include <cmath>

namespace qdmr {
namespace {

std::int64_t texel_index(std::int64_t i, std::int64_t n, AddressMode mode) {
  switch (mode) {
    case AddressMode::Wrap: {
      if (i >= 0 && i < n) return i;
      const std::int64_t m = i % n;
      return m < 0 ? m + n : m;
    }
    case AddressMode::Clamp: return std::clamp<std::int64_t>(i, 0, n - 1);
    case AddressMode::Mirror: {
      if (i >= 0 && i < n) return i;
      std::int64_t m = i % (2 * n);
      if (m < 0) m += 2 * n;
      return m < n ? m : 2 * n - 1 - m;
    }
  }
  return 0;
}

}  // namespace

double HeightField::at(std::int64_t i, std::int64_t j) const {
  return h[std::size_t(texel_index(j, height, address) * width + texel_index(i, width, address))];
}

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
  const double x = u * field.width - 0.5, y = v * field.height - 0.5;
  const double fi = std::floor(x), fj = std::floor(y);
  const double fx = x - fi, fy = y - fj;
  const auto i = std::int64_t(fi), j = std::int64_t(fj);
  const double h00 = field.at(i, j), h10 = field.at(i + 1, j), h01 = field.at(i, j + 1), h11 = field.at(i + 1, j + 1);
  const double h = h00 + (h10 - h00) * fx + (h01 - h00) * fy + (h00 - h10 - h01 + h11) * fx * fy;
  return depth_scale * (1.0 - h);
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
