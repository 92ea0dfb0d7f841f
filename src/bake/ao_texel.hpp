#pragma once
// One texel of a baked AO map (bake/ao_map.hpp's definition), scalar and in double: the baseline bake and the
// per-ISA bakes (kernel/ao_rows.cpp) share it, the latter for lanes their vectors do not cover. Inline: compiled
// with each ISA's flags it rounds alike everywhere (only IEEE operations, -ffp-contract=off). Templates on the
// stored height type: double (a HeightField) or float (a blend's box values, texture/blend_box_values.hpp, read as
// the doubles they convert to exactly: the same bits as their fp64 copy, without making it).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "bake/ao_pattern.hpp"
#include "qdmr/core/zeroed_buffer.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "texture/height_view.hpp"

namespace qdmr::ao {

// The max pyramid of the heights, shaped like the max-quadtree: level k+1 has max(1, floor(n/2)) cells per axis,
// the last one also covering the leftover row/column, so texel x of level 0 lies in cell min(x >> k, n_k - 1).
// Level 0 is the field's own heights (not copied); the levels above hold T too (a maximum is one of its inputs).
template <class T>
struct MaxPyramid {
  std::vector<int> width, height;
  std::vector<const T*> level;
  std::vector<ZeroedBuffer<T>> parents;  // levels 1..

  explicit MaxPyramid(const HeightView<T>& field);

  int top() const { return int(level.size()) - 1; }

  // The level-k cell column of level-0 column x, and row of row y.
  std::int64_t cell_x(int k, std::int64_t x) const { return std::min<std::int64_t>(x >> k, width[std::size_t(k)] - 1); }
  std::int64_t cell_y(int k, std::int64_t y) const { return std::min<std::int64_t>(y >> k, height[std::size_t(k)] - 1); }

  double cell_max(int k, std::int64_t x, std::int64_t y) const {
    return double(level[std::size_t(k)][std::size_t(cell_y(k, y) * width[std::size_t(k)] + cell_x(k, x))]);
  }
};

struct UniformColumns;

// The level-0 texel a tap at coordinate t (UV) reads along an axis of n texels, under the address mode
// (HeightField::at's rule; no division inside the map).
inline std::int64_t tap_texel(double t, int n, AddressMode address) {
  return HeightField::texel_index(std::int64_t(std::floor(t * n)), n, address);
}

// Everything one texel of a bake reads. pyramid is null for fine taps.
template <class T>
struct Bake {
  HeightView<T> field;
  const MaxPyramid<T>* pyramid;
  double depth_scale;
  Pattern pattern;
  Taps taps;
  int map_width, map_height;
  const UniformColumns* columns = nullptr;  // coarse without jitter: what every row shares (for the kernels' rows)
};

// Without jitter, every row of a coarse bake looks along the same directions from the same columns: tap k of
// direction d at texel i reads the same pyramid column in every row, and texel i's bilinear footprint has the same
// two columns and fraction. Found once per bake by the definition's own operations; the kernels' rows then read
// them instead of finding them per texel, with the same bits.
struct UniformColumns {
  int taps = 0;                          // per direction (Bake::taps.count)
  std::vector<std::int32_t> cell;        // [(d * taps + k) * map_width + i]: the tap's cell column, level min(k, top)
  std::vector<std::int32_t> left, right; // texel i's bilinear footprint: its level-0 columns (address applied)
  std::vector<double> fraction;          // and the fraction between them

