// The exact reference intersector: hand-computed cases for both surfaces (flat fields, a pillar, ramps, a slit,
// a checkerboard, the address modes at the map edges, degenerate rays and maps), invariance under large uv
// offsets, a 4096^2 map, and a brute-force cross-check against dense sampling of random fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "qdmr/reference/reference.hpp"

namespace qdmr {
namespace {

using S = ReferenceSurface;
constexpr S kSurfaces[] = {S::Box, S::Bilinear};
constexpr AddressMode kModes[] = {AddressMode::Wrap, AddressMode::Clamp, AddressMode::Mirror};
constexpr double kEps = 2.220446049250313e-16;
const double kTan1Deg = std::tan(1.0 * 3.14159265358979323846 / 180.0);

std::string name(S s) { return s == S::Box ? "box" : "bilinear"; }

std::string sci(double x) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(2) << x;
  return out.str();
}

HeightField make_field(int w, int h, double value, AddressMode mode = AddressMode::Wrap) {
  return HeightField{w, h, ZeroedBuffer<double>(std::size_t(w) * std::size_t(h), value), mode};
}

void set(HeightField& f, int i, int j, double value) {
  f.h[std::size_t(j) * std::size_t(f.width) + std::size_t(i)] = value;
}

ReferenceHit cast(const HeightField& f, double depth_scale, glm::dvec3 origin, glm::dvec3 direction, S surface,
                  std::int64_t max_cells = 1 << 22) {
  return intersect_reference(f, depth_scale, SurfaceRay{origin, direction}, surface, max_cells);
}

// Hand-computed hits hold to a few roundings of numbers of order 1 (each input like 0.1 is itself rounded).
constexpr double kHand = 1e-14;

void expect_hit(const ReferenceHit& r, double t, glm::dvec3 point, double tol = kHand) {
  ASSERT_TRUE(r.hit);
  EXPECT_FALSE(r.inside_at_start);
  EXPECT_NEAR(r.t, t, tol);
  EXPECT_NEAR(r.point.x, point.x, tol);
  EXPECT_NEAR(r.point.y, point.y, tol);
  EXPECT_NEAR(r.point.z, point.z, tol);
}

TEST(StudyReference, AddressModes) {
  HeightField f{3, 2, {0.0, 0.1, 0.2, 0.3, 0.4, 0.5}, AddressMode::Wrap};
  EXPECT_EQ(f.at(-1, 0), 0.2);
  EXPECT_EQ(f.at(3, 3), 0.3);
  EXPECT_EQ(f.at(-30001, -19999), 0.5);
  f.address = AddressMode::Clamp;
  EXPECT_EQ(f.at(-1, 0), 0.0);
  EXPECT_EQ(f.at(7, 9), 0.5);
  f.address = AddressMode::Mirror;
  EXPECT_EQ(f.at(-1, -1), 0.0);
  EXPECT_EQ(f.at(3, 2), 0.5);
  EXPECT_EQ(f.at(4, 3), 0.1);
  EXPECT_EQ(f.at(6, 4), 0.0);
  EXPECT_EQ(f.at(-4, 0), 0.2);
}

TEST(StudyReference, SurfaceDepthBoxEdgesBelongToTheHigherTexel) {
  HeightField f = make_field(8, 8, 0.0);
  set(f, 4, 4, 0.75);
  EXPECT_EQ(surface_depth(f, 1.0, 0.55, 0.55, S::Box), 0.25);
  EXPECT_EQ(surface_depth(f, 1.0, 0.625, 0.55, S::Box), 0.25);  // right edge of the pillar
  EXPECT_EQ(surface_depth(f, 1.0, 0.625, 0.625, S::Box), 0.25);  // its far corner
  EXPECT_EQ(surface_depth(f, 1.0, 0.6251, 0.55, S::Box), 1.0);
  EXPECT_EQ(surface_depth(f, 1.0, 0.5625, 0.5625, S::Bilinear), 0.25);  // the pillar's texel centre
  EXPECT_EQ(surface_depth(f, 1.0, 0.5, 0.5625, S::Bilinear), 1.0 - 0.75 * 0.5);
}

TEST(StudyReference, FlatFieldHitsAtItsDepthExactly) {
  for (const S s : kSurfaces)
    for (const double h : {0.0, 0.3, 0.5, 0.77, 1.0})
      for (const glm::dvec3 d : {glm::dvec3(0, 0, 1), glm::dvec3(0.3, -0.2, 0.7), glm::dvec3(-2, 1.5, 0.1)}) {
        SCOPED_TRACE(name(s) + " h=" + std::to_string(h));
        const HeightField f = make_field(8, 8, h);
        const double D = 0.37, depth = D * (1.0 - h);
        const ReferenceHit r = cast(f, D, {0.3, 0.6, 0}, d, s);
        ASSERT_TRUE(r.hit);
        EXPECT_EQ(r.point.z, depth);
        // t = depth / d.z is one division for a box top hit; bilinear adds the rounding of the cell entry
        // ta and of depth - (ray depth at ta): a few ulps of t.
        EXPECT_NEAR(r.t, depth / d.z, 4 * kEps * r.t);
        EXPECT_EQ(r.inside_at_start, false);
      }
}

// A pillar at texel (4, 4) of an 8x8 map: u, v in [0.5, 0.625), height 0.75 (depth 0.25), floor at depth 1.
HeightField pillar(AddressMode mode = AddressMode::Wrap, double floor_height = 0.0) {
  HeightField f = make_field(8, 8, floor_height, mode);
  set(f, 4, 4, 0.75);
  return f;
}

TEST(StudyReference, BoxPillarWallsAndTop) {
  const HeightField f = pillar();
  // Steep from the left: reaches u = 0.5 at t = 0.25, depth 0.5 below the top: the wall.
  ReferenceHit r = cast(f, 1.0, {0.25, 0.56, 0}, {1, 0, 2}, S::Box);
  expect_hit(r, 0.25, {0.5, 0.56, 0.5});
  EXPECT_EQ(r.cells_visited, 3);
  // Starting closer: above the top at u = 0.5 (depth 0.1), then down onto it at depth 0.25.
  r = cast(f, 1.0, {0.45, 0.56, 0}, {1, 0, 2}, S::Box);
  expect_hit(r, 0.125, {0.575, 0.56, 0.25});
  EXPECT_EQ(r.point.z, 0.25);
  // From the right, going -u: the wall at u = 0.625 at t = 0.275, depth 0.275.
  expect_hit(cast(f, 1.0, {0.9, 0.56, 0}, {-1, 0, 1}, S::Box), 0.275, {0.625, 0.56, 0.275});
  // Going +v with a slant in u: at v = 0.5 (t = 0.2) at depth 0.2, above the top: onto it at depth 0.25; steeper,
  // at depth 0.3 there: the wall.
  expect_hit(cast(f, 1.0, {0.55, 0.3, 0}, {0.1, 1, 1}, S::Box), 0.25, {0.575, 0.55, 0.25});
  expect_hit(cast(f, 1.0, {0.55, 0.3, 0}, {0.1, 1, 1.5}, S::Box), 0.2, {0.57, 0.5, 0.3});
  // Shallow: passes over the pillar (depth 0.1625 at its far edge); with wrap it meets the next repeat's wall
  // at u = 1.5, depth 0.6; with clamp it reaches the floor at depth 1.
  expect_hit(cast(f, 1.0, {0.3, 0.56, 0}, {1, 0, 0.5}, S::Box), 1.2, {1.5, 0.56, 0.6});
  expect_hit(cast(pillar(AddressMode::Clamp), 1.0, {0.3, 0.56, 0}, {1, 0, 0.5}, S::Box), 2.0, {2.3, 0.56, 1.0});
}

TEST(StudyReference, BoxColumnsAreClosedACornerGrazeHits) {
  const HeightField f = pillar();
  // Diagonal through the corner (0.5, 0.625) between texels (3,4), (4,4), (3,5), (4,5): from (3,4) to (4,5), the
  // pillar (4,4) beside the diagonal is touched along its vertical edge at depth 0.5.
  ReferenceHit r = cast(f, 1.0, {0.25, 0.375, 0}, {1, 1, 2}, S::Box);
  expect_hit(r, 0.25, {0.5, 0.625, 0.5});
  // The same line shifted by a hair misses the edge and falls to the floor at depth 1, t = 0.5.
  r = cast(f, 1.0, {0.25 - 1e-9, 0.375 + 1e-9, 0}, {1, 1, 2}, S::Box);
  expect_hit(r, 0.5, {0.75 - 1e-9, 0.875 + 1e-9, 1.0});
}

TEST(StudyReference, BilinearPillar) {
  const HeightField f = pillar();
  // Along row v = 0.5625 (texel centres): between centres 3 and 4 the height is 0.75 fx with
  // fx = 8 u - 3.5, so the depth is 1 - 0.75 fx; the ray depth 2t with u = 0.25 + t meets it at t = 2.125 / 8.
  expect_hit(cast(f, 1.0, {0.25, 0.5625, 0}, {1, 0, 2}, S::Bilinear), 0.265625, {0.515625, 0.5625, 0.53125});
  // Straight down on the pillar's centre: its height.
  const ReferenceHit r = cast(f, 1.0, {0.5625, 0.5625, 0}, {0, 0, 3}, S::Bilinear);
  expect_hit(r, 0.25 / 3, {0.5625, 0.5625, 0.25});
  EXPECT_EQ(r.cells_visited, 1);
}

TEST(StudyReference, Ramps) {
  // Box: depths 1, 0.75, 0.5, 0.25 over u in quarters.
  const HeightField steps{4, 1, {0.0, 0.25, 0.5, 0.75}, AddressMode::Clamp};
  ReferenceHit r = cast(steps, 1.0, {0.05, 0.5, 0}, {1, 0, 1}, S::Box);  // onto the top of the third step
  expect_hit(r, 0.5, {0.55, 0.5, 0.5});
  EXPECT_EQ(r.cells_visited, 3);
  expect_hit(cast(steps, 1.0, {0.05, 0.5, 0}, {1, 0, 0.5}, S::Box), 0.7, {0.75, 0.5, 0.35});  // the fourth's wall

  // h_i = (i + 0.5) / 8 at the texel centres: the bilinear surface is h = u between the first and last centres,
  // depth 1 - u; the ray depth t with u = 0.1 + t meets it at t = 0.45. A v component changes nothing (all rows
  // equal) but makes the traversal step in v too.
  HeightField ramp = make_field(8, 8, 0.0);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) set(ramp, i, j, (i + 0.5) / 8);
  expect_hit(cast(ramp, 1.0, {0.1, 0.3, 0}, {1, 0, 1}, S::Bilinear), 0.45, {0.55, 0.3, 0.45});
  expect_hit(cast(ramp, 1.0, {0.1, 0.3, 0}, {1, 0.7, 1}, S::Bilinear), 0.45, {0.55, 0.615, 0.45});
  // Box on the same field: texel i at depth (7.5 - i) / 8; texel 4 (entered at t = 0.4, depth 0.4 < 0.4375)
  // is hit on top at t = 0.4375.
  expect_hit(cast(ramp, 1.0, {0.1, 0.3, 0}, {1, 0, 1}, S::Box), 0.4375, {0.5375, 0.3, 0.4375});
}

