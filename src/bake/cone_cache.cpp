// Cone maps on disk: the content-hash cache of baked maps and the EXR the `qdmr bake cone` command writes.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>

#include "qdmr/bake/cone_map.hpp"
#include "bake/content_hash.hpp"
#include "io/atomic_file.hpp"
#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

// Bump when the definition, the rounding or the file layout of a cone map changes: old files stop matching.
constexpr std::uint32_t kConeFormatVersion = 1;
constexpr char kMagic[8] = {'Q', 'D', 'M', 'R', 'C', 'O', 'N', 'E'};

// The fixed-size header in front of the float ratios of a cache file (host byte order: the cache is local).
struct CacheHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t kind;
  std::int32_t width, height;
  std::uint64_t key;
  std::uint64_t payload_hash;  // FNV-1a of the ratios' bytes
};

std::uint64_t payload_hash(const std::vector<float>& ratio) {
  Fnv1a f;
  f.bytes(ratio.data(), ratio.size() * sizeof(float));
  return f.hash;
}

// The cached map, or nothing when the file is missing, foreign, truncated or corrupt.
std::optional<ConeMap> read_cache(const std::filesystem::path& file, std::uint64_t key, const HeightField& field,
                                  ConeKind kind) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  const std::size_t count = std::size_t(field.width) * std::size_t(field.height);
  std::error_code ec;
  if (std::filesystem::file_size(file, ec) != sizeof(CacheHeader) + count * sizeof(float) || ec) return std::nullopt;
  CacheHeader header{};
  if (!in.read(reinterpret_cast<char*>(&header), sizeof header)) return std::nullopt;
  if (std::memcmp(header.magic, kMagic, sizeof kMagic) != 0 || header.version != kConeFormatVersion ||
      header.kind != std::uint32_t(kind) || header.width != field.width || header.height != field.height ||
      header.key != key)
    return std::nullopt;
  ConeMap map;
  map.width = field.width;
  map.height = field.height;
  map.kind = kind;
  map.ratio.resize(count);
  if (!in.read(reinterpret_cast<char*>(map.ratio.data()), std::streamsize(count * sizeof(float)))) return std::nullopt;
  if (payload_hash(map.ratio) != header.payload_hash) return std::nullopt;
  for (float r : map.ratio)
    if (!(r >= 0.0f && r <= kMaxConeRatio)) return std::nullopt;
  return map;
}

void write_cache(const std::filesystem::path& file, std::uint64_t key, const ConeMap& map) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return;
  CacheHeader header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.version = kConeFormatVersion;
  header.kind = std::uint32_t(map.kind);
  header.width = map.width;
  header.height = map.height;
  header.key = key;
  header.payload_hash = payload_hash(map.ratio);
  try {  // the cache is best effort: an unwritable folder only costs a rebake next time
    write_atomically(file, "cone map cache", [&](const std::filesystem::path& temporary) -> std::string {
      std::ofstream out(temporary, std::ios::binary);
      out.write(reinterpret_cast<const char*>(&header), sizeof header);
      out.write(reinterpret_cast<const char*>(map.ratio.data()), std::streamsize(map.ratio.size() * sizeof(float)));
      return out.flush() ? "" : "write failed";
    });
  } catch (const Error&) {
  }
}

}  // namespace

std::filesystem::path default_cache_dir() {
  if (const char* dir = std::getenv("QDMR_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "qdmr";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "qdmr";
  return ".qdmr-cache";
}

std::uint64_t cone_map_key(const HeightField& field, ConeKind kind) {
  Fnv1a f;
  f.value(kConeFormatVersion);
  f.value(std::int32_t(field.width));
  f.value(std::int32_t(field.height));
  f.value(std::int32_t(field.address));
  f.value(std::int32_t(kind));
  for (double h : field.h) f.value(h);
  return f.hash;
}

ConeMap load_or_bake_cone_map(const HeightField& field, ConeKind kind, const std::filesystem::path& cache_dir) {
  const std::uint64_t key = cone_map_key(field, kind);
  const std::filesystem::path file =
      cache_dir / ("cone-" + std::string(cone_kind_name(kind)) + "-" + hex(key) + ".bin");
  if (field.width > 0 && field.height > 0)
    if (std::optional<ConeMap> cached = read_cache(file, key, field, kind)) return std::move(*cached);
  ConeMap map = bake_cone_map(field, kind);
  write_cache(file, key, map);
  return map;
}

void write_cone_map_exr(const ConeMap& map, const std::filesystem::path& file) {
  // Row 0 (v = 0) is the last row of the file, as read_image expects.
  std::vector<float> rows(map.ratio.size());
  for (int y = 0; y < map.height; ++y)
    std::copy_n(map.ratio.begin() + std::ptrdiff_t(y) * map.width, map.width,
                rows.begin() + std::ptrdiff_t(map.height - 1 - y) * map.width);
  OIIO::ImageSpec spec(map.width, map.height, 1, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"R"};
  write_image_file(file, spec, OIIO::TypeDesc::FLOAT, rows.data(), "cone map");
}

}  // namespace qdmr
