// Cone maps: the fast baker against brute force, the defining properties checked by marching every ray of a
// dense set through small maps against the exact box surface, hand-computed cases, the cache and the command.
#include "qdmr/bake/cone_map.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <tbb/task_arena.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "support/captured_warnings.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

HeightField random_field(int w, int h, AddressMode address, std::uint32_t seed, double low = 0.0) {
  std::mt19937 rng(seed);
  HeightField f;
  f.width = w;
  f.height = h;
  f.address = address;
  f.h = ZeroedBuffer<double>(std::size_t(w) * std::size_t(h));
  // 8-bit levels: ties (equal heights) are common, as in real maps.
  for (double& v : f.h) v = low + (1.0 - low) * double(rng() % 256) / 255.0;
  return f;
}

HeightField procedural_field(ProceduralPattern pattern, int size, int cells, AddressMode address) {
  ProceduralDesc desc;
  desc.pattern = pattern;
  desc.size = size;
  desc.cells = cells;
  const Image image = generate_procedural(desc);
  HeightField f;
  f.width = image.width;
  f.height = image.height;
  f.address = address;
  f.h.assign(image.texels.begin(), image.texels.end());
  return f;
}

struct NamedField {
  std::string name;
  HeightField field;
};

// Random fields (square and not, plateaus near the top) and the structured patterns, in every address mode.
std::vector<NamedField> test_fields(int max_size) {
  std::vector<NamedField> fields;
  const std::pair<AddressMode, const char*> modes[] = {
      {AddressMode::Wrap, "wrap"}, {AddressMode::Clamp, "clamp"}, {AddressMode::Mirror, "mirror"}};
  for (const auto& [mode, mode_name] : modes) {
    const std::string suffix = std::string(" ") + mode_name;
    for (int n : {8, 16, 32})
      if (n <= max_size)
        fields.push_back({"random " + std::to_string(n) + suffix, random_field(n, n, mode, 7u + unsigned(n))});
    if (max_size >= 13) fields.push_back({"random 13x7" + suffix, random_field(13, 7, mode, 3)});
    if (max_size >= 32) {
      // Smooth bumps cut into four levels: wide plateaus whose texels walk the hierarchy together (the fast
      // baker's blocks of 4x4 texels; 37 and 21 are not multiples of 4).
      HeightField terraces = random_field(37, 21, mode, 11);
      for (int y = 0; y < 21; ++y)
        for (int x = 0; x < 37; ++x)
          terraces.h[std::size_t(y * 37 + x)] =
              std::floor(3.999 * (0.5 + 0.25 * std::sin(0.7 * x) + 0.25 * std::cos(0.45 * y))) / 3.0;
      fields.push_back({"terraces 37x21" + suffix, terraces});
    }
    fields.push_back({"high random 8" + suffix, random_field(8, 8, mode, 5, 0.9)});
    fields.push_back({"steps" + suffix, procedural_field(ProceduralPattern::Steps, std::min(16, max_size), 2, mode)});
    fields.push_back({"spikes" + suffix, procedural_field(ProceduralPattern::Spikes, std::min(16, max_size), 2, mode)});
    fields.push_back({"checker" + suffix, procedural_field(ProceduralPattern::Checker, 8, 2, mode)});
  }
  return fields;
}

TEST(ConeMap, FastBakerEqualsBruteForceBitForBit) {
  for (const NamedField& nf : test_fields(32))
    for (ConeKind kind : {ConeKind::Conservative, ConeKind::Relaxed}) {
      const ConeMap fast = bake_cone_map(nf.field, kind);
      const ConeMap brute = bake_cone_map_brute_force(nf.field, kind);
      ASSERT_EQ(fast.width, nf.field.width);
      ASSERT_EQ(fast.height, nf.field.height);
      EXPECT_EQ(fast.kind, kind);
      for (std::size_t k = 0; k < brute.ratio.size(); ++k)
        ASSERT_EQ(fast.ratio[k], brute.ratio[k]) << nf.name << " " << cone_kind_name(kind) << " texel " << k;
    }
}