// Height 0.5 (depth 0.5) everywhere but a one-texel slit along v at u in [0.375, 0.5), height 0 (depth 1).
TEST(StudyReference, Slit) {
  HeightField f = make_field(8, 8, 0.5);
  for (int j = 0; j < 8; ++j) set(f, 3, j, 0.0);
  // Enters the slit at depth 0.5 (u = 0.4125) and reaches its bottom at u = 0.425.
  expect_hit(cast(f, 1.0, {0.4, 0.5, 0}, {0.1, 0, 4}, S::Box), 0.25, {0.425, 0.5, 1.0});
  // Enters it (u = 0.425 at depth 0.5) and meets its far wall at u = 0.5, depth 0.8.
  expect_hit(cast(f, 1.0, {0.3, 0.5, 0}, {1, 0, 4}, S::Box), 0.2, {0.5, 0.5, 0.8});
  // Lands before it, on texel 2.
  expect_hit(cast(f, 1.0, {0.2, 0.5, 0}, {1, 0, 4}, S::Box), 0.125, {0.325, 0.5, 0.5});
  // Bilinear: a V groove with its bottom at the slit's centre u = 0.4375.
  expect_hit(cast(f, 1.0, {0.4375, 0.5, 0}, {0, 0, 1}, S::Bilinear), 1.0, {0.4375, 0.5, 1.0});
  // A quarter texel from the bottom: height 0.5 * 0.25, depth 0.875.
  expect_hit(cast(f, 1.0, {0.40625, 0.5, 0}, {0, 0, 1}, S::Bilinear), 0.875, {0.40625, 0.5, 0.875});
}

