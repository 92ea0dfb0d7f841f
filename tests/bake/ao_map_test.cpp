// Baked ambient occlusion maps: flat ground, the pit of the per-frame test in double, sizes, thread-count
// independence and the content-hash cache.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>

#include "qdmr/bake/ao_map.hpp"
#include "qdmr/core/error.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

HeightField random_field(int w, int h, AddressMode address, std::uint32_t seed) {
  HeightField f;
  f.width = w;
  f.height = h;
  f.address = address;
  std::uint32_t state = seed;
  for (int k = 0; k < w * h; ++k) {
    state = state * 1664525u + 1013904223u;
    f.h.push_back(double(state >> 8) / double(1u << 24));
  }
  return f;
}

AoDesc baked_desc(bool coarse) {
  AoDesc d;
  d.mode = AoMode::Baked;
  d.directions = 8;
  d.radius = 0.25f;
  d.coarse = coarse;
  return d;
}

TEST(AoMap, FlatFieldIsExactlyOpen) {
  HeightField f;
  f.width = 16;
  f.height = 8;
  f.h.assign(16 * 8, 0.7);
  for (AddressMode address : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
    for (bool coarse : {false, true}) {
      f.address = address;
      AoDesc d = baked_desc(coarse);
      d.jitter = true;
      const Image map = bake_ao_map(f, 0.1, d);
      ASSERT_EQ(map.width, 16);
      ASSERT_EQ(map.height, 8);
      ASSERT_EQ(map.channels, 1);
      for (float a : map.texels) EXPECT_EQ(a, 1.0f);
    }
}

TEST(AoMap, ResolutionAndErrors) {
  const HeightField f = random_field(16, 8, AddressMode::Wrap, 4);
  AoDesc d = baked_desc(true);
  d.resolution = 40;  // 40 x (40 * 8 / 16)
  const Image map = bake_ao_map(f, 0.1, d);
  EXPECT_EQ(map.width, 40);
  EXPECT_EQ(map.height, 20);
  for (float a : map.texels) {
    EXPECT_GE(a, 0.0f);
    EXPECT_LE(a, 1.0f);
  }
  EXPECT_THROW(bake_ao_map(HeightField{}, 0.1, d), Error);
}

// The bake's pit: centre of a round pit of radius r = 12 texels and depth 0.5 on a 64 map, texels outside iff their
// centre is at least r from the pit's. The bilinear surface at a tap mixes the 4 texel centres within sqrt(2)
// texels of it: it rises above the pit floor only for taps beyond r - sqrt(2), and reaches the full rise D for every
// tap beyond r + sqrt(2), of which there is one before r + sqrt(2) + 1 (taps every texel). So every direction's
// slope lies in [D / (r + sqrt(2) + 1), D / (r - sqrt(2))]: bounds around the closed form 1 - sin(atan(D / r)).
TEST(AoMap, PitCentreWithinTheClosedFormBounds) {
  const int n = 64, c = 32;
  const double r = 12.0, depth = 0.5, ds = 0.1;
  HeightField f;
  f.width = f.height = n;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) f.h.push_back((x - c) * (x - c) + (y - c) * (y - c) < r * r ? 1.0 - depth : 1.0);
  const auto visibility = [&](double texels) {
    const double slope = ds * depth / (texels / n);
    return 1.0 - slope / std::sqrt(1.0 + slope * slope);
  };
  const Image map = bake_ao_map(f, ds, baked_desc(false));
  const float centre = map.at(c, c, 0);
  EXPECT_GE(centre, visibility(r - std::sqrt(2.0)));
  EXPECT_LE(centre, visibility(r + std::sqrt(2.0) + 1));
}

TEST(AoMap, SameBitsForAnyThreadCount) {
  const HeightField f = random_field(32, 32, AddressMode::Mirror, 8);
  for (bool coarse : {false, true}) {
    AoDesc d = baked_desc(coarse);
    d.jitter = true;
    const Image all = bake_ao_map(f, 0.05, d);
    Image one;
    tbb::task_arena(1).execute([&] { one = bake_ao_map(f, 0.05, d); });
    EXPECT_EQ(all.texels, one.texels);
  }
}

fs::path only_file(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  EXPECT_EQ(files.size(), 1u);
  return files.empty() ? fs::path() : files[0];
}