TEST(ConeMap, RelaxedConesAreNeverNarrowerThanConservative) {
  for (const NamedField& nf : test_fields(32)) {
    const ConeMap conservative = bake_cone_map(nf.field, ConeKind::Conservative);
    const ConeMap relaxed = bake_cone_map(nf.field, ConeKind::Relaxed);
    for (std::size_t k = 0; k < relaxed.ratio.size(); ++k) {
      ASSERT_GE(relaxed.ratio[k], conservative.ratio[k]) << nf.name << " texel " << k;
      ASSERT_GE(conservative.ratio[k], 0.0f);
      ASSERT_LE(relaxed.ratio[k], kMaxConeRatio);
    }
  }
}

TEST(ConeMap, FlatMapHasTheWidestCones) {
  HeightField f;
  f.width = 5;
  f.height = 3;
  f.h.assign(15, 0.25);
  for (ConeKind kind : {ConeKind::Conservative, ConeKind::Relaxed})
    for (float r : bake_cone_map(f, kind).ratio) EXPECT_EQ(r, kMaxConeRatio);
}

// One pillar of height 0.5 at texel (3, 3) of an 8x8 map at height 0, clamp (no copies of the pillar).
TEST(ConeMap, SinglePillarByHand) {
  HeightField f;
  f.width = f.height = 8;
  f.address = AddressMode::Clamp;
  f.h.assign(64, 0.0);
  f.h[3 * 8 + 3] = 0.5;
  const ConeMap c = bake_cone_map(f, ConeKind::Conservative);
  const ConeMap r = bake_cone_map(f, ConeKind::Relaxed);
  auto at = [](const ConeMap& m, int i, int j) { return double(m.ratio[std::size_t(j) * 8 + std::size_t(i)]); };
  // Stored values are the double rounded toward zero: within one float ulp below (2^-23 relative).
  auto expect_stored = [](double stored, double exact) {
    EXPECT_LE(stored, exact);
    EXPECT_GE(stored, exact * (1.0 - 0x1p-23));
  };
  EXPECT_EQ(at(c, 3, 3), double(kMaxConeRatio));  // the pillar: nothing higher
  EXPECT_EQ(at(c, 2, 2), 0.0);                    // 8-neighbours touch the pillar's square
  EXPECT_EQ(at(c, 4, 3), 0.0);
  // (0, 0): 2 whole texels between the squares on each axis, 1/8 UV each; height difference 0.5.
  expect_stored(at(c, 0, 0), std::sqrt(2.0 * 2.0 + 2.0 * 2.0) / 8.0 / 0.5);
  expect_stored(at(c, 0, 3), 2.0 / 8.0 / 0.5);
  expect_stored(at(c, 7, 7), std::sqrt(3.0 * 3.0 + 3.0 * 3.0) / 8.0 / 0.5);
  // Relaxed: the binding walls are the pillar's far sides (3 texels away along the ray) and its side walls.
  // (0, 0): +x wall at 3 texels with 2 texels across, or +y wall likewise: sqrt(13) / 8 / 0.5.
  expect_stored(at(r, 0, 0), std::sqrt(13.0) / 8.0 / 0.5);
  // (0, 3): the +y and -y walls of the pillar are 2 texels away horizontally, touching p's row: 2 / 8 / 0.5.
  expect_stored(at(r, 0, 3), 2.0 / 8.0 / 0.5);
  // (2, 3), the left neighbour: the pillar's +x wall is one texel away, its y walls touch p's corner: 0.
  EXPECT_EQ(at(r, 2, 3), 0.0);
  // (2, 1): the pillar's +x wall is 1 texel right of p's square and 1 texel above its row: sqrt(2) / 8 / 0.5
  // (its +y wall, 0 across and 2 up, gives 2 / 8 / 0.5); conservative: the pillar's square is 1 texel above p's.
  expect_stored(at(r, 2, 1), std::sqrt(2.0) / 8.0 / 0.5);
  expect_stored(at(c, 2, 1), 1.0 / 8.0 / 0.5);
  EXPECT_EQ(at(r, 3, 3), double(kMaxConeRatio));
}

// --- marching against the exact box surface ------------------------------------------------------------------