// Height (i + j) mod 2 on an 8x8 map: the finest checkerboard, depth scale 1.
TEST(StudyReference, Checkerboard) {
  HeightField f = make_field(8, 8, 0.0);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) set(f, i, j, double((i + j) % 2));
  // Box: from the middle of a low texel, the next texel's wall at once; on a high texel, t = 0.
  expect_hit(cast(f, 1.0, {0.0625, 0.0625, 0}, {1, 0, 1}, S::Box), 0.0625, {0.125, 0.0625, 0.0625});
  ReferenceHit r = cast(f, 1.0, {0.1875, 0.0625, 0}, {1, 0, 1}, S::Box);
  EXPECT_TRUE(r.hit && r.t == 0 && !r.inside_at_start);
  // Diagonally through the corner to the next low texel, touching the two high ones beside it.
  expect_hit(cast(f, 1.0, {0.0625, 0.0625, 0}, {1, 1, 1}, S::Box), 0.0625, {0.125, 0.125, 0.0625});

  // Bilinear, from a low texel centre along u: height 8t, depth 1 - 8t = t at t = 1/9.
  expect_hit(cast(f, 1.0, {0.0625, 0.0625, 0}, {1, 0, 1}, S::Bilinear), 1.0 / 9,
             {0.0625 + 1.0 / 9, 0.0625, 1.0 / 9});
  // Bilinear along the diagonal valley, through cell corners: in each cell the height is 16s - 128s^2
  // (s = t - k/8), so ray depth - surface depth = t - 1 + 16s - 128s^2. No root in cells 0-3; in cell 4
  // 128s^2 - 17s + 0.5 = 0, s = (17 - sqrt 33) / 256.
  const double t = 0.5 + (17 - std::sqrt(33.0)) / 256;
  r = cast(f, 1.0, {0.0625, 0.0625, 0}, {1, 1, 1}, S::Bilinear);
  expect_hit(r, t, {0.0625 + t, 0.0625 + t, t});
  EXPECT_EQ(r.cells_visited, 5);
}

