#pragma once
// Where horizon-based ambient occlusion looks: the same pattern for the per-frame AO (SIMD, float) and the
// baked AO map (scalar, double), so both see the same directions and tap distances. The per-lane jitter
// rotation is in kernel/ambient_occlusion.hpp.
//
// Directions: n = clamp(directions, 4, 16) equally spaced directions in the UV plane, direction i at
//   angle 2 pi (i + r / kRotations) / n,
// where r in [0, kRotations) is 0 without jitter and the top bits of a hash of (pixel x, pixel y, seed) with
// it: the set of n directions rotated by one of kRotations fixed fractions of the spacing. The cosines and
// sines of every such angle are computed at compile time from exact integer ratios (a Taylor series in double,
// quarter turns exact), so no trigonometry runs per pixel and no libm result enters an image.
//
// Taps along a direction, at horizontal UV distances t (one texel = 1 / max(width, height) UV):
//   coarse: t = 1, 2, 4, 8, ... texels up to the radius; the tap at 2^k texels reads max-quadtree level k;
//   fine:   t = 1, 2, 3, ... texels up to the radius, level 0; beyond kMaxFineTaps texels the taps spread
//           evenly, t = k * radius / kMaxFineTaps (the cost per direction is capped at kMaxFineTaps fetches).
// A radius below one texel has no taps (nothing to occlude: AO = 1).
#include <algorithm>
#include <array>
#include <cstdint>

namespace qdmr::ao {

// What the pattern is made from: AoDesc's fields of the same names (bake/ao_map.hpp's pattern_of), for the baked
// map and the programs' per-frame AO alike.
struct Pattern {
  int directions = 8;
  bool jitter = false;
  std::uint32_t seed = 1;
  float radius = 0.05f;
  bool coarse = true;
};

inline constexpr int kMinDirections = 4, kMaxDirections = 16;
inline constexpr int kRotations = 16;  // jitter rotations per direction spacing (4 hash bits)
inline constexpr int kMaxFineTaps = 64;
inline constexpr int kMaxTaps = kMaxFineTaps;  // coarse needs at most 32 (2^31 texels)

inline int direction_count(const Pattern& pattern) {
  return std::clamp(pattern.directions, kMinDirections, kMaxDirections);
}

namespace detail {

// cos and sin of (numerator / denominator) quarter turns for |numerator / denominator| <= 1/2, in double.
constexpr void quarter_turn_fraction(std::int64_t numerator, std::int64_t denominator, double& c, double& s) {
  const double x = double(numerator) / double(denominator) * 1.5707963267948966;
  const double x2 = x * x;
  double term_c = 1.0, term_s = x;
  c = 0.0;
  s = 0.0;
  for (int k = 0; k < 24; ++k) {  // |x| <= pi/4: the 24th terms are far below double precision
    c += term_c;
    s += term_s;
    term_c *= -x2 / double((2 * k + 1) * (2 * k + 2));
    term_s *= -x2 / double((2 * k + 2) * (2 * k + 3));
  }
}

inline constexpr int kTableSize = kRotations * (kMinDirections + kMaxDirections) * (kMaxDirections - kMinDirections + 1) / 2;

constexpr int table_offset(int n) { return kRotations * (n * (n - 1) / 2 - kMinDirections * (kMinDirections - 1) / 2); }

struct DirectionTable {
  std::array<float, kTableSize> cos{}, sin{};
};

// Entry table_offset(n) + m holds the angle 2 pi m / (n kRotations), m in [0, n kRotations).
constexpr DirectionTable make_direction_table() {
  DirectionTable t;
  for (int n = kMinDirections; n <= kMaxDirections; ++n) {
    const std::int64_t steps = std::int64_t(n) * kRotations;  // per turn
    for (std::int64_t m = 0; m < steps; ++m) {
      // m / steps turns = 4m / steps quarter turns = q + f with q an integer and |f| <= 1/2.
      const std::int64_t q = (8 * m + steps) / (2 * steps);
      double c = 0.0, s = 0.0;
      quarter_turn_fraction(4 * m - q * steps, steps, c, s);
      for (std::int64_t k = 0; k < q % 4; ++k) {  // rotate by a quarter turn: exact
        const double rotated_c = -s;
        s = c;
        c = rotated_c;
      }
      t.cos[std::size_t(table_offset(n) + m)] = float(c);
      t.sin[std::size_t(table_offset(n) + m)] = float(s);
    }
  }
  return t;
}

}  // namespace detail

inline constexpr detail::DirectionTable kDirections = detail::make_direction_table();

// Index into kDirections.cos / .sin of direction i (of n) with rotation r.
inline constexpr int direction_index(int n, int i, int r) { return detail::table_offset(n) + i * kRotations + r; }

// The jitter rotation of a pixel: the top 4 bits of a 32-bit hash of (x, y, seed) (integer pixel coordinates).
inline std::uint32_t mix_hash(std::uint32_t x, std::uint32_t y, std::uint32_t seed) {
  std::uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}
inline int rotation(std::uint32_t x, std::uint32_t y, std::uint32_t seed) { return int(mix_hash(x, y, seed) >> 28); }

struct Tap {
  float distance;      // UV units
  float inv_distance;  // 1 / distance
  int level;           // max-quadtree level (coarse), 0 (fine)
};

struct Taps {
  std::array<Tap, kMaxTaps> tap{};
  int count = 0;
};

// The taps of one direction for a height map of width x height texels.
inline Taps make_taps(const Pattern& pattern, int width, int height) {
  Taps taps;
  const float texel = 1.0f / float(std::max(width, height));
  const auto add = [&](float distance, int level) {
    taps.tap[std::size_t(taps.count++)] = {distance, 1.0f / distance, level};
  };
  if (pattern.coarse) {
    for (int k = 0; k < 31 && float(1 << k) * texel <= pattern.radius; ++k) add(float(1 << k) * texel, k);
  } else {
    const float texels = pattern.radius / texel;
    const bool spread = texels > float(kMaxFineTaps);
    const int count = spread ? kMaxFineTaps : int(texels);
    const float step = spread ? pattern.radius / float(kMaxFineTaps) : texel;
    for (int k = 1; k <= count; ++k) add(float(k) * step, 0);
  }
  return taps;
}

}  // namespace qdmr::ao