// A ray in (u, v, h) space parameterised by its drop in height t: p(t) = (o + t d, 1 - t), t in [0, 1].
struct Ray {
  double u, v, du, dv;
};

struct Surface {
  const HeightField& f;
  // Height of the (unwrapped) cell (x, y) with the address mode; clamp extends the edge texels.
  double cell(long x, long y) const {
    const long w = f.width, h = f.height;
    auto fold = [&](long i, long n) -> long {
      switch (f.address) {
        case AddressMode::Wrap:
          return ((i % n) + n) % n;
        case AddressMode::Clamp:
          return std::clamp(i, 0L, n - 1);
        case AddressMode::Mirror: {
          const long m = ((i % (2 * n)) + 2 * n) % (2 * n);
          return m < n ? m : 2 * n - 1 - m;
        }
      }
      return 0;
    };
    return f.h[std::size_t(fold(y, h) * w + fold(x, w))];
  }
};

// The cells a ray crosses for t in [t0, 1], in order, with the t interval of each (a 2D DDA in texel units).
void walk_cells(const Surface& s, const Ray& r, double t0,
                const std::function<bool(long, long, double, double)>& visit) {
  const double W = s.f.width, H = s.f.height;
  const double x = (r.u + t0 * r.du) * W, y = (r.v + t0 * r.dv) * H;
  const double dx = r.du * W, dy = r.dv * H;
  long cx = long(std::floor(x)), cy = long(std::floor(y));
  // On a cell boundary, the cell ahead.
  if (dx < 0 && x == std::floor(x)) --cx;
  if (dy < 0 && y == std::floor(y)) --cy;
  const double inf = std::numeric_limits<double>::infinity();
  auto next = [&](double p, long c, double d) {
    return d > 0 ? (double(c + 1) - p) / d : d < 0 ? (double(c) - p) / d : inf;
  };
  double tx = t0 + next(x, cx, dx), ty = t0 + next(y, cy, dy);
  double t = t0;
  while (t < 1.0) {
    const double t_end = std::min({tx, ty, 1.0});
    if (!visit(cx, cy, t, t_end)) return;
    t = t_end;
    if (tx <= ty) {
      cx += dx > 0 ? 1 : -1;
      tx = t0 + (double(dx > 0 ? cx + 1 : cx) - x) / dx;
    } else {
      cy += dy > 0 ? 1 : -1;
      ty = t0 + (double(dy > 0 ? cy + 1 : cy) - y) / dy;
    }
  }
}

// Intervals shorter than this (in t) are a ray through a cell corner: fp64 rounding of tx vs ty (~1e-16), not a
// crossing of the cell; far below the shortest genuine crossing of the rays used here.
constexpr double kCorner = 1e-12;

// The first t >= t0 where the ray enters the interior of a column (touching an edge or corner is not a hit).
// The ray reaches h = 0, below every column, by t = 1.
double first_hit(const Surface& s, const Ray& r, double t0) {
  double hit = 1.0;
  walk_cells(s, r, t0, [&](long x, long y, double ta, double tb) {
    const double enter = std::max(ta, 1.0 - s.cell(x, y));  // inside for t in (enter, tb)
    if (tb - ta > kCorner && enter < tb) {
      hit = enter;
      return false;
    }
    return true;
  });
  return hit;
}

// The first cell boundary after t0 where the ray, inside the surface, comes out strictly above the next cell.
double first_exit(const Surface& s, const Ray& r, double t0) {
  double exit = 2.0;
  walk_cells(s, r, t0, [&](long x, long y, double ta, double tb) {
    if (ta > t0 && tb - ta > kCorner && 1.0 - ta > s.cell(x, y)) {
      exit = ta;
      return false;
    }
    return true;
  });
  return exit;
}

// The distance in UV from (u, v) to the square of unwrapped cell (x, y).
double distance_to_cell(const HeightField& f, double u, double v, long x, long y) {
  const double gx = std::max({double(x) / f.width - u, u - double(x + 1) / f.width, 0.0});
  const double gy = std::max({double(y) / f.height - v, v - double(y + 1) / f.height, 0.0});
  return std::hypot(gx, gy);
}