TEST(StudyReference, RaysStartingInsideOrOnTheSurface) {
  for (const S s : kSurfaces) {
    SCOPED_TRACE(name(s));
    const HeightField f = make_field(4, 4, 0.5);
    for (const glm::dvec3 d : {glm::dvec3(1, 0, 1), glm::dvec3(0, 0, -1), glm::dvec3(1, 1, 0)}) {
      ReferenceHit r = cast(f, 1.0, {0.3, 0.3, 0.7}, d, s);
      EXPECT_TRUE(r.hit && r.inside_at_start);
      EXPECT_EQ(r.t, 0);
      EXPECT_EQ(r.point, glm::dvec3(0.3, 0.3, 0.7));
      EXPECT_EQ(r.cells_visited, 0);
      r = cast(f, 1.0, {0.3, 0.3, 1.5}, d, s);  // below the bottom
      EXPECT_TRUE(r.hit && r.inside_at_start);
      r = cast(f, 1.0, {0.3, 0.3, 0.5}, d, s);  // on the surface: a hit at t = 0, not inside
      EXPECT_TRUE(r.hit && !r.inside_at_start && r.t == 0);
    }
  }
}

TEST(StudyReference, ParallelAndRisingRays) {
  const HeightField f = pillar(AddressMode::Wrap, 0.5);  // floor at depth 0.5, the pillar's top at 0.25
  // At depth 0.3, along row 4: the pillar's wall at u = 0.5.
  expect_hit(cast(f, 1.0, {0.1, 0.56, 0.3}, {1, 0, 0}, S::Box), 0.4, {0.5, 0.56, 0.3});
  // Bilinear along the centres' row: depth 0.5 - 0.25 fx between centres 3 and 4 is 0.3 at fx = 0.8.
  expect_hit(cast(f, 1.0, {0.1, 0.5625, 0.3}, {1, 0, 0}, S::Bilinear), 0.4375, {0.5375, 0.5625, 0.3});
  for (const S s : kSurfaces) {
    SCOPED_TRACE(name(s));
    // Above every texel but below the polygon: runs until the cap.
    ReferenceHit r = cast(f, 1.0, {0.1, 0.56, 0.2}, {1, 0.3, 0}, s, 1000);
    EXPECT_FALSE(r.hit);
    EXPECT_EQ(r.cells_visited, 1000);
    // Above the polygon: no cell is visited.
    r = cast(f, 1.0, {0.1, 0.56, -0.1}, {1, 0.3, 0}, s);
    EXPECT_FALSE(r.hit);
    EXPECT_EQ(r.cells_visited, 0);
    // Straight up or a vertical ray standing still: nothing to meet.
    EXPECT_FALSE(cast(f, 1.0, {0.1, 0.1, 0.3}, {0, 0, -1}, s).hit);
    EXPECT_FALSE(cast(f, 1.0, {0.1, 0.1, 0.3}, {0, 0, 0}, s).hit);
    // Rising out of the floor level, away from everything: misses once above depth 0.
    r = cast(f, 1.0, {0.1, 0.1, 0.45}, {1, 0, -1}, s);
    EXPECT_FALSE(r.hit);
  }
  // Rising towards the pillar from depth 0.4: its wall at u = 0.5, at depth 0.3.
  expect_hit(cast(f, 1.0, {0.3, 0.56, 0.4}, {1, 0, -0.5}, S::Box), 0.2, {0.5, 0.56, 0.3});
}

