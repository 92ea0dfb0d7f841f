#pragma once
// The bake cache's folder as a whole (cone and AO maps, default_cache_dir()): its entries, its size limit and
// least-recently-used eviction, and emptying it (`qdmr cache`, `qdmr cache clear`). Each entry is a
// content-addressed file checked on every read (bake/float_cache.hpp): losing one only costs a rebake.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace qdmr {

struct BakeCacheEntry {
  std::filesystem::path file;
  std::string kind;  // "cone map (relaxed)", "cone map (conservative)", "AO map", "glTF embedded image"
  std::uint64_t bytes = 0;
  std::filesystem::file_time_type last_used;  // the file's modification time: set when written and when read
};

// The default limit, and the variable that overrides it (in MiB; 0 keeps nothing).
inline constexpr std::uint64_t kDefaultBakeCacheMiB = 1024;
inline constexpr const char* kBakeCacheLimitVariable = "QDMR_CACHE_MAX_MIB";

// $QDMR_CACHE_MAX_MIB in bytes, else the default. Throws qdmr::Error naming the variable for a value that is not
// a whole number of MiB from 0 to 2^30.
std::uint64_t bake_cache_limit_bytes();

// qdmr's entries in `folder` (cone-*.bin, ao-*.bin), least recently used first; none when it does not exist.
std::vector<BakeCacheEntry> bake_cache_entries(const std::filesystem::path& folder);

// Removes the least recently used entries until the rest hold at most `limit` bytes; `keep` (the entry just
// written) goes last. Entries another process removes meanwhile are skipped.
void trim_bake_cache(const std::filesystem::path& folder, std::uint64_t limit, const std::filesystem::path& keep = {});

// Removes every entry; returns how many and their bytes. Other files in the folder are left alone. Throws qdmr::Error with the OS reason when an entry cannot be removed.
std::pair<std::size_t, std::uint64_t> clear_bake_cache(const std::filesystem::path& folder);

// Marks `file` as just used (its modification time: atime is not updated on most mounts), ignoring failures.
void touch_bake_cache_entry(const std::filesystem::path& file);

}  // namespace qdmr
