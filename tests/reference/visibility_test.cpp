// The exact light visibility (light_visibility, the hard self-shadow's reference) against closed forms: the
// shadow of a step, the column a pillar casts, a spherical cap bracketed by two balls; and the conventions at
// the start texel, on walls, edges and corners.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "qdmr/reference/reference.hpp"
#include "reference/shadow_shapes.hpp"

namespace qdmr::test {
namespace {

struct Light {
  double elevation_deg, du, dv;  // (du, dv): UV per unit of depth climbed
};

std::vector<Light> lights(std::initializer_list<double> elevations, int azimuths) {
  std::vector<Light> out;
  for (double e : elevations)
    for (int k = 0; k < azimuths; ++k) {
      const double az = 2.0 * std::numbers::pi * (k + 0.25) / azimuths;  // never exactly along an axis
      const double reach = 1.0 / std::tan(e * std::numbers::pi / 180.0);
      out.push_back({e, reach * std::cos(az), reach * std::sin(az)});
    }
  return out;
}

bool visible(const HeightField& f, double ds, double x, double y, double depth, double du, double dv) {
  return light_visibility(f, ds, {x / f.width, y / f.height, depth}, {du, dv}).visible;
}

// A step of height dh = high - low casts a shadow of length dh * ds * |du| (UV) across the wall along x:
// low-floor points closer to a wall (x = 32 ahead for du > 0, x = 0 behind for du < 0) are shadowed.
TEST(VisibilityReference, StepCastsItsClosedFormShadow) {
  const double low = 0.2, high = 0.9, ds = 0.1;
  const HeightField f = step_field(64, low, high);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int shadowed = 0, lit = 0, ties = 0;
  for (const Light& l : lights({80, 60, 45, 30, 20, 10, 5}, 24))
    for (int n = 0; n < 40; ++n) {
      const double u = 0.5 * unit(rng), v = unit(rng);  // on the low floor
      const double to_wall = l.du > 0 ? 0.5 - u : u;
      const double shadow = (high - low) * ds * std::abs(l.du);
      // 1e-12 UV: a few roundings of order-1 numbers; closer than that the comparison is a coin toss.
      if (std::abs(to_wall - shadow) < 1e-12) {
        ++ties;
        continue;
      }
      const bool expect = to_wall >= shadow;
      EXPECT_EQ(visible(f, ds, u * 64, v * 64, ds * (1 - low), l.du, l.dv), expect)
          << "u " << u << " v " << v << " elevation " << l.elevation_deg << " du " << l.du;
      (expect ? lit : shadowed)++;
      // The plateau is never shadowed: nothing is higher.
      EXPECT_TRUE(visible(f, ds, (0.5 + 0.5 * unit(rng)) * 64, v * 64, ds * (1 - high), l.du, l.dv));
    }
  EXPECT_EQ(ties, 0);
  EXPECT_GT(shadowed, 500);  // both outcomes well represented (of 6720 cases)
  EXPECT_GT(lit, 500);
}

// A pillar shadows a floor point iff the light ray passes through the pillar's open square while below its top:
// the slab test on the square (and its wrapped copies), entry depth against the top.
TEST(VisibilityReference, PillarShadowIsTheRaysPassageThroughItsColumn) {
  const int size = 32, p = 16;
  const double hp = 0.7, ds = 0.1, floor_depth = ds;
  const HeightField f = pillar_field(size, p, hp);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> near(8.0, 24.0);
  int shadowed = 0, lit = 0, ties = 0;
  // Elevations >= 10 degrees: the ray reaches the pillar's top within 0.7 * 3.2 * cot(10) = 12.7 texels.
  for (const Light& l : lights({80, 60, 45, 30, 20, 10}, 24))
    for (int n = 0; n < 60; ++n) {
      const double x0 = near(rng), y0 = near(rng);
      if (std::floor(x0) == p && std::floor(y0) == p) continue;  // the start texel itself never shadows
      const double dx = l.du * size, dy = l.dv * size;  // texels per unit of depth
      bool expect = true, tie = false;
      for (int ox = -1; ox <= 1; ++ox)
        for (int oy = -1; oy <= 1; ++oy) {
          const double lo_x = p + ox * size, lo_y = p + oy * size;
          const double ax = (lo_x - x0) / dx, bx = (lo_x + 1 - x0) / dx, ay = (lo_y - y0) / dy, by = (lo_y + 1 - y0) / dy;
          const double c_in = std::max({std::min(ax, bx), std::min(ay, by), 0.0});
          const double c_out = std::min(std::max(ax, bx), std::max(ay, by));
          const double rise = floor_depth - c_in - ds * (1 - hp);  // > 0: below the top where it enters
          // 1e-12: roundings of order-1 values; closer is a grazing contact decided by rounding.
          if (std::abs(c_out - c_in) < 1e-12 || std::abs(rise) < 1e-12) tie = true;
          if (c_in < c_out && rise > 0) expect = false;
        }
      if (tie) {
        ++ties;
        continue;
      }
      EXPECT_EQ(visible(f, ds, x0, y0, floor_depth, l.du, l.dv), expect) << x0 << " " << y0 << " el " << l.elevation_deg;
      (expect ? lit : shadowed)++;
    }
  EXPECT_EQ(ties, 0);
  EXPECT_GT(shadowed, 100);  // of 8640 cases; the pillar's shadow is a few texels long
  EXPECT_GT(lit, 1000);
}

// The box cap lies between the balls of radius R -+ sqrt(2)/2 (shadow_shapes.hpp): a ray through the inner
// ball is shadowed, one missing the outer ball lit, whatever the rasterisation; in between it is undecided.
TEST(VisibilityReference, SphericalCapBetweenTheInnerAndOuterBall) {
  const Cap cap;
  const HeightField f = cap.field();
  const double half_diagonal = std::sqrt(0.5) + 1e-9;  // plus a rounding margin on distances of order 10
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> anywhere(0.0, cap.size);
  int shadowed = 0, lit = 0, undecided = 0;
  for (const Light& l : lights({80, 60, 45, 30, 20, 10, 5}, 16))
    for (int n = 0; n < 60; ++n) {
      const double x0 = anywhere(rng), y0 = anywhere(rng);
      if (f.at(std::int64_t(x0), std::int64_t(y0)) != 0.0) continue;  // floor starts only
      // In texel units the climb direction is (du, dv) (UV per UV of depth); the ray may cross wrapped copies.
      bool inner = false, outer = false;
      for (int ox = -4; ox <= 4; ++ox)
        for (int oy = -4; oy <= 4; ++oy) {
          inner = inner || cap.ray_meets_ball(x0 - ox * cap.size, y0 - oy * cap.size, l.du, l.dv, cap.radius - half_diagonal);
          outer = outer || cap.ray_meets_ball(x0 - ox * cap.size, y0 - oy * cap.size, l.du, l.dv, cap.radius + half_diagonal);
        }
      if (inner != outer) {
        ++undecided;
        continue;
      }
      EXPECT_EQ(visible(f, cap.depth_scale, x0, y0, cap.floor_depth() / cap.size, l.du, l.dv), !inner)
          << x0 << " " << y0 << " el " << l.elevation_deg;
      (inner ? shadowed : lit)++;
    }
  EXPECT_GT(shadowed, 500);  // of ~5000 floor cases, undecided ones (a ~1.4 texel band) set aside
  EXPECT_GT(lit, 500);
  EXPECT_LT(undecided, shadowed + lit);
}

// Hand cases on a 4x4 map, depth scale 1 (depth in UV; one texel = 0.25): the pillar (2, 2) tops out at depth
// 0.5 (h = 0.5) or 0 (h = 1); the floor is at depth 1. Positions below are in texels.
TEST(VisibilityReference, ConventionsAtTheStartWallsEdgesAndCorners) {
  const HeightField half = pillar_field(4, 2, 0.5), tall = pillar_field(4, 2, 1.0);
  const double eps = std::ldexp(1.0, -20);
  // Entering the pillar exactly at its top edge (c = 0.5, depth 0.5): grazing, lit; a hair closer: shadowed.
  EXPECT_TRUE(visible(half, 1.0, 1.5, 2.5, 1.0, 0.25, 0.0));
  EXPECT_FALSE(visible(half, 1.0, 1.5 + eps, 2.5, 1.0, 0.25, 0.0));
  // Through the pillar's corner (3, 2) diagonally: touching a corner is lit; a hair to the side enters.
  EXPECT_TRUE(visible(tall, 1.0, 2.5, 1.5, 1.0, 0.25, 0.25));
  EXPECT_FALSE(visible(tall, 1.0, 2.5 - eps, 1.5, 1.0, 0.25, 0.25));
  // Along the pillar's wall x = 2: lit; inside its column x = 2.5 from below: shadowed.
  EXPECT_TRUE(visible(tall, 1.0, 2.0, 1.5, 1.0, 0.0, 0.25));
  EXPECT_FALSE(visible(tall, 1.0, 2.5, 1.5, 1.0, 0.0, 0.25));
  // A start on the pillar's wall x = 2 at floor depth: the light beyond the wall (+x) is blocked by the pillar;
  // from the other side (-x) the wall is lit. On the far wall x = 3 the other way round.
  EXPECT_FALSE(visible(tall, 1.0, 2.0, 2.5, 1.0, 0.1, 0.0));
  EXPECT_TRUE(visible(tall, 1.0, 2.0, 2.5, 1.0, -0.1, 0.0));
  EXPECT_TRUE(visible(tall, 1.0, 3.0, 2.5, 1.0, 0.1, 0.0));
  EXPECT_FALSE(visible(tall, 1.0, 3.0, 2.5, 1.0, -0.1, 0.0));
  // The start texel never shadows its point, even one below its top (a filtered or rounded hit).
  EXPECT_TRUE(visible(tall, 1.0, 2.5, 2.5, 0.5, 0.1, 0.05));
  // On the pillar's top, anything is lit; so is a light straight overhead.
  EXPECT_TRUE(visible(half, 1.0, 2.5, 2.5, 0.5, -0.3, 0.7));
  EXPECT_TRUE(visible(tall, 1.0, 1.5, 1.5, 1.0, 0.0, 0.0));
  // A flat map shadows nothing.
  const HeightField flat = flat_field(4, 0.3);
  for (double du : {-3.0, -0.1, 0.0, 0.2, 5.0}) EXPECT_TRUE(visible(flat, 1.0, 1.3, 2.7, 0.7, du, 0.4));
}

TEST(VisibilityReference, MaxCellsStopsTheWalkAsLit) {
  // A light at 0.01 rad over a flat low floor: the walk crosses ~100 * 32 texels before reaching depth 0.
  const HeightField f = flat_field(32, 0.0);
  const LightVisibility r = light_visibility(f, 1.0, {0.3, 0.4, 1.0}, {100.0, 1.0}, 50);
  EXPECT_TRUE(r.visible);
  EXPECT_TRUE(r.capped);
  EXPECT_EQ(r.cells_visited, 50);
}

}  // namespace
}  // namespace qdmr::test
