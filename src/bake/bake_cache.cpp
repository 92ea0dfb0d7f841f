#include "qdmr/bake/bake_cache.hpp"

#include <fcntl.h>
#include <sys/stat.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cstring>

#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

// What an entry's name says it holds ("cone-relaxed-<16 hex>.bin", "ao-<16 hex>.bin", "gltf-image-<40 hex>.png"),
// or "" for other files.
std::string entry_kind(const std::string& name) {
  const auto hex_bin = [&](std::size_t from) {
    return name.size() == from + 20 && name.compare(from + 16, 4, ".bin") == 0 &&
           name.find_first_not_of("0123456789abcdef", from) == from + 16;
  };
  if (name.starts_with("cone-relaxed-") && hex_bin(13)) return "cone map (relaxed)";
  if (name.starts_with("cone-conservative-") && hex_bin(18)) return "cone map (conservative)";
  if (name.starts_with("ao-") && hex_bin(3)) return "AO map";
  // An image embedded in a glTF asset, stored under its SHA-1 to be read by qdmr's image readers (mesh/gltf.cpp).
  if (name.starts_with("gltf-image-") && name.size() == 11 + 40 + 4 &&
      (name.ends_with(".png") || name.ends_with(".jpg")) && name.find_first_not_of("0123456789abcdef", 11) == 51)
    return "glTF embedded image";
  return "";
}

}  // namespace

std::uint64_t bake_cache_limit_bytes() {
  const char* text = std::getenv(kBakeCacheLimitVariable);
  if (!text || !*text) return kDefaultBakeCacheMiB << 20;
  std::uint64_t mib = 0;
  const char* end = text + std::strlen(text);
  const auto [ptr, ec] = std::from_chars(text, end, mib);
  if (ec != std::errc() || ptr != end || mib > (std::uint64_t(1) << 30))
    throw Error(std::string("$") + kBakeCacheLimitVariable,
                "must be a whole number of MiB from 0 to 1073741824, got '" + std::string(text) + "'");
  return mib << 20;
}

std::vector<BakeCacheEntry> bake_cache_entries(const std::filesystem::path& folder) {
  std::vector<BakeCacheEntry> entries;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string kind = entry_kind(it->path().filename().string());
    std::error_code entry_error;
    if (kind.empty() || !it->is_regular_file(entry_error)) continue;
    BakeCacheEntry e{it->path(), kind, it->file_size(entry_error), it->last_write_time(entry_error)};
    if (!entry_error) entries.push_back(std::move(e));
  }
  std::sort(entries.begin(), entries.end(), [](const BakeCacheEntry& a, const BakeCacheEntry& b) {
    return a.last_used != b.last_used ? a.last_used < b.last_used : a.file < b.file;
  });
  return entries;
}

void trim_bake_cache(const std::filesystem::path& folder, std::uint64_t limit, const std::filesystem::path& keep) {
  std::vector<BakeCacheEntry> entries = bake_cache_entries(folder);
  std::stable_partition(entries.begin(), entries.end(), [&](const BakeCacheEntry& e) { return e.file != keep; });
  std::uint64_t total = 0;
  for (const BakeCacheEntry& e : entries) total += e.bytes;
  for (const BakeCacheEntry& e : entries) {
    if (total <= limit) break;
    std::error_code ec;
    std::filesystem::remove(e.file, ec);  // gone already (another process trimmed it): fine too
    total -= e.bytes;
  }
}

std::pair<std::size_t, std::uint64_t> clear_bake_cache(const std::filesystem::path& folder) {
  std::pair<std::size_t, std::uint64_t> removed{0, 0};
  for (const BakeCacheEntry& e : bake_cache_entries(folder)) {
    std::error_code ec;
    if (!std::filesystem::remove(e.file, ec) && ec) throw Error(e.file.string(), "cannot remove: " + ec.message());
    removed.first += 1;
    removed.second += e.bytes;
  }
  return removed;
}

void touch_bake_cache_entry(const std::filesystem::path& file) {
  ::utimensat(AT_FDCWD, file.c_str(), nullptr, 0);  // both times to now
}

}  // namespace qdmr
