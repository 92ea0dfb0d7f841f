// Baked ambient occlusion maps: flat ground, the pit of the per-frame test in double, sizes, thread-count
// independence and the content-hash cache.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <tbb/task_arena.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

#include "bake/ao_pattern.hpp"
#include "bake/ao_map.hpp"
#include "qdmr/core/error.hpp"
#include "kernel/kernel.hpp"
#include "qdmr/core/isa.hpp"
#include "support/captured_warnings.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

HeightField continuous_random_field(int w, int h, AddressMode address, std::uint32_t seed) {
  HeightField f;
  f.width = w;
  f.height = h;
  f.address = address;
  f.h = ZeroedBuffer<double>(std::size_t(w) * std::size_t(h));
  std::uint32_t state = seed;
  for (double& v : f.h) {
    state = state * 1664525u + 1013904223u;
    v = double(state >> 8) / double(1u << 24);
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
  const HeightField f = continuous_random_field(16, 8, AddressMode::Wrap, 4);
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
  f.h = ZeroedBuffer<double>(std::size_t(n) * std::size_t(n));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) f.h[std::size_t(y * n + x)] = (x - c) * (x - c) + (y - c) * (y - c) < r * r ? 1.0 - depth : 1.0;
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
  const HeightField f = continuous_random_field(32, 32, AddressMode::Mirror, 8);
  for (bool coarse : {false, true}) {
    AoDesc d = baked_desc(coarse);
    d.jitter = true;
    const Image all = bake_ao_map(f, 0.05, d);
    Image one;
    tbb::task_arena(1).execute([&] { one = bake_ao_map(f, 0.05, d); });
    EXPECT_EQ(all.texels, one.texels);
  }
}

// The bake's definition (ao_map.hpp), evaluated the plain way: every tap's slope divided out, every direction's
// visibility computed, the coarse taps' pyramid cell maxima found by scanning the level-0 texels the cell covers.
// The bake takes a shortcut that must keep every bit of the map (one division per direction for coarse taps).
// The map stores floats, so a last-bit slip in double would rarely show here; a wrong choice of tap does.
double defined_texel_ao(const HeightField& f, double ds, const AoDesc& d, int i, int j, int map_w, int map_h) {
  const double u = (i + 0.5) / map_w, v = (j + 0.5) / map_h;
  const auto bilinear_depth = [&](double tu, double tv) { return bilinear_surface_depth(f, ds, tu, tv); };
  const auto cell_max = [&](int level, std::int64_t x, std::int64_t y) {
    int w = f.width, h = f.height;  // level `level`'s size: max(1, floor(n / 2)) per step
    for (int k = 0; k < level; ++k) w = std::max(1, w / 2), h = std::max(1, h / 2);
    const std::int64_t cx = std::min<std::int64_t>(x >> level, w - 1), cy = std::min<std::int64_t>(y >> level, h - 1);
    // The cell's level-0 texels: [c 2^level, (c + 1) 2^level), the last cell running to the edge.
    const std::int64_t x0 = cx << level, y0 = cy << level;
    const std::int64_t x1 = cx == w - 1 ? f.width : (cx + 1) << level, y1 = cy == h - 1 ? f.height : (cy + 1) << level;
    double m = 0.0;
    for (std::int64_t ty = y0; ty < y1; ++ty)
      for (std::int64_t tx = x0; tx < x1; ++tx) m = std::max(m, f.h[std::size_t(ty * f.width + tx)]);
    return m;
  };
  const int n = ao::direction_count(pattern_of(d));
  const int rotation = d.jitter ? ao::rotation(std::uint32_t(i), std::uint32_t(j), d.seed) : 0;
  const ao::Taps taps = ao::make_taps(pattern_of(d), f.width, f.height);
  const double s = bilinear_depth(u, v);
  double visible = 0.0;
  for (int k = 0; k < n; ++k) {
    const int index = ao::direction_index(n, k, rotation);
    const double dx = ao::kDirections.cos[std::size_t(index)], dy = ao::kDirections.sin[std::size_t(index)];
    double slope = 0.0;
    for (int t = 0; t < taps.count; ++t) {
      const ao::Tap& tap = taps.tap[std::size_t(t)];
      const double tu = u + dx * double(tap.distance), tv = v + dy * double(tap.distance);
      double depth;
      if (d.coarse) {
        const auto x = HeightField::texel_index(std::int64_t(std::floor(tu * f.width)), f.width, f.address);
        const auto y = HeightField::texel_index(std::int64_t(std::floor(tv * f.height)), f.height, f.address);
        int top = 0;
        for (int w = f.width, h = f.height; w > 1 || h > 1; w = std::max(1, w / 2), h = std::max(1, h / 2)) ++top;
        depth = ds * (1.0 - cell_max(std::min(tap.level, top), x, y));
      } else {
        depth = bilinear_depth(tu, tv);
      }
      slope = std::max(slope, (s - depth) / double(tap.distance));
    }
    visible += 1.0 - slope / std::sqrt(1.0 + slope * slope);
  }
  return visible / double(n);
}

