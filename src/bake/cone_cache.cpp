// Cone maps on disk: the content-hash cache of baked maps and the EXR the `qdmr bake cone` command writes.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <string>

#include "qdmr/bake/cone_map.hpp"
#include "bake/content_hash.hpp"
#include "bake/float_cache.hpp"
#include "codec/image_file.hpp"
#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

// Bump when the definition, the rounding or the file layout of a cone map changes: old files stop matching.
constexpr std::uint32_t kConeFormatVersion = 1;
constexpr std::array<char, 8> kConeCacheMagic = {'Q', 'D', 'M', 'R', 'C', 'O', 'N', 'E'};

}  // namespace

std::filesystem::path default_cache_dir() {
  if (const char* dir = std::getenv("QDMR_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "qdmr";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "qdmr";
  return ".qdmr-cache";
}

std::uint64_t cone_map_key(const HeightField& field, ConeKind kind) {
  ContentHash f;
  f.value(kConeFormatVersion);
  f.value(std::int32_t(field.width));
  f.value(std::int32_t(field.height));
  f.value(std::int32_t(field.address));
  f.value(std::int32_t(kind));
  f.bytes(field.h.data(), field.h.size() * sizeof(double));
  return f.digest();
}

ConeMap load_or_bake_cone_map(const HeightField& field, ConeKind kind, const std::filesystem::path& cache_dir) {
  const std::uint64_t key = cone_map_key(field, kind);
  const std::filesystem::path file =
      cache_dir / ("cone-" + std::string(cone_kind_name(kind)) + "-" + hex(key) + ".bin");
  const FloatCacheId id{kConeCacheMagic, kConeFormatVersion, std::uint32_t(kind), field.width, field.height, key};
  if (field.width > 0 && field.height > 0) {
    ConeMap cached;
    cached.width = field.width;
    cached.height = field.height;
    cached.kind = kind;
    cached.ratio = ZeroedBuffer<float>(std::size_t(field.width) * std::size_t(field.height));
    if (read_float_cache(file, id, 0.0f, kMaxConeRatio, cached.ratio)) return cached;
  }
  ConeMap map = bake_cone_map(field, kind);
  write_float_cache(file, id, map.ratio);
  return map;
}

void write_cone_map_exr(const ConeMap& map, const std::filesystem::path& file) {
  // Row 0 (v = 0) is the last row of the file, as read_image expects.
  std::vector<float> rows(map.ratio.size());
  for (int y = 0; y < map.height; ++y)
    std::copy_n(map.ratio.begin() + std::ptrdiff_t(y) * map.width, map.width,
                rows.begin() + std::ptrdiff_t(map.height - 1 - y) * map.width);
  const imageio::WriteSpec spec{map.width, map.height, 1, imageio::PixelType::Float, {"R"}, {}, {}};
  write_image_file(file, spec, rows.data(), "cone map");
}

}  // namespace qdmr
