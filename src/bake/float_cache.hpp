#pragma once
// The on-disk format of the bake caches (cone maps, AO maps): a fixed 40-byte header in host byte order (the cache
// is local) and width x height floats. A file is used only if its size, magic, version, tag, size, key and payload
// checksum all match and every value lies in [lo, hi] (a hit marks the file as used); writing goes through a
// temporary file and a rename, then evicts the least recently used entries past the cache's limit
// (qdmr/bake/bake_cache.hpp). A cache that cannot be written is not an error (it only costs a rebake next time)
// but is reported as a warning (qdmr/core/warning.hpp) naming the entry and the OS reason.
#include <array>
#include <cstdint>
#include <filesystem>
#include <span>

namespace qdmr {

struct FloatCacheId {
  std::array<char, 8> magic;  // what kind of map the file holds
  std::uint32_t version;      // bumped when the definition, rounding or layout changes
  std::uint32_t tag;          // a variant of the map (the cone kind), or 0
  std::int32_t width, height;
  std::uint64_t key;          // content hash of what the map was baked from
};

// Fills `values` (id.width x id.height of them) from the cache; false, `values` unspecified, when it is not usable.
bool read_float_cache(const std::filesystem::path& file, const FloatCacheId& id, float lo, float hi,
                      std::span<float> values);
// Stores `values` at `file`, or warns why it could not (a full or read-only file system). A map larger than the
// cache's whole limit is not kept, silently: that is the limit working.
void write_float_cache(const std::filesystem::path& file, const FloatCacheId& id, std::span<const float> values);

}  // namespace qdmr
