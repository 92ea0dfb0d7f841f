// The bake cache as a whole (qdmr/bake/bake_cache.hpp): its entries, least-recently-used eviction under the
// limit, reads marking entries as used, clearing, and the limit's variable.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "qdmr/bake/bake_cache.hpp"
#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/error.hpp"
#include "support/test_support.hpp"

namespace qdmr {
namespace {

namespace fs = std::filesystem;

// An entry of `bytes` bytes last used `age` seconds ago (before a fixed point, so ages order exactly).
fs::path entry(const fs::path& folder, const std::string& name, std::size_t bytes, int age) {
  test::write_file(folder / name, std::string(bytes, 'x'));
  fs::last_write_time(folder / name, fs::file_time_type::clock::now() - std::chrono::seconds(1000 + age));
  return folder / name;
}

TEST(BakeCache, EvictsTheLeastRecentlyUsedEntriesPastTheLimit) {
  test::TempDir dir;
  const std::string key = "0123456789abcdef";
  entry(dir.path(), "cone-relaxed-" + key + ".bin", 300, 40);
  entry(dir.path(), "ao-" + key + ".bin", 300, 30);
  entry(dir.path(), "cone-conservative-" + key + ".bin", 300, 20);
  const fs::path newest = entry(dir.path(), "ao-fedcba9876543210.bin", 300, 50);  // oldest time, but just written
  entry(dir.path(), "notes.txt", 5000, 60);  // not an entry: never counted, never removed
  entry(dir.path(), "cone-relaxed-xyz.bin", 5000, 60);
  ASSERT_EQ(bake_cache_entries(dir.path()).size(), 4u);
  EXPECT_EQ(bake_cache_entries(dir.path()).front().kind, "AO map");  // least recently used first

  trim_bake_cache(dir.path(), 650, newest);  // room for two of the four: the newest and the most recently used
  EXPECT_TRUE(fs::exists(newest));
  EXPECT_TRUE(fs::exists(dir / ("cone-conservative-" + key + ".bin")));
  EXPECT_FALSE(fs::exists(dir / ("ao-" + key + ".bin")));
  EXPECT_FALSE(fs::exists(dir / ("cone-relaxed-" + key + ".bin")));
  EXPECT_TRUE(fs::exists(dir / "notes.txt") && fs::exists(dir / "cone-relaxed-xyz.bin"));

  // A read marks an entry as used: it then outlives the other.
  touch_bake_cache_entry(newest);
  trim_bake_cache(dir.path(), 300);
  EXPECT_TRUE(fs::exists(newest));
  EXPECT_EQ(bake_cache_entries(dir.path()).size(), 1u);

  const auto [count, bytes] = clear_bake_cache(dir.path());
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(bytes, 300u);
  EXPECT_TRUE(bake_cache_entries(dir.path()).empty());
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_TRUE(bake_cache_entries(dir / "missing").empty());
}

TEST(BakeCache, TheLimitComesFromItsVariable) {
  const char* saved = std::getenv(kBakeCacheLimitVariable);
  const std::string old = saved ? saved : "";
  ::unsetenv(kBakeCacheLimitVariable);
  EXPECT_EQ(bake_cache_limit_bytes(), kDefaultBakeCacheMiB << 20);
  ::setenv(kBakeCacheLimitVariable, "3", 1);
  EXPECT_EQ(bake_cache_limit_bytes(), std::uint64_t(3) << 20);
  for (const char* bad : {"-1", "1.5", "lots", "1073741825"}) {
    ::setenv(kBakeCacheLimitVariable, bad, 1);
    EXPECT_THROW(bake_cache_limit_bytes(), Error) << bad;
  }
  // With a limit of 0 nothing is kept, and baking still works.
  ::setenv(kBakeCacheLimitVariable, "0", 1);
  test::TempDir dir;
  HeightField f;
  f.width = f.height = 8;
  f.h.assign(64, 0.0);
  f.h[9] = 1.0;
  EXPECT_EQ(load_or_bake_cone_map(f, ConeKind::Relaxed, dir / "cache").ratio, bake_cone_map(f, ConeKind::Relaxed).ratio);
  EXPECT_TRUE(bake_cache_entries(dir / "cache").empty());
  saved ? ::setenv(kBakeCacheLimitVariable, old.c_str(), 1) : ::unsetenv(kBakeCacheLimitVariable);
}

}  // namespace
}  // namespace qdmr