TEST(AoMap, CacheMissThenHitThenCorruptFilesAreRebuilt) {
  TempDir dir;
  const HeightField f = random_field(16, 12, AddressMode::Clamp, 21);
  const AoDesc d = baked_desc(false);
  const Image expected = bake_ao_map(f, 0.05, d);
  EXPECT_EQ(load_or_bake_ao_map(f, 0.05, d, dir / "cache").texels, expected.texels);
  const fs::path file = only_file(dir / "cache");
  const std::string good = read_file(file);
  EXPECT_EQ(good.size(), 40 + 16 * 12 * sizeof(float));  // header + values

  // A hit leaves the file alone (a rebuild would replace it: another inode) and marks it as used (its
  // modification time: the cache evicts the least recently used, qdmr/bake/bake_cache.hpp).
  const auto old_time = fs::file_time_type::clock::now() - std::chrono::hours(24);
  fs::last_write_time(file, old_time);
  struct stat before{}, after{};
  ASSERT_EQ(::stat(file.c_str(), &before), 0);
  const Image hit = load_or_bake_ao_map(f, 0.05, d, dir / "cache");
  EXPECT_EQ(hit.texels, expected.texels);
  EXPECT_EQ(hit.width, 16);
  EXPECT_EQ(hit.height, 12);
  ASSERT_EQ(::stat(file.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_GT(fs::last_write_time(file), old_time);

  std::string payload_flip = good;
  payload_flip[good.size() - 3] ^= 0x40;
  std::string key_flip = good;
  key_flip[24] ^= 1;
  const std::string corrupt[] = {good.substr(0, good.size() - 4), payload_flip, key_flip, std::string(good.size(), 'x'),
                                 "",                              good + "extra"};
  for (const std::string& bytes : corrupt) {
    write_file(file, bytes);
    EXPECT_EQ(load_or_bake_ao_map(f, 0.05, d, dir / "cache").texels, expected.texels);
    EXPECT_EQ(read_file(file), good);
  }
}

TEST(AoMap, KeyCoversWhatChangesTheMap) {
  const HeightField f = random_field(8, 8, AddressMode::Wrap, 3);
  const AoDesc d = baked_desc(true);
  const std::uint64_t key = ao_map_key(f, 0.05, d);
  const auto changed = [&](auto edit) {
    AoDesc e = d;
    HeightField g = f;
    double ds = 0.05;
    edit(g, ds, e);
    return ao_map_key(g, ds, e) != key;
  };
  EXPECT_TRUE(changed([](HeightField& g, double&, AoDesc&) { g.h[5] += 1e-12; }));
  EXPECT_TRUE(changed([](HeightField& g, double&, AoDesc&) { g.address = AddressMode::Mirror; }));
  EXPECT_TRUE(changed([](HeightField&, double& ds, AoDesc&) { ds = 0.06; }));
  EXPECT_TRUE(changed([](HeightField&, double&, AoDesc& e) { e.directions = 9; }));
  EXPECT_TRUE(changed([](HeightField&, double&, AoDesc& e) { e.radius = 0.3f; }));
  EXPECT_TRUE(changed([](HeightField&, double&, AoDesc& e) { e.coarse = false; }));
  EXPECT_TRUE(changed([](HeightField&, double&, AoDesc& e) { e.jitter = true; }));
  EXPECT_TRUE(changed([](HeightField&, double&, AoDesc& e) { e.resolution = 16; }));
  // Not in the key: what the map does not depend on.
  EXPECT_FALSE(changed([](HeightField&, double&, AoDesc& e) { e.strength = 0.5f; }));
  EXPECT_FALSE(changed([](HeightField&, double&, AoDesc& e) { e.mode = AoMode::Frame; }));
  EXPECT_FALSE(changed([](HeightField&, double&, AoDesc& e) { e.seed = 99; }));     // unjittered
  EXPECT_FALSE(changed([](HeightField&, double&, AoDesc& e) { e.resolution = 8; }));   // the field's own size
  AoDesc many = d, clamped = d;  // directions clamp to 4..16
  many.directions = 40;
  clamped.directions = 16;
  EXPECT_EQ(ao_map_key(f, 0.05, many), ao_map_key(f, 0.05, clamped));
  AoDesc jittered = d;
  jittered.jitter = true;
  AoDesc reseeded = jittered;
  reseeded.seed = 2;
  EXPECT_NE(ao_map_key(f, 0.05, jittered), ao_map_key(f, 0.05, reseeded));
}

TEST(AoMap, UnwritableCacheStillBakes) {
  TempDir dir;
  write_file(dir / "not-a-folder", "x");
  const HeightField f = random_field(8, 8, AddressMode::Wrap, 2);
  const AoDesc d = baked_desc(true);
  EXPECT_EQ(load_or_bake_ao_map(f, 0.05, d, dir / "not-a-folder").texels, bake_ao_map(f, 0.05, d).texels);
}

}  // namespace
}  // namespace qdmr::test