TEST(StudyReference, OneByOneMaps) {
  for (const AddressMode m : kModes)
    for (const S s : kSurfaces) {
      SCOPED_TRACE(name(s));
      const HeightField f = make_field(1, 1, 0.3, m);
      const ReferenceHit r = cast(f, 1.0, {0.5, 0.5, 0}, {1, 0.5, 1}, s);
      expect_hit(r, 0.7, {1.2, 0.85, 0.7});
      EXPECT_EQ(r.point.z, 1.0 * (1.0 - 0.3));
      EXPECT_EQ(r.cells_visited, s == S::Box ? 2 : 1);  // box: u crosses 1 at t = 0.5; bilinear: u crosses 1.5 after
    }
}

TEST(StudyReference, AllZeroAllOneAndDepthScales) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  HeightField random = make_field(8, 8, 0.0);
  for (double& h : random.h) h = unit(rng);
  for (const S s : kSurfaces) {
    SCOPED_TRACE(name(s));
    ReferenceHit r = cast(make_field(8, 8, 0.0), 0.2, {0.3, 0.4, 0}, {0.5, 0.5, 1}, s);
    expect_hit(r, 0.2, {0.4, 0.5, 0.2});
    EXPECT_EQ(r.point.z, 0.2);
    r = cast(make_field(8, 8, 1.0), 0.2, {0.3, 0.4, 0}, {0.5, 0.5, 1}, s);
    EXPECT_TRUE(r.hit && r.t == 0 && !r.inside_at_start);
    // Depth scale 0: the surface is the polygon, every ray starting on it hits at once.
    for (const glm::dvec3 d : {glm::dvec3(0.5, 0.5, 1), glm::dvec3(1, 0, 0), glm::dvec3(1, 0, -1)}) {
      r = cast(random, 0.0, {0.3, 0.4, 0}, d, s);
      EXPECT_TRUE(r.hit && r.t == 0 && !r.inside_at_start);
      EXPECT_EQ(r.point, glm::dvec3(0.3, 0.4, 0));
    }
    // Depth scale 100 on a flat field at 0.5: depth 50, reached after 400 texels in u.
    r = cast(make_field(8, 8, 0.5), 100.0, {0.3, 0.4, 0}, {1, 0.3, 1}, s);
    expect_hit(r, 50, {50.3, 15.4, 50}, 1e-12);  // 50 = 400 texels: a few roundings of numbers of order 50
    EXPECT_GT(r.cells_visited, 400);
  }
}