// Tolerances. kStepSlack: in t (height), how far a step may end past the first hit: far above the bisection's
// resolution (1e-15) and the overshoot kInside allows (1e-12 UV at slopes >= 0.02: 5e-11), far below a texel's
// worth of t (> 1e-3 here). kInside: in UV, the slack of S_p's membership test, so a point that a step left on a
// cell boundary (off by fp64 rounding, ~1e-16) counts as inside the next cell's region. kAhead: in texels, the
// nudge that decides which cell a point on a boundary is over (the one ahead of it along the ray).
constexpr double kStepSlack = 1e-9;
constexpr double kInside = 1e-12;
constexpr double kAhead = 1e-9;

struct MarchReport {
  long rays = 0, violations = 0, unfinished = 0;
  std::string first, first_unfinished;
};

// Marches every ray of a dense set with steps to the boundary of S_p (see cone_map.hpp) and calls check(ray,
// t_from, t_to) for each step. Rays start at h = 1 above texel centres and off-centre points, 16 azimuths, 5
// slopes (UV per unit of height, from steep to grazing); for clamp, a ray is followed while it is over the map.
void march_all(const HeightField& f, const ConeMap& cones, bool stop_below,
               const std::function<bool(const Ray&, double, double)>& step_ok, MarchReport& report) {
  const Surface s{f};
  // The cell under the ray at t, the one ahead of it when the point is on a boundary.
  auto cell_ahead = [&](const Ray& r, double t) {
    return std::pair{long(std::floor((r.u + t * r.du) * f.width + (r.du > 0 ? kAhead : -kAhead))),
                     long(std::floor((r.v + t * r.dv) * f.height + (r.dv > 0 ? kAhead : -kAhead)))};
  };
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i)
      for (const auto& [fx, fy] : {std::pair{0.5, 0.5}, std::pair{0.1, 0.8}, std::pair{0.93, 0.27}})
        for (int a = 0; a < 16; ++a)
          for (double slope : {0.02, 0.1, 0.4, 1.5, 6.0}) {
            const double angle = 2.0 * std::numbers::pi * a / 16.0 + (a % 2 ? 0.1 : 0.0);
            const Ray r{(i + fx) / f.width, (j + fy) / f.height, slope * std::cos(angle), slope * std::sin(angle)};
            ++report.rays;
            double t = 0.0;
            bool done = false;
            for (int iteration = 0; iteration < 2000 && !done; ++iteration) {
              const double u = r.u + t * r.du, v = r.v + t * r.dv, h = 1.0 - t;
              if (f.address == AddressMode::Clamp && (u < 0 || v < 0 || u >= 1 || v >= 1)) {
                done = true;
                break;
              }
              // The cell under the point, ahead of it when the point sits on a boundary (within the tolerance).
              const auto [x, y] = cell_ahead(r, t);
              const double hp = s.cell(x, y);
              if (h <= hp || t >= 1.0) {
                done = true;
                break;
              }
              const long tx = ((x % f.width) + f.width) % f.width, ty = ((y % f.height) + f.height) % f.height;
              long mx = tx, my = ty;  // mirror: the texel the cell copies
              if (f.address == AddressMode::Mirror) {
                const long px = ((x % (2L * f.width)) + 2L * f.width) % (2L * f.width);
                const long py = ((y % (2L * f.height)) + 2L * f.height) % (2L * f.height);
                mx = px < f.width ? px : 2L * f.width - 1 - px;
                my = py < f.height ? py : 2L * f.height - 1 - py;
              }
              const double ratio = cones.ratio[std::size_t(my * f.width + mx)];
              // S_p along the ray: { t' : dist(uv(t'), cell) <= ratio (h(t') - hp) }, an interval (S_p is convex).
              // Captured by copy: clang 14 cannot capture structured bindings (C++20 allows it; clang 16 does).
              auto inside = [&, cx = x, cy = y](double tt) {
                return distance_to_cell(f, r.u + tt * r.du, r.v + tt * r.dv, cx, cy) <= ratio * (1.0 - tt - hp) + kInside;
              };
              double lo = t, hi = t + (h - hp);
              const bool to_top = inside(hi);  // the step reaches p's top: a hit
              if (to_top) {
                lo = hi;
              } else {
                for (int k = 0; k < 80 && hi - lo > 1e-15; ++k) {
                  const double mid = 0.5 * (lo + hi);
                  (inside(mid) ? lo : hi) = mid;
                }
              }
              if (!step_ok(r, t, lo)) {
                if (report.violations++ == 0)
                  report.first =
                      "texel (" + std::to_string(i) + ", " + std::to_string(j) + ") ray u=" + std::to_string(r.u) +
                      " v=" + std::to_string(r.v) + " du=" + std::to_string(r.du) + " dv=" + std::to_string(r.dv) +
                      " step " + std::to_string(t) + " -> " + std::to_string(lo) + " over cell (" + std::to_string(x) +
                      ", " + std::to_string(y) + ") h=" + std::to_string(hp) + " ratio=" + std::to_string(ratio) +
                      " first hit " + std::to_string(first_hit(s, r, 0.0));
                done = true;
                break;
              }
              // A step that ends inside the surface ends the relaxed search (a binary search takes over).
              if (to_top) done = true;
              if (stop_below) {
                const auto [ex, ey] = cell_ahead(r, lo);
                done = done || 1.0 - lo <= s.cell(ex, ey);
              }
              t = std::max(lo, t);
            }
            if (!done && report.unfinished++ == 0)
              report.first_unfinished = "texel (" + std::to_string(i) + ", " + std::to_string(j) +
                                        ") ray u=" + std::to_string(r.u) + " v=" + std::to_string(r.v) +
                                        " du=" + std::to_string(r.du) + " dv=" + std::to_string(r.dv) +
                                        " at t=" + std::to_string(t);
          }
}