TEST(AoMap, FloatHeightsBakeAsTheirDoubles) {
  // A blend's AO map is baked from its fp32 box values through a HeightView<float>: every texel, and the cache key,
  // must be those of the fp64 copy of the same values (which the bake read before). random_field's values have 24
  // significant bits, so the floats hold them exactly. Scalar rows and every kernel this CPU runs; coarse (the
  // kernels' shared-column rows without jitter, per-lane gathers with it) and fine taps; every address mode.
  std::vector<std::pair<std::string, AoMapRow>> bakes = {{"scalar", AoMapRow{}}};
  for (Isa isa : usable_isas()) bakes.emplace_back(isa_name(isa), kernel_for(isa).ao_map_row());
  int cases = 0;
  for (const auto& [name, row] : bakes)
    for (AddressMode address : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
      for (bool coarse : {true, false})
        for (bool jitter : {false, true}) {
          const HeightField f = continuous_random_field(41, 27, address, std::uint32_t(31 + cases++));
          const std::vector<float> floats(f.h.begin(), f.h.end());
          for (std::size_t k = 0; k < floats.size(); ++k) ASSERT_EQ(double(floats[k]), f.h[k]);  // exact copies
          const HeightView<float> view{f.width, f.height, f.address, floats.data()};
          AoDesc d = baked_desc(coarse);
          d.jitter = jitter;
          d.resolution = cases % 3 == 0 ? 33 : 0;
          const Image from_doubles = bake_ao_map(f, 0.05, d, row);
          const Image from_floats = bake_ao_map(view, 0.05, d, row);
          EXPECT_EQ(from_floats.texels, from_doubles.texels) << name << " address " << int(address) << " coarse "
                                                             << coarse << " jitter " << jitter;
          EXPECT_EQ(ao_map_key(view, 0.05, d), ao_map_key(f, 0.05, d));
        }
}

TEST(AoMap, BakeIsTheDefinitionBitForBit) {
  // Odd sizes (leftover pyramid cells, rows that end in a part of a vector), every address mode, jitter, a map of
  // another size than the field, and depth scales from shallow to steep (most directions open, most closed);
  // coarse with radii of 1 to 5 taps. Then the lanes the vector bakes hand to the scalar definition: rises so
  // small that they are compared tap by tap (depth scale 1e-300), taps a billion texels away (fine, radius 1e7).
  // The scalar bake (no row function) and every kernel of this binary that this CPU runs bake them.
  std::vector<std::pair<std::string, AoMapRow>> bakes = {{"scalar", AoMapRow{}}};
  for (Isa isa : usable_isas()) bakes.emplace_back(isa_name(isa), kernel_for(isa).ao_map_row());
  for (const auto& [name, row] : bakes) {
    int cases = 0;
    for (AddressMode address : {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror})
      for (bool coarse : {true, false})
        for (double ds : {0.002, 0.05, 2.0, 1e-300})
          for (float radius : {0.03f, 0.2f, 0.6f, 1e7f}) {
            if (radius > 1.0f && coarse) continue;  // coarse taps stop at 2^30 texels
            const HeightField f = continuous_random_field(37, 23, address, std::uint32_t(7 + cases));
            AoDesc d = baked_desc(coarse);
            d.radius = radius;
            d.jitter = cases % 2 == 1;
            d.resolution = cases % 3 == 0 ? 29 : 0;
            const Image map = bake_ao_map(f, ds, d, row);
            for (int j = 0; j < map.height; ++j)
              for (int i = 0; i < map.width; ++i)
                ASSERT_EQ(map.at(i, j, 0), float(defined_texel_ao(f, ds, d, i, j, map.width, map.height)))
                    << name << " texel " << i << "," << j << " address " << int(address) << " coarse " << coarse
                    << " ds " << ds << " radius " << radius;
            ++cases;
          }
  }
}

TEST(AoMap, CacheMissThenHitThenCorruptFilesAreRebuilt) {
  TempDir dir;
  const HeightField f = continuous_random_field(16, 12, AddressMode::Clamp, 21);
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
  const HeightField f = continuous_random_field(8, 8, AddressMode::Wrap, 3);
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

// As ConeMapCache.UnwritableCacheStillBakesAndSaysWhy: the map, and one warning naming the entry and the reason.
TEST(AoMap, UnwritableCacheStillBakesAndSaysWhy) {
  TempDir dir;
  write_file(dir / "not-a-folder", "x");
  const HeightField f = continuous_random_field(8, 8, AddressMode::Wrap, 2);
  const AoDesc d = baked_desc(true);
  CapturedWarnings warnings;
  EXPECT_EQ(load_or_bake_ao_map(f, 0.05, d, dir / "not-a-folder").texels, bake_ao_map(f, 0.05, d).texels);
  const std::vector<std::string> lines = warnings.lines();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].rfind((dir / "not-a-folder" / "ao-").string(), 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find(".bin: cannot write bake cache: cannot create its folder: " + std::string(std::strerror(ENOTDIR))),
            std::string::npos) << lines[0];
}

}  // namespace
}  // namespace qdmr::test
