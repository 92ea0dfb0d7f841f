// Baked ambient occlusion: the per-frame horizon AO per texel in double precision, and its content-hash cache.
#include "qdmr/bake/ao_map.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bake/content_hash.hpp"
#include "bake/float_cache.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "bake/ao_pattern.hpp"

namespace qdmr {
namespace {

// Bump when the definition, the rounding or the file layout of an AO map changes: old files stop matching.
// Version 2: the shared bake-cache header (bake/float_cache.hpp).
constexpr std::uint32_t kAoFormatVersion = 2;
constexpr std::array<char, 8> kMagic = {'Q', 'D', 'M', 'R', 'A', 'O', 'M', 'P'};

AoMapSize map_size(const HeightField& field, const AoDesc& desc) { return ao_map_size(field.width, field.height, desc); }

// The max pyramid of the heights, shaped like the max-quadtree: level k+1 has max(1, floor(n/2)) cells per axis,
// the last one also covering the leftover row/column, so texel x of level 0 lies in cell min(x >> k, n_k - 1).
// Level 0 is the field's own heights (not copied).
struct MaxPyramid {
  std::vector<int> width, height;
  std::vector<const std::vector<double>*> level;
  std::vector<std::vector<double>> parents;  // levels 1..

  explicit MaxPyramid(const HeightField& field) {
    width.push_back(field.width);
    height.push_back(field.height);
    int levels = 1;
    for (int w = field.width, h = field.height; w > 1 || h > 1; w = std::max(1, w / 2), h = std::max(1, h / 2)) ++levels;
    parents.reserve(std::size_t(levels - 1));  // level's pointers stay valid
    level.push_back(&field.h);
    while (width.back() > 1 || height.back() > 1) {
      const int w = width.back(), h = height.back();
      const int pw = std::max(1, w / 2), ph = std::max(1, h / 2);
      std::vector<double> parent(std::size_t(pw) * std::size_t(ph), 0.0);
      const std::vector<double>& child = *level.back();
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          double& p = parent[std::size_t(std::min(y / 2, ph - 1)) * std::size_t(pw) + std::size_t(std::min(x / 2, pw - 1))];
          p = std::max(p, child[std::size_t(y) * std::size_t(w) + std::size_t(x)]);
        }
      width.push_back(pw);
      height.push_back(ph);
      parents.push_back(std::move(parent));
      level.push_back(&parents.back());
    }
  }

  int top() const { return int(level.size()) - 1; }

  double cell_max(int k, std::int64_t x, std::int64_t y) const {
    const std::int64_t cx = std::min<std::int64_t>(x >> k, width[std::size_t(k)] - 1);
    const std::int64_t cy = std::min<std::int64_t>(y >> k, height[std::size_t(k)] - 1);
    return (*level[std::size_t(k)])[std::size_t(cy * width[std::size_t(k)] + cx)];
  }
};

// The coarse taps' horizon slope along (dx, dy): the largest (s - depth_k) / d_k, where tap k reads max pyramid
// level k at d_k = 2^k d_0 (ao::make_taps: exact powers of two times the first distance). Scaling by 2^-k is exact,
// so (s - depth_k) / d_k and ((s - depth_k) 2^-k) / d_0 are the same real number and round alike, and rounding a
// division by d_0 is monotonic: the largest quotient is the quotient of the largest scaled rise. One division per
// direction instead of one per tap, with the same bits. Scaled rises that underflow round by less than 2^-1074, so
// a largest scaled rise of at least 2^-990 still names the largest quotient; below that (never met with heights in
// [0, 1]) the slope is found tap by tap. Returns 0 when no tap rises.
double coarse_slope(const HeightField& field, const MaxPyramid& pyramid, double depth_scale, const ao::Taps& taps,
                    double s, double u, double v, double dx, double dy) {
  const auto rise_at = [&](int k) {
    const ao::Tap& tap = taps.tap[std::size_t(k)];
    const double tu = u + dx * double(tap.distance), tv = v + dy * double(tap.distance);
    // Level-0 texel of the tap under the address mode (HeightField::at's rule; no division inside the map).
    const auto x = HeightField::texel_index(std::int64_t(std::floor(tu * field.width)), field.width, field.address);
    const auto y = HeightField::texel_index(std::int64_t(std::floor(tv * field.height)), field.height, field.address);
    return s - depth_scale * (1.0 - pyramid.cell_max(std::min(tap.level, pyramid.top()), x, y));
  };
  double rise = 0.0, scale = 1.0;  // scale = 2^-k; no branch per tap: a rise's sign is a coin toss on rough ground
  for (int k = 0; k < taps.count; ++k, scale *= 0.5) rise = std::max(rise, rise_at(k) * scale);
  if (rise == 0.0 || rise >= 0x1p-990) return rise / double(taps.tap[0].distance);
  double slope = 0.0;  // the definition, tap by tap
  for (int k = 0; k < taps.count; ++k) slope = std::max(slope, rise_at(k) / double(taps.tap[std::size_t(k)].distance));
  return slope;
}

// The fine taps' horizon slope along (dx, dy): the largest (s - depth) / distance over taps on the bilinear surface.
double fine_slope(const HeightField& field, double depth_scale, const ao::Taps& taps, double s, double u, double v,
                  double dx, double dy) {
  double slope = 0.0;
  for (int k = 0; k < taps.count; ++k) {
    const ao::Tap& tap = taps.tap[std::size_t(k)];
    const double depth =
        bilinear_surface_depth(field, depth_scale, u + dx * double(tap.distance), v + dy * double(tap.distance));
    slope = std::max(slope, (s - depth) / double(tap.distance));
  }
  return slope;
}

// The raw AO of the point above (u, v); pyramid: the max pyramid for coarse taps (null when fine).
double texel_ao(const HeightField& field, const MaxPyramid* pyramid, double depth_scale, const AoDesc& desc,
                const ao::Taps& taps, int i, int j, double u, double v) {
  const int n = ao::direction_count(desc);
  const int rotation = desc.jitter ? ao::rotation(std::uint32_t(i), std::uint32_t(j), desc.seed) : 0;
  const double s = bilinear_surface_depth(field, depth_scale, u, v);
  double visible = 0.0;
  for (int d = 0; d < n; ++d) {
    const int index = ao::direction_index(n, d, rotation);
    const double dx = ao::kDirections.cos[std::size_t(index)], dy = ao::kDirections.sin[std::size_t(index)];
    const double slope = pyramid ? coarse_slope(field, *pyramid, depth_scale, taps, s, u, v, dx, dy)
                                 : fine_slope(field, depth_scale, taps, s, u, v, dx, dy);
    visible += 1.0 - slope / std::sqrt(1.0 + slope * slope);
  }
  return visible / double(n);
}

}  // namespace