MarchReport check_conservative(const HeightField& f, const ConeMap& cones) {
  const Surface s{f};
  MarchReport report;
  // Never past the first point where the box surface is at or above the ray.
  march_all(
      f, cones, false, [&](const Ray& r, double, double to) { return to <= first_hit(s, r, 0.0) + kStepSlack; },
      report);
  return report;
}

MarchReport check_relaxed(const HeightField& f, const ConeMap& cones) {
  const Surface s{f};
  MarchReport report;
  // A step from above the surface enters it at most once: after the first hit, no exit before the step's end.
  march_all(
      f, cones, true,
      [&](const Ray& r, double from, double to) {
        const double hit = first_hit(s, r, from);
        return hit >= to - kStepSlack || first_exit(s, r, hit) >= to - kStepSlack;
      },
      report);
  return report;
}

TEST(ConeMap, ConservativeConesNeverLetARayPassThroughTheSurface) {
  for (const NamedField& nf : test_fields(16)) {
    const MarchReport report = check_conservative(nf.field, bake_cone_map(nf.field, ConeKind::Conservative));
    EXPECT_EQ(report.violations, 0) << nf.name << ": " << report.first;
    EXPECT_EQ(report.unfinished, 0) << nf.name << ": " << report.first_unfinished;
    EXPECT_GT(report.rays, 0);
  }
}

TEST(ConeMap, RelaxedConesEnterTheSurfaceAtMostOncePerStep) {
  for (const NamedField& nf : test_fields(16)) {
    const MarchReport report = check_relaxed(nf.field, bake_cone_map(nf.field, ConeKind::Relaxed));
    EXPECT_EQ(report.violations, 0) << nf.name << ": " << report.first;
    EXPECT_EQ(report.unfinished, 0) << nf.name;
  }
}

// The checks have teeth: cones wider than the definition are caught.
TEST(ConeMap, MarchChecksCatchTooWideCones) {
  const HeightField f = random_field(8, 8, AddressMode::Wrap, 11);
  EXPECT_GT(check_conservative(f, bake_cone_map(f, ConeKind::Relaxed)).violations, 0);
  ConeMap wide = bake_cone_map(f, ConeKind::Relaxed);
  for (float& r : wide.ratio) r = r * 1.5f + 0.05f;
  EXPECT_GT(check_relaxed(f, wide).violations, 0);
}