TEST(StudyReference, GrazingOneDegree) {
  const glm::dvec3 d(std::sqrt(0.5), std::sqrt(0.5), kTan1Deg);  // |d.xy| = 1, 1 degree below the polygon
  for (const S s : kSurfaces) {
    SCOPED_TRACE(name(s));
    // Flat at depth 0.05: t = 0.05 / tan(1 deg) = 2.86, across 2 x 46 texels of a 16x16 map.
    const HeightField f = make_field(16, 16, 0.5);
    const ReferenceHit r = cast(f, 0.1, {0.3, 0.4, 0}, d, s);
    ASSERT_TRUE(r.hit);
    EXPECT_EQ(r.point.z, 0.05);
    EXPECT_NEAR(r.t, 0.05 / kTan1Deg, 8 * kEps * r.t);  // as the flat test, a few more roundings of ta
  }
  // Box, pillar with depth scale 0.1 (top at depth 0.025, floor at 0.1), along row 4 from u = -1.5: over the
  // repeat at u = -0.5 at depth <= 0.0196, into the wall at u = 0.5 at depth 2 tan 1 deg = 0.035.
  expect_hit(cast(pillar(), 0.1, {-1.5, 0.56, 0}, {1, 0, kTan1Deg}, S::Box), 2.0, {0.5, 0.56, 2 * kTan1Deg});
}

TEST(StudyReference, AddressModesAtTheEdges) {
  // Depths 0.9, 0.7, 0.4, 0.05 over u in quarters; the ray leaves the map at u = 0 going -u.
  HeightField f{4, 1, {0.1, 0.3, 0.6, 0.95}, AddressMode::Wrap};
  const glm::dvec3 o(0.2, 0.5, 0), d(-1, 0, 0.8);
  for (const S s : kSurfaces) EXPECT_EQ(surface_depth(f, 1.0, 0.125, 0.5, s), 1.0 - 0.1);
  // Wrap: texel 3 (depth 0.05) lies beyond u = 0: its wall, depth 0.16.
  expect_hit(cast(f, 1.0, o, d, S::Box), 0.2, {0.0, 0.5, 0.16});
  EXPECT_NEAR(surface_depth(f, 1.0, 0.0, 0.5, S::Bilinear), 1 - (0.1 + 0.95) / 2, kHand);
  EXPECT_EQ(surface_depth(f, 1.0, -0.125, 0.5, S::Bilinear), 1 - 0.95);
  EXPECT_EQ(surface_depth(f, 1.0, -0.375, 0.5, S::Bilinear), 1 - 0.6);
  EXPECT_EQ(surface_depth(f, 1.0, 1.125, 0.5, S::Bilinear), 1 - 0.1);
  // Clamp: texel 0 forever: its top at depth 0.9, t = 1.125.
  f.address = AddressMode::Clamp;
  expect_hit(cast(f, 1.0, o, d, S::Box), 1.125, {-0.925, 0.5, 0.9});
  expect_hit(cast(f, 1.0, o, d, S::Bilinear), 1.125, {-0.925, 0.5, 0.9});
  EXPECT_EQ(surface_depth(f, 1.0, 0.0, 0.5, S::Bilinear), 1 - 0.1);
  EXPECT_EQ(surface_depth(f, 1.0, -0.375, 0.5, S::Bilinear), 1 - 0.1);
  EXPECT_EQ(surface_depth(f, 1.0, 1.125, 0.5, S::Bilinear), 1 - 0.95);
  // Mirror: texels 0, 1, 2 again beyond u = 0; texel 2 (depth 0.4) entered at u = -0.5 at depth 0.56.
  f.address = AddressMode::Mirror;
  expect_hit(cast(f, 1.0, o, d, S::Box), 0.7, {-0.5, 0.5, 0.56});
  EXPECT_EQ(surface_depth(f, 1.0, 0.0, 0.5, S::Bilinear), 1 - 0.1);
  EXPECT_EQ(surface_depth(f, 1.0, -0.375, 0.5, S::Bilinear), 1 - 0.3);
  EXPECT_EQ(surface_depth(f, 1.0, 1.125, 0.5, S::Bilinear), 1 - 0.95);
  // Bilinear mirror: flat depth 0.9 on [-0.125, 0.125]; on [-0.375, -0.125] towards texel 1, depth
  // 0.9 - 0.8 (-0.125 - u) = 1.16 - 0.8 t (u = 0.2 - t), reached at t = 0.725, past the cell; on [-0.625, -0.375]
  // towards texel 2, depth 0.7 - 1.2 (-0.375 - u) = 1.39 - 1.2 t = 0.8 t at t = 0.695, u = -0.495.
  expect_hit(cast(f, 1.0, o, d, S::Bilinear), 0.695, {-0.495, 0.5, 0.556});
}

