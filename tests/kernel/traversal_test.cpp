// The max-quadtree cell stepping (kernel/traversal.hpp) has a shortcut for rays that GridRay calls regular (no lane
// parallel to an axis, no infinite reciprocal, finite origin): it must move every lane exactly as the general
// rules do, including rays standing exactly on a wall or a mid line, where the two sides of a comparison meet.
// Compiled as the AVX2 kernel here and as the AVX-512 one in qdmr_avx512_tests (their masks are their own).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>

#include "kernel/traversal.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;
using simd::kLanes;

struct Lanes {
  alignas(64) float x0[kLanes], y0[kLanes], dx[kLanes], dy[kLanes], t[kLanes];
  alignas(64) std::int32_t level[kLanes], cx[kLanes], cy[kLanes];
};

GridRay grid_ray(const Lanes& l) {
  return GridRay(Float::load_aligned(l.x0), Float::load_aligned(l.y0), Float::load_aligned(l.dx),
                 Float::load_aligned(l.dy));
}

// Random lanes: origins anywhere in a 64-texel map, directions of any sign and size (some tiny, some huge), a
// cell of a random level that holds the origin, and t at one of the crossings the stepping compares with (exactly,
// or one float either side), or anywhere.
Lanes random_lanes(std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 5);
  Lanes l;
  for (int i = 0; i < kLanes; ++i) {
    l.level[i] = pick(rng);
    const float cell = float(1 << l.level[i]);
    // Origins on exact texel and cell boundaries too: where a crossing is 0.
    l.x0[i] = pick(rng) == 0 ? cell * float(int(unit(rng) * 64.0f / cell)) : unit(rng) * 64.0f;
    l.y0[i] = pick(rng) == 0 ? float(int(unit(rng) * 64.0f)) : unit(rng) * 64.0f;
    const auto direction = [&] {
      const float magnitude = std::ldexp(0.5f + unit(rng), int(unit(rng) * 40.0f) - 20);  // 2^-20 .. 2^20
      return unit(rng) < 0.5f ? -magnitude : magnitude;
    };
    l.dx[i] = direction();
    l.dy[i] = direction();
    l.cx[i] = int(std::floor(l.x0[i] / cell));
    l.cy[i] = int(std::floor(l.y0[i] / cell));
    const float child = cell * 0.5f;
    const float mid_x = float(2 * l.cx[i] + 1) * child, mid_y = float(2 * l.cy[i] + 1) * child;
    const float at[] = {(mid_x - l.x0[i]) * (1.0f / l.dx[i]), (mid_y - l.y0[i]) * (1.0f / l.dy[i]),
                        (float(l.cx[i] + 1) * cell - l.x0[i]) * (1.0f / l.dx[i]), 0.0f, unit(rng) * 100.0f};
    const float base = at[pick(rng) % 5];
    const int side = pick(rng) % 3;
    l.t[i] = side == 0 ? base : std::nextafter(base, side == 1 ? INFINITY : -INFINITY);
  }
  return l;
}

template <bool Fp64>
void expect_same_steps(const Lanes& l, const char* what) {
  const GridRay regular = grid_ray(l);
  ASSERT_TRUE(regular.regular) << what;
  GridRay general = regular;
  general.regular = false;  // the same ray through the general rules
  const Int level0 = Int::load_aligned(l.level), cx0 = Int::load_aligned(l.cx), cy0 = Int::load_aligned(l.cy);
  const Float t = Float::load_aligned(l.t);

  Float tx_r, ty_r, tx_g, ty_g;
  exit_walls<Fp64>(level0, cx0, cy0, regular, tx_r, ty_r);
  exit_walls<Fp64>(level0, cx0, cy0, general, tx_g, ty_g);
  alignas(64) float a[kLanes], b[kLanes], c[kLanes], d[kLanes];
  tx_r.store_aligned(a);
  tx_g.store_aligned(b);
  ty_r.store_aligned(c);
  ty_g.store_aligned(d);
  for (int i = 0; i < kLanes; ++i) {
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a[i]), std::bit_cast<std::uint32_t>(b[i])) << what << " tx lane " << i;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(c[i]), std::bit_cast<std::uint32_t>(d[i])) << what << " ty lane " << i;
  }

  const simd::IntMask descend = level0 > Int(0);
  Int level_r = level0, cx_r = cx0, cy_r = cy0, level_g = level0, cx_g = cx0, cy_g = cy0;
  descend_to_child<Fp64>(descend, t, regular, level_r, cx_r, cy_r);
  descend_to_child<Fp64>(descend, t, general, level_g, cx_g, cy_g);
  alignas(64) std::int32_t r[3][kLanes], g[3][kLanes];
  level_r.store_aligned(r[0]);
  cx_r.store_aligned(r[1]);
  cy_r.store_aligned(r[2]);
  level_g.store_aligned(g[0]);
  cx_g.store_aligned(g[1]);
  cy_g.store_aligned(g[2]);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < kLanes; ++i)
      EXPECT_EQ(r[k][i], g[k][i]) << what << (k == 0 ? " level" : k == 1 ? " cx" : " cy") << " lane " << i
                                  << ": t " << l.t[i] << " x0 " << l.x0[i] << " dx " << l.dx[i] << " cell ("
                                  << l.cx[i] << ", " << l.cy[i] << ") of level " << l.level[i];
}

TEST(Traversal, RegularRaysStepAsTheGeneralRulesDo) {
  std::mt19937 rng(20261129);
  for (int round = 0; round < 4000; ++round) {
    const Lanes l = random_lanes(rng);
    expect_same_steps<false>(l, "fp32");
    expect_same_steps<true>(l, "fp64");
    if (HasFailure()) return;
  }
}

// Which rays the shortcut must leave alone: one lane parallel to an axis (dx = +0 or -0), a direction so small
// that its reciprocal overflows, or a non-finite origin.
TEST(Traversal, RaysWithAParallelTinyOrNonFiniteLaneAreNotRegular) {
  std::mt19937 rng(7);
  Lanes l = random_lanes(rng);
  ASSERT_TRUE(grid_ray(l).regular);
  for (float bad_dx : {0.0f, -0.0f, 1e-39f, -1e-39f}) {
    Lanes m = l;
    m.dx[kLanes - 1] = bad_dx;
    EXPECT_FALSE(grid_ray(m).regular) << bad_dx;
    m = l;
    m.dy[0] = bad_dx;
    EXPECT_FALSE(grid_ray(m).regular) << bad_dx;
  }
  for (float bad_origin : {NAN, INFINITY, -INFINITY}) {
    Lanes m = l;
    m.x0[1] = bad_origin;
    EXPECT_FALSE(grid_ray(m).regular) << bad_origin;
    m = l;
    m.y0[2] = bad_origin;
    EXPECT_FALSE(grid_ray(m).regular) << bad_origin;
  }
}

}  // namespace
}  // namespace qdmr