TEST(ConeMap, EmptyOrOutOfRangeFieldsAreRejected) {
  HeightField empty;
  EXPECT_THROW(bake_cone_map(empty, ConeKind::Conservative), Error);
  HeightField bad = random_field(4, 4, AddressMode::Wrap, 1);
  bad.h[5] = 1.5;
  EXPECT_THROW(bake_cone_map(bad, ConeKind::Relaxed), Error);
  bad.h[5] = std::nan("");
  EXPECT_THROW(bake_cone_map_brute_force(bad, ConeKind::Conservative), Error);
}

TEST(ConeMap, SameBitsForAnyThreadCount) {
  const HeightField f = procedural_field(ProceduralPattern::Cobbles, 128, 8, AddressMode::Wrap);
  for (ConeKind kind : {ConeKind::Conservative, ConeKind::Relaxed}) {
    const ConeMap all = bake_cone_map(f, kind);
    ConeMap one;
    tbb::task_arena(1).execute([&] { one = bake_cone_map(f, kind); });
    EXPECT_EQ(all.ratio, one.ratio);
  }
}

// --- cache ---------------------------------------------------------------------------------------------------

TEST(ConeMapCache, MissThenHitThenCorruptFilesAreRebuilt) {
  TempDir dir;
  const HeightField f = random_field(16, 12, AddressMode::Clamp, 21);
  const ConeMap expected = bake_cone_map(f, ConeKind::Relaxed);
  EXPECT_EQ(load_or_bake_cone_map(f, ConeKind::Relaxed, dir.path() / "cache").ratio, expected.ratio);
  const fs::path file = only_file(dir.path() / "cache");
  const std::string good = read_file(file);
  EXPECT_EQ(good.size(), 40 + 16 * 12 * sizeof(float));  // header + ratios

  // A hit leaves the file alone (a rebuild would replace it: another inode) and marks it as used (its
  // modification time: the cache evicts the least recently used, qdmr/bake/bake_cache.hpp).
  const auto old_time = fs::file_time_type::clock::now() - std::chrono::hours(24);
  fs::last_write_time(file, old_time);
  struct stat before{}, after{};
  ASSERT_EQ(::stat(file.c_str(), &before), 0);
  EXPECT_EQ(load_or_bake_cone_map(f, ConeKind::Relaxed, dir.path() / "cache").ratio, expected.ratio);
  ASSERT_EQ(::stat(file.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_GT(fs::last_write_time(file), old_time);

  std::string payload_flip = good;
  payload_flip[good.size() - 3] ^= 0x40;
  std::string key_flip = good;
  key_flip[24] ^= 1;
  const std::string corrupt[] = {good.substr(0, good.size() - 4), payload_flip, key_flip,
                                 std::string(good.size(), 'x'),   "",           good + "extra"};
  for (const std::string& bytes : corrupt) {
    write_file(file, bytes);
    EXPECT_EQ(load_or_bake_cone_map(f, ConeKind::Relaxed, dir.path() / "cache").ratio, expected.ratio);
    EXPECT_EQ(read_file(file), good);
  }

  // Another kind, address or content: another entry.
  load_or_bake_cone_map(f, ConeKind::Conservative, dir.path() / "cache");
  HeightField wrapped = f;
  wrapped.address = AddressMode::Wrap;
  load_or_bake_cone_map(wrapped, ConeKind::Relaxed, dir.path() / "cache");
  HeightField changed = f;
  changed.h[7] = std::nextafter(changed.h[7], 2.0) > 1.0 ? 0.5 : std::nextafter(changed.h[7], 2.0);
  EXPECT_NE(cone_map_key(changed, ConeKind::Relaxed), cone_map_key(f, ConeKind::Relaxed));
  load_or_bake_cone_map(changed, ConeKind::Relaxed, dir.path() / "cache");
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path() / "cache")) ++count;
  EXPECT_EQ(count, 4u);
}