std::mt19937 random_field(HeightField& f, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (double& h : f.h) h = unit(rng);
  return rng;
}

// A random direction going down at an elevation in [min_deg, 80] degrees, |d.xy| = 1.
glm::dvec3 random_direction(std::mt19937& rng, double min_deg) {
  std::uniform_real_distribution<double> angle(0.0, 2 * 3.14159265358979323846), elev(min_deg, 80.0);
  const double a = angle(rng), e = elev(rng) * 3.14159265358979323846 / 180;
  return {std::cos(a), std::sin(a), std::tan(e)};
}

TEST(StudyReference, LargeUvOffsetsShiftTheHit) {
  // Shifting changes the rounding, not the answer: origin u + 1e4 is stored to half an ulp of 1e4 (9e-13), the
  // grid coordinate (u + 1e4) W (W = 16) to half an ulp of 1.6e5 (9e-13 in u). A wall crossing moves by that over
  // |d.u|; a bilinear crossing by that times the patch slope (up to depth_scale x W = 3.2 here) over the difference
  // of ray and patch slopes along the ray, which is unbounded only for tangent hits. Seen over these 4000 pairs:
  // 1.7e-10 relative at worst (a bilinear hit at t = 0.3 with an amplification of ~50); 1e-9 leaves a factor 6.
  HeightField f = make_field(16, 16, 0.0);
  std::mt19937 rng = random_field(f, 11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const glm::dvec3 shifts[] = {{1e4, 0, 0}, {-1e4, 1e4, 0}, {1e4, -1e4, 0}, {-1e4, -1e4, 0}};
  double worst = 0;
  for (const S s : kSurfaces)
    for (int n = 0; n < 500; ++n) {
      const glm::dvec3 o(unit(rng), unit(rng), 0), d = random_direction(rng, 5.0);
      const ReferenceHit r0 = cast(f, 0.2, o, d, s);
      ASSERT_TRUE(r0.hit);
      for (const glm::dvec3& shift : shifts) {
        const ReferenceHit r = cast(f, 0.2, o + shift, d, s);
        ASSERT_TRUE(r.hit);
        const double rel = std::abs(r.t - r0.t) / r0.t;
        worst = std::max(worst, rel);
        EXPECT_LE(rel, 1e-9) << name(s) << " ray " << n;
        EXPECT_NEAR(r.point.x - shift.x, r0.point.x, 1e-9);
        EXPECT_NEAR(r.point.y - shift.y, r0.point.y, 1e-9);
        EXPECT_NEAR(r.point.z, r0.point.z, 1e-9);
      }
    }
  RecordProperty("worst_relative_t", sci(worst));
}

// The first crossing by dense sampling: the first of n steps from t = 0 to the bottom (or back to depth 0) that
// lies at or below the surface, refined by bisection to the last bit. -1 when no sample is below.
struct Sampled {
  double first_below = -1;  // the sample
  double crossing = -1;     // the bisected crossing before it
};

Sampled sample_ray(const HeightField& f, double D, glm::dvec3 o, glm::dvec3 d, S s, int n) {
  const auto below = [&](double t) {
    const glm::dvec3 p = o + t * d;
    return p.z >= surface_depth(f, D, p.x, p.y, s);
  };
  const double t_end = d.z > 0 ? (D - o.z) / d.z : -o.z / d.z;
  Sampled out;
  for (int k = 1; k <= n; ++k) {
    const double t = t_end * k / n;
    if (!below(t)) continue;
    double lo = t_end * (k - 1) / n, hi = t;
    while (true) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      (below(mid) ? hi : lo) = mid;
    }
    out.first_below = t;
    out.crossing = hi;
    return out;
  }
  return out;
}

