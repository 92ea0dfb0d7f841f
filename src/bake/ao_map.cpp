// Baked ambient occlusion: the per-frame horizon AO per texel in double precision, and its content-hash cache.
#include "bake/ao_map.hpp"

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
#include "qdmr/core/zeroed_buffer.hpp"
#include "bake/ao_texel.hpp"

namespace qdmr {
namespace {

// Bump when the definition, the rounding or the file layout of an AO map changes: old files stop matching.
// Version 2: the shared bake-cache header (bake/float_cache.hpp).
constexpr std::uint32_t kAoFormatVersion = 2;
constexpr std::array<char, 8> kAoCacheMagic = {'Q', 'D', 'M', 'R', 'A', 'O', 'M', 'P'};

template <class T>
AoMapSize map_size(const HeightView<T>& field, const AoDesc& desc) { return ao_map_size(field.width, field.height, desc); }

}  // namespace

template <class T>
ao::MaxPyramid<T>::MaxPyramid(const HeightView<T>& field) {
  width.push_back(field.width);
  height.push_back(field.height);
  int levels = 1;
  for (int w = field.width, h = field.height; w > 1 || h > 1; w = std::max(1, w / 2), h = std::max(1, h / 2)) ++levels;
  parents.reserve(std::size_t(levels - 1));  // level's pointers stay valid
  level.push_back(field.h);
  while (width.back() > 1 || height.back() > 1) {
    const int w = width.back(), h = height.back();
    const int pw = std::max(1, w / 2), ph = std::max(1, h / 2);
    // Zero pages, first touched by the rows' own threads, each cell written once and never read first: a read
    // maps the shared zero page, and the write after it then copies the page and flushes the TLB of every thread
    // (an interrupt to the other cores per 4 KiB page). A cell's maximum starts at 0, below every height.
    ZeroedBuffer<T> parent(std::size_t(pw) * std::size_t(ph));
    const T* child = level.back();
    tbb::parallel_for(tbb::blocked_range<int>(0, ph), [&](const tbb::blocked_range<int>& rows) {
      for (int py = rows.begin(); py < rows.end(); ++py) {
        T* out = parent.data() + std::size_t(py) * std::size_t(pw);
        const int y_end = py == ph - 1 ? h : std::min(h, 2 * py + 2);  // the last row and column take the leftover
        for (int px = 0; px < pw; ++px) {
          const int x_end = px == pw - 1 ? w : std::min(w, 2 * px + 2);
          T m = T(0);
          for (int y = 2 * py; y < y_end; ++y) {
            const T* in = child + std::size_t(y) * std::size_t(w);
            for (int x = 2 * px; x < x_end; ++x) m = std::max(m, in[x]);
          }
          out[px] = m;
        }
      }
    });
    width.push_back(pw);
    height.push_back(ph);
    parents.push_back(std::move(parent));
    level.push_back(parents.back().data());
  }
}

template <class T>
ao::UniformColumns::UniformColumns(const Bake<T>& b) : taps(b.taps.count) {
  const HeightView<T>& f = b.field;
  const MaxPyramid<T>& p = *b.pyramid;
  const int n = direction_count(b.pattern), w = b.map_width;
  cell.resize(std::size_t(n) * std::size_t(taps) * std::size_t(w));
  left.resize(std::size_t(w));
  right.resize(std::size_t(w));
  fraction.resize(std::size_t(w));
  tbb::parallel_for(0, n, [&](int d) {
    const double dx = kDirections.cos[std::size_t(direction_index(n, d, 0))];
    for (int k = 0; k < taps; ++k) {
      const Tap& tap = b.taps.tap[std::size_t(k)];
      const int level = std::min(tap.level, p.top());
      std::int32_t* out = cell.data() + (std::size_t(d) * std::size_t(taps) + std::size_t(k)) * std::size_t(w);
      for (int i = 0; i < w; ++i)
        out[i] = std::int32_t(p.cell_x(level, tap_texel(texel_u(b, i) + dx * double(tap.distance), f.width, f.address)));
    }
  });
  for (int i = 0; i < w; ++i) {  // bilinear_surface_depth's columns
    const double x = texel_u(b, i) * f.width - 0.5, fi = std::floor(x);
    const auto c = std::int64_t(fi);
    left[std::size_t(i)] = std::int32_t(HeightField::texel_index(c, f.width, f.address));
    right[std::size_t(i)] = std::int32_t(HeightField::texel_index(c + 1, f.width, f.address));
    fraction[std::size_t(i)] = x - fi;
  }
}

std::uint64_t ao::UniformColumns::bytes(int map_width, int directions, int taps) {
  return std::uint64_t(map_width) * (std::uint64_t(directions) * std::uint64_t(taps) * 4 + 4 + 4 + 8);
}

AoMapSize ao_map_size(int field_width, int field_height, const AoDesc& desc) {
  if (desc.resolution <= 0) return {field_width, field_height};
  const auto h = std::int64_t(desc.resolution) * field_height / field_width;
  return {desc.resolution, int(std::max<std::int64_t>(1, h))};
}

std::uint64_t ao_bake_bytes(int field_width, int field_height, const AoDesc& desc, int height_bytes) {
  const AoMapSize size = ao_map_size(field_width, field_height, desc);
  std::uint64_t bytes = std::uint64_t(size.width) * std::uint64_t(size.height) * sizeof(float);
  if (desc.coarse) {
    for (int w = field_width, h = field_height; w > 1 || h > 1;) {
      w = std::max(1, w / 2), h = std::max(1, h / 2);
      bytes += std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(height_bytes);
    }
    if (!desc.jitter)
      bytes += ao::UniformColumns::bytes(size.width, ao::direction_count(pattern_of(desc)),
                                        ao::make_taps(pattern_of(desc), field_width, field_height).count);
  }
  return bytes;
}

template <class T>
Image bake_ao_map(const HeightView<T>& field, double depth_scale, const AoDesc& desc, AoMapRow row) {
  if (field.width <= 0 || field.height <= 0) throw Error("ao map", "empty or inconsistent height field");
  const AoMapSize size = map_size(field, desc);
  Image map(size.width, size.height, 1);
  bake_ao_rows(field, depth_scale, desc, map, 0, 1, row);
  return map;
}

template <class T>
void bake_ao_rows(const HeightView<T>& field, double depth_scale, const AoDesc& desc, Image& map, int first, int step,
                  AoMapRow row_of) {
  if (field.width <= 0 || field.height <= 0 || !field.h) throw Error("ao map", "empty or inconsistent height field");
  const AoRowOf<T> row = row_of.template of<T>();
  const AoMapSize size = map_size(field, desc);
  if (map.width != size.width || map.height != size.height || map.channels != 1 || step < 1 || first < 0)
    throw Error("ao map", "bake_ao_rows: the map or the rows do not fit the bake");
  const std::optional<ao::MaxPyramid<T>> pyramid =
      desc.coarse ? std::optional<ao::MaxPyramid<T>>(field) : std::nullopt;
  ao::Bake<T> bake{field, pyramid ? &*pyramid : nullptr, depth_scale, pattern_of(desc),
                ao::make_taps(pattern_of(desc), field.width, field.height),
                size.width, size.height};
  // The kernels' rows of a coarse bake without jitter read the columns every row shares.
  const std::optional<ao::UniformColumns> columns =
      row && pyramid && !desc.jitter ? std::optional<ao::UniformColumns>(bake) : std::nullopt;
  if (columns) bake.columns = &*columns;
  const int count = first < size.height ? (size.height - first + step - 1) / step : 0;
  ProgressStep progress("AO map " + std::to_string(size.width) + "x" + std::to_string(size.height), count);
  tbb::parallel_for(tbb::blocked_range<int>(0, count), [&](const tbb::blocked_range<int>& rows) {
    progress.advance();  // stops here when asked to (Ctrl-C)
    for (int r = rows.begin(); r < rows.end(); ++r) {
      const int j = first + r * step;
      float* out = &map.texels[std::size_t(j) * std::size_t(size.width)];
      if (row) {
        row(bake, j, out);
      } else {
        for (int i = 0; i < size.width; ++i) out[i] = float(ao::texel_ao(bake, i, j));
      }
    }
    progress.advance(rows.size());
  });
}

template <class T>
std::uint64_t ao_map_key(const HeightView<T>& field, double depth_scale, const AoDesc& desc) {
  const AoMapSize size = map_size(field, desc);
  ContentHash f;
  f.value(kAoFormatVersion);
  f.value(std::int32_t(field.width));
  f.value(std::int32_t(field.height));
  f.value(std::int32_t(field.address));
  const std::size_t count = std::size_t(field.width) * std::size_t(field.height);
  if constexpr (std::is_same_v<T, double>) {
    f.bytes(field.h, count * sizeof(double));
  } else {  // the doubles they convert to, a block at a time
    std::array<double, 4096> block;
    for (std::size_t i = 0; i < count; i += block.size()) {
      const std::size_t n = std::min(block.size(), count - i);
      std::copy_n(field.h + i, n, block.begin());
      f.bytes(block.data(), n * sizeof(double));
    }
  }
  f.value(depth_scale);
  f.value(std::int32_t(ao::direction_count(pattern_of(desc))));
  f.value(desc.radius);
  f.value(std::uint8_t(desc.coarse));
  f.value(std::uint8_t(desc.jitter));
  f.value(desc.jitter ? desc.seed : 0u);
  f.value(std::int32_t(size.width));
  f.value(std::int32_t(size.height));
  return f.digest();
}

template <class T>
Image load_or_bake_ao_map(const HeightView<T>& field, double depth_scale, const AoDesc& desc,
                          const std::filesystem::path& cache_dir, AoMapRow row) {
  if (field.width <= 0 || field.height <= 0) return bake_ao_map(field, depth_scale, desc, row);  // throws
  const std::uint64_t key = ao_map_key(field, depth_scale, desc);
  const std::filesystem::path file = cache_dir / ("ao-" + hex(key) + ".bin");
  const AoMapSize size = map_size(field, desc);
  const FloatCacheId id{kAoCacheMagic, kAoFormatVersion, 0, size.width, size.height, key};
  if (Image cached(size.width, size.height, 1); read_float_cache(file, id, 0.0f, 1.0f, cached.texels)) return cached;
  Image map = bake_ao_map(field, depth_scale, desc, row);
  write_float_cache(file, id, map.texels);
  return map;
}

#define QDMR_AO_BAKE(T)                                                                                            \
  template struct ao::MaxPyramid<T>;                                                                              \
  template ao::UniformColumns::UniformColumns(const ao::Bake<T>&);                                                \
  template Image bake_ao_map(const HeightView<T>&, double, const AoDesc&, AoMapRow);                              \
  template void bake_ao_rows(const HeightView<T>&, double, const AoDesc&, Image&, int, int, AoMapRow);            \
  template std::uint64_t ao_map_key(const HeightView<T>&, double, const AoDesc&);                                \
  template Image load_or_bake_ao_map(const HeightView<T>&, double, const AoDesc&, const std::filesystem::path&,  \
                                     AoMapRow);
QDMR_AO_BAKE(double)
QDMR_AO_BAKE(float)
#undef QDMR_AO_BAKE

}  // namespace qdmr