// The cache is an optimisation: a folder that cannot be made still gives the map, and one warning names the entry
// and the OS reason (the command prints it as "qdmr: warning: ..."; full and read-only mounts: faults.injection).
TEST(ConeMapCache, UnwritableCacheStillBakesAndSaysWhy) {
  TempDir dir;
  write_file(dir / "not-a-folder", "x");
  const HeightField f = random_field(8, 8, AddressMode::Wrap, 2);
  CapturedWarnings warnings;
  EXPECT_EQ(load_or_bake_cone_map(f, ConeKind::Conservative, dir / "not-a-folder").ratio,
            bake_cone_map(f, ConeKind::Conservative).ratio);
  const std::vector<std::string> lines = warnings.lines();
  ASSERT_EQ(lines.size(), 1u);
  const std::string entry = (dir / "not-a-folder" / "cone-conservative-").string();  // then the key, ".bin"
  EXPECT_EQ(lines[0].substr(0, entry.size()), entry) << lines[0];
  const std::string why = std::string(".bin: cannot write bake cache: cannot create its folder: ") +
                          std::strerror(ENOTDIR) + " (the map is baked again next time)";
  EXPECT_TRUE(lines[0].ends_with(why)) << lines[0];
}

TEST(ConeMapCache, DefaultFolderFromTheEnvironment) {
  auto saved = [](const char* name) {
    const char* v = std::getenv(name);
    return v ? std::optional<std::string>(v) : std::nullopt;
  };
  const auto qdmr = saved("QDMR_CACHE_DIR"), xdg = saved("XDG_CACHE_HOME"), home = saved("HOME");
  ::setenv("QDMR_CACHE_DIR", "/a/qc", 1);
  ::setenv("XDG_CACHE_HOME", "/b/xdg", 1);
  ::setenv("HOME", "/c/home", 1);
  EXPECT_EQ(default_cache_dir(), fs::path("/a/qc"));
  ::unsetenv("QDMR_CACHE_DIR");
  EXPECT_EQ(default_cache_dir(), fs::path("/b/xdg/qdmr"));
  ::unsetenv("XDG_CACHE_HOME");
  EXPECT_EQ(default_cache_dir(), fs::path("/c/home/.cache/qdmr"));
  auto restore = [](const char* name, const std::optional<std::string>& v) {
    if (v)
      ::setenv(name, v->c_str(), 1);
    else
      ::unsetenv(name);
  };
  restore("QDMR_CACHE_DIR", qdmr);
  restore("XDG_CACHE_HOME", xdg);
  restore("HOME", home);
}

// --- the command ---------------------------------------------------------------------------------------------

void write_gray_png(const fs::path& file, int w, int h, const std::vector<std::uint8_t>& pixels) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  ASSERT_TRUE(out->open(file.string(), OIIO::ImageSpec(w, h, 1, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  ASSERT_TRUE(out->close());
}

// w x h 8-bit heights of noise from `seed`.
std::vector<std::uint8_t> noise_heights(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> pixels(std::size_t(w) * std::size_t(h));
  for (auto& p : pixels) p = std::uint8_t(rng() % 256);
  return pixels;
}

TEST(ConeMapCli, BakesTheSameMapAsTheLibrary) {
  TempDir dir;
  write_gray_png(dir / "height.png", 24, 20, noise_heights(24, 20, 4));
  fs::create_directory(dir / "out");
  for (const auto& [kind_name, kind, address_name, address] :
       {std::tuple{"conservative", ConeKind::Conservative, "wrap", AddressMode::Wrap},
        std::tuple{"relaxed", ConeKind::Relaxed, "clamp", AddressMode::Clamp}}) {
    const fs::path out = dir / "out" / (std::string(kind_name) + ".exr");
    const CommandResult result = run(cli(), {"bake", "cone", (dir / "height.png").string(), "--kind", kind_name,
                                             "--address", address_name, "-o", out.string()});
    ASSERT_EQ(result.exit_code, 0) << result.output;
    const Image height = read_image(dir / "height.png", "test");
    HeightField f;
    f.width = height.width;
    f.height = height.height;
    f.address = address;
    f.h.assign(height.texels.begin(), height.texels.end());
    const Image cones = read_image(out, "test");
    ASSERT_EQ(cones.channels, 1);
    EXPECT_EQ(cones.texels, bake_cone_map(f, kind).ratio) << kind_name;
  }
  // Only the two outputs: no temporary file left behind.
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "out")) ++count;
  EXPECT_EQ(count, 2u);
}