TEST(StudyReference, BruteForceOnRandomFields) {
  // Box and bilinear hits are fp64 solutions of one linear or quadratic equation each, a few ulps of t for
  // well-conditioned crossings; the bisection pins the sampled crossing to an ulp. Only near-tangent crossings
  // amplify rounding (by patch slope over slope difference, as in LargeUvOffsetsShiftTheHit); 1e-9 absolute
  // allows an amplification of ~1e6 over an ulp of t ~ 1. Seen: 7e-15 at worst (t up to ~30 with depth scale 100).
  constexpr int kSamples = 1000000;
  constexpr double kAgree = 1e-9;
  double worst = 0;
  int rising_hits = 0;
  for (const int size : {8, 16})
    for (const S s : kSurfaces) {
      HeightField f = make_field(size, size, 0.0);
      std::mt19937 rng = random_field(f, unsigned(size) * 31 + (s == S::Box ? 0 : 1));
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      for (int n = 0; n < 64; ++n) {
        f.address = kModes[n % 3];
        const double D = std::array{1.0, 0.3, 0.05, 100.0}[std::size_t(n % 4)];
        glm::dvec3 o(unit(rng) * 2 - 0.5, unit(rng) * 2 - 0.5, 0), d = random_direction(rng, n % 6 == 5 ? 1.0 : 5.0);
        if (n % 8 == 7) {  // rising from just above the surface: may meet a box wall or a bilinear slope, or miss
          o.z = 0.9 * surface_depth(f, D, o.x, o.y, s);
          d.z = -d.z;
        }
        const ReferenceHit r = cast(f, D, o, d, s);
        const Sampled sm = sample_ray(f, D, o, d, s, kSamples);
        SCOPED_TRACE(name(s) + " size " + std::to_string(size) + " ray " + std::to_string(n));
        if (sm.first_below < 0) {
          // Nothing sampled below: a rising ray leaving, or a graze thinner than a step (then the reference hit
          // must be on the surface).
          if (r.hit) {
            EXPECT_NEAR(r.point.z, surface_depth(f, D, r.point.x, r.point.y, s), 1e-12);
          }
          continue;
        }
        ASSERT_TRUE(r.hit);
        if (d.z < 0) ++rising_hits;
        EXPECT_LE(r.t, sm.first_below);
        EXPECT_NEAR(r.t, sm.crossing, kAgree);
        worst = std::max(worst, std::abs(r.t - sm.crossing));
      }
    }
  EXPECT_GT(rising_hits, 0);
  RecordProperty("worst_abs_t", sci(worst));
}

TEST(StudyReference, Map4096Squared) {
  // Rows equal, h_i = (i + 0.5) / W: bilinear depth D (1 - u) between the first and last centres.
  constexpr int W = 4096;
  HeightField f{W, W, ZeroedBuffer<double>(std::size_t(W) * W), AddressMode::Wrap};
  for (int j = 0; j < W; ++j)
    for (int i = 0; i < W; ++i) f.h[std::size_t(j) * W + i] = (i + 0.5) / W;
  const double D = 0.05, u0 = 0.01;
  const glm::dvec3 d(1, 0.25, kTan1Deg);
  for (const double shift : {0.0, 1e4}) {
    const glm::dvec3 o(u0 + shift, 0.3 - shift, 0);
    // Bilinear: t d.z = D (1 - u0 - t): across ~3000 cells in u.
    const double t = D * (1 - u0) / (d.z + D);
    ReferenceHit r = cast(f, D, o, d, S::Bilinear);
    expect_hit(r, t, {o.x + t, o.y + 0.25 * t, t * d.z}, 1e-9);  // as in LargeUvOffsetsShiftTheHit
    EXPECT_GT(r.cells_visited, 3000);
    // Box: texel i at depth D (1 - (i + 0.5) / W), walked in 1D independently of the traversal.
    double tb = 0, zb = 0;
    for (int i = int(u0 * W);; ++i) {
      const double depth = D * (1 - (i + 0.5) / W);
      const double enter = std::max(0.0, double(i) / W - u0), exit = (i + 1.0) / W - u0;
      if (enter * d.z >= depth) {  // the wall
        tb = enter, zb = enter * d.z;
        break;
      }
      if (depth / d.z <= exit) {  // the top
        tb = depth / d.z, zb = depth;
        break;
      }
    }
    r = cast(f, D, o, d, S::Box);
    expect_hit(r, tb, {o.x + tb, o.y + 0.25 * tb, zb}, 1e-9);
  }
}

}  // namespace
}  // namespace qdmr