AoMapSize ao_map_size(int field_width, int field_height, const AoDesc& desc) {
  if (desc.resolution <= 0) return {field_width, field_height};
  const auto h = std::int64_t(desc.resolution) * field_height / field_width;
  return {desc.resolution, int(std::max<std::int64_t>(1, h))};
}

std::uint64_t ao_bake_bytes(int field_width, int field_height, const AoDesc& desc) {
  const AoMapSize size = ao_map_size(field_width, field_height, desc);
  std::uint64_t bytes = std::uint64_t(size.width) * std::uint64_t(size.height) * sizeof(float);
  if (desc.coarse)
    for (int w = field_width, h = field_height; w > 1 || h > 1;) {
      w = std::max(1, w / 2), h = std::max(1, h / 2);
      bytes += std::uint64_t(w) * std::uint64_t(h) * sizeof(double);
    }
  return bytes;
}

Image bake_ao_map(const HeightField& field, double depth_scale, const AoDesc& desc) {
  if (field.width <= 0 || field.height <= 0 || field.h.size() != std::size_t(field.width) * std::size_t(field.height))
    throw Error("ao map", "empty or inconsistent height field");
  const AoMapSize size = map_size(field, desc);
  const std::optional<MaxPyramid> pyramid = desc.coarse ? std::optional<MaxPyramid>(field) : std::nullopt;
  const ao::Taps taps = ao::make_taps(desc, field.width, field.height);
  Image map(size.width, size.height, 1);
  ProgressStep step("AO map " + std::to_string(size.width) + "x" + std::to_string(size.height), size.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, size.height), [&](const tbb::blocked_range<int>& rows) {
    step.advance();  // stops here when asked to (Ctrl-C)
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < size.width; ++i)
        map.at(i, j, 0) = float(texel_ao(field, pyramid ? &*pyramid : nullptr, depth_scale, desc, taps, i, j, (i + 0.5) / size.width,
                                         (j + 0.5) / size.height));
    step.advance(rows.size());
  });
  return map;
}

std::uint64_t ao_map_key(const HeightField& field, double depth_scale, const AoDesc& desc) {
  const AoMapSize size = map_size(field, desc);
  ContentHash f;
  f.value(kAoFormatVersion);
  f.value(std::int32_t(field.width));
  f.value(std::int32_t(field.height));
  f.value(std::int32_t(field.address));
  f.bytes(field.h.data(), field.h.size() * sizeof(double));
  f.value(depth_scale);
  f.value(std::int32_t(ao::direction_count(desc)));
  f.value(desc.radius);
  f.value(std::uint8_t(desc.coarse));
  f.value(std::uint8_t(desc.jitter));
  f.value(desc.jitter ? desc.seed : 0u);
  f.value(std::int32_t(size.width));
  f.value(std::int32_t(size.height));
  return f.digest();
}

Image load_or_bake_ao_map(const HeightField& field, double depth_scale, const AoDesc& desc,
                          const std::filesystem::path& cache_dir) {
  if (field.width <= 0 || field.height <= 0) return bake_ao_map(field, depth_scale, desc);  // throws
  const std::uint64_t key = ao_map_key(field, depth_scale, desc);
  const std::filesystem::path file = cache_dir / ("ao-" + hex(key) + ".bin");
  const AoMapSize size = map_size(field, desc);
  const FloatCacheId id{kMagic, kAoFormatVersion, 0, size.width, size.height, key};
  if (Image cached(size.width, size.height, 1); read_float_cache(file, id, 0.0f, 1.0f, cached.texels)) return cached;
  Image map = bake_ao_map(field, depth_scale, desc);
  write_float_cache(file, id, map.texels);
  return map;
}

}  // namespace qdmr