// --threads bounds the bake (and its read and write) to a task arena of that many threads, like render's: every
// count writes the same bytes, those of a bake on every core. 160x120 texels of noise: many rows for the bake's
// parallel loops, and an EXR input of several chunks.
TEST(ConeMapCli, EveryThreadCountWritesTheSameBytes) {
  TempDir dir;
  const std::vector<std::uint8_t> pixels = noise_heights(160, 120, 7);
  write_gray_png(dir / "height.png", 160, 120, pixels);
  write_gray_png(dir / "height.exr", 160, 120, pixels);  // OpenImageIO writes it as OpenEXR: k / 255 as halves
  const CommandResult help = run(cli(), {"bake", "cone", "--help"});
  EXPECT_NE(help.output.find("--threads"), std::string::npos) << help.output;
  for (const char* kind : {"conservative", "relaxed"}) {
    SCOPED_TRACE(kind);
    const auto bake = [&](const fs::path& in, const std::string& name, const std::vector<std::string>& threads) {
      std::vector<std::string> args = {"bake", "cone", in.string(), "--kind", kind, "-o", (dir / name).string()};
      args.insert(args.end(), threads.begin(), threads.end());
      const CommandResult result = run(cli(), args);
      EXPECT_EQ(result.exit_code, 0) << result.output;
      return read_file(dir / name);
    };
    const std::string all = bake(dir / "height.png", "all.exr", {});
    EXPECT_EQ(bake(dir / "height.png", "one.exr", {"--threads", "1"}), all);
    EXPECT_EQ(bake(dir / "height.png", "two.exr", {"--threads", "2"}), all);
    EXPECT_EQ(bake(dir / "height.png", "five.exr", {"--threads", "5"}), all);
    // An OpenEXR input (several chunks), read on 1 thread and on every core.
    EXPECT_EQ(bake(dir / "height.exr", "exr-one.exr", {"--threads", "1"}), bake(dir / "height.exr", "exr-all.exr", {}));
  }
}

TEST(ConeMapCli, BadInputGivesOneErrorLineAndWritesNothing) {
  TempDir dir;
  write_gray_png(dir / "height.png", 4, 4, std::vector<std::uint8_t>(16, 100));
  write_file(dir / "broken.png", "not an image");
  fs::create_directory(dir / "out");
  const std::string in = (dir / "height.png").string(), out = (dir / "out" / "c.exr").string();
  const std::vector<std::vector<std::string>> cases = {
      {"bake", "cone", (dir / "missing.png").string(), "-o", out},
      {"bake", "cone", (dir / "broken.png").string(), "-o", out},
      {"bake", "cone", in, "--kind", "wide", "-o", out},
      {"bake", "cone", in, "--address", "border", "-o", out},
      {"bake", "cone", in, "--channel", "g", "-o", out},
      {"bake", "cone", in, "--threads", "0", "-o", out},
      {"bake", "cone", in, "--threads", "257", "-o", out},
      {"bake", "cone", in, "--threads", "many", "-o", out},
      {"bake", "cone", in, "-o", (dir / "out" / "c.png").string()},
      {"bake", "cone", in, "-o", (dir / "nowhere" / "c.exr").string()},
      {"bake", "cone", in},
      {"bake"},
  };
  for (const auto& args : cases) {
    const CommandResult result = run(cli(), args);
    EXPECT_EQ(result.exit_code, 2) << args.back() << ": " << result.output;
    const std::vector<std::string> lines = lines_of(result.output);
    ASSERT_EQ(lines.size(), 1u) << result.output;
    EXPECT_EQ(lines[0].rfind("qdmr: error: ", 0), 0u) << lines[0];
    EXPECT_TRUE(fs::is_empty(dir / "out")) << lines[0];
  }
}

}  // namespace
}  // namespace qdmr::test