  template <class T>
  explicit UniformColumns(const Bake<T>& b);
  // What they hold for a map `map_width` wide with `directions` x `taps` taps.
  static std::uint64_t bytes(int map_width, int directions, int taps);
};

// The coarse taps' horizon slope along (dx, dy): the largest (s - depth_k) / d_k, where tap k reads max pyramid
// level k at d_k = 2^k d_0 (make_taps: exact powers of two times the first distance). Scaling by 2^-k is exact,
// so (s - depth_k) / d_k and ((s - depth_k) 2^-k) / d_0 are the same real number and round alike, and rounding a
// division by d_0 is monotonic: the largest quotient is the quotient of the largest scaled rise. One division per
// direction instead of one per tap, with the same bits. Scaled rises that underflow round by less than 2^-1074, so
// a largest scaled rise of at least 2^-990 still names the largest quotient; below that (never met with heights in
// [0, 1]) the slope is found tap by tap. Returns 0 when no tap rises.
inline constexpr double kSmallestScaledRise = 0x1p-990;

template <class T>
double coarse_tap_rise(const Bake<T>& b, int k, double s, double u, double v, double dx, double dy) {
  const HeightView<T>& field = b.field;
  const Tap& tap = b.taps.tap[std::size_t(k)];
  const double tu = u + dx * double(tap.distance), tv = v + dy * double(tap.distance);
  const std::int64_t x = tap_texel(tu, field.width, field.address), y = tap_texel(tv, field.height, field.address);
  return s - b.depth_scale * (1.0 - b.pyramid->cell_max(std::min(tap.level, b.pyramid->top()), x, y));
}

// The slope tap by tap, for a largest scaled rise below kSmallestScaledRise.
template <class T>
double coarse_slope_by_tap(const Bake<T>& b, double s, double u, double v, double dx, double dy) {
  double slope = 0.0;
  for (int k = 0; k < b.taps.count; ++k)
    slope = std::max(slope, coarse_tap_rise(b, k, s, u, v, dx, dy) / double(b.taps.tap[std::size_t(k)].distance));
  return slope;
}

template <class T>
double coarse_slope(const Bake<T>& b, double s, double u, double v, double dx, double dy) {
  double rise = 0.0, scale = 1.0;  // scale = 2^-k; no branch per tap: a rise's sign is a coin toss on rough ground
  for (int k = 0; k < b.taps.count; ++k, scale *= 0.5) rise = std::max(rise, coarse_tap_rise(b, k, s, u, v, dx, dy) * scale);
  if (rise == 0.0 || rise >= kSmallestScaledRise) return rise / double(b.taps.tap[0].distance);
  return coarse_slope_by_tap(b, s, u, v, dx, dy);
}

// The fine taps' horizon slope along (dx, dy): the largest (s - depth) / distance over taps on the bilinear surface.
template <class T>
double fine_slope(const Bake<T>& b, double s, double u, double v, double dx, double dy) {
  double slope = 0.0;
  for (int k = 0; k < b.taps.count; ++k) {
    const Tap& tap = b.taps.tap[std::size_t(k)];
    const double depth =
        bilinear_surface_depth(b.field, b.depth_scale, u + dx * double(tap.distance), v + dy * double(tap.distance));
    slope = std::max(slope, (s - depth) / double(tap.distance));
  }
  return slope;
}

// The map's UV of texel (i, j).
template <class T>
double texel_u(const Bake<T>& b, int i) { return (i + 0.5) / b.map_width; }
template <class T>
double texel_v(const Bake<T>& b, int j) { return (j + 0.5) / b.map_height; }

// The raw AO of texel (i, j) of the map.
template <class T>
double texel_ao(const Bake<T>& b, int i, int j) {
  const int n = direction_count(b.pattern);
  const int r = b.pattern.jitter ? rotation(std::uint32_t(i), std::uint32_t(j), b.pattern.seed) : 0;
  const double u = texel_u(b, i), v = texel_v(b, j);
  const double s = bilinear_surface_depth(b.field, b.depth_scale, u, v);
  double visible = 0.0;
  for (int d = 0; d < n; ++d) {
    const int index = direction_index(n, d, r);
    const double dx = kDirections.cos[std::size_t(index)], dy = kDirections.sin[std::size_t(index)];
    const double slope = b.pyramid ? coarse_slope(b, s, u, v, dx, dy) : fine_slope(b, s, u, v, dx, dy);
    visible += 1.0 - slope / std::sqrt(1.0 + slope * slope);
  }
  return visible / double(n);
}

}  // namespace qdmr::ao
