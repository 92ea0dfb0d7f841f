#pragma once
// Math modes: how shader code addresses texels and quadtree cells along one texture axis.
//   Sm4Math    positions in 32.32 fixed point of UV (integer repeat, 32-bit fraction), integer cell arithmetic:
//              exact, as Shader Model 4 integer instructions allow.
//   Sm3Math    the same operations emulated in fp32 (floor of uv * n, edges as c / n), as Shader Model 3 must:
//              exact only while uv * n and c / n are representable, off by a cell beyond.
//   ExactMath  the fp32 formulas in fp64, for references and studies.
// Each policy has Position, from_uv, to_uv, cell_of(position, n) and cell_start(cell, n), the first position
// inside a cell. cell_of(cell_start(c, n), n) == c is exact for Sm4Math; docs/sampling.md records where the
// others first break.
#include <cmath>
#include <cstdint>

namespace qdmr {

struct Sm4Math {
  using Position = std::int64_t;  // UV * 2^32
  static constexpr int kFractionBits = 32;
  static Position from_uv(float u) {
    // Exact: a float with |u| < 2^31 has at most 24 significant bits, all of which fit 32.32.
    return Position(std::floor(std::ldexp(double(u), kFractionBits)));
  }
  static double to_uv(Position p) { return std::ldexp(double(p), -kFractionBits); }
  // floor(p * n / 2^32). Domain: |uv| * n < 2^31 (e.g. |uv| <= 1e4 with n <= 16384), so the product fits 64 bits.
  static std::int64_t cell_of(Position p, int n) {
    const std::int64_t scaled = p * std::int64_t(n);
    return scaled >> kFractionBits;  // arithmetic shift floors negative values
  }
  // ceil(c * 2^32 / n): the smallest position whose cell is c.
  static Position cell_start(std::int64_t c, int n) {
    const std::int64_t numerator = c * (std::int64_t(1) << kFractionBits);
    const std::int64_t q = numerator / n, r = numerator % n;
    return q + (r > 0 ? 1 : 0);  // division truncates towards zero: round positive remainders up
  }
};

struct Sm3Math {
  using Position = float;
  static Position from_uv(float u) { return u; }
  static double to_uv(Position p) { return p; }
  static std::int64_t cell_of(Position p, int n) { return std::int64_t(std::floor(p * float(n))); }
  static Position cell_start(std::int64_t c, int n) { return float(c) / float(n); }
};

struct ExactMath {
  using Position = double;
  static Position from_uv(float u) { return u; }
  static double to_uv(Position p) { return p; }
  static std::int64_t cell_of(Position p, int n) { return std::int64_t(std::floor(p * double(n))); }
  static Position cell_start(std::int64_t c, int n) { return double(c) / double(n); }
};

}  // namespace qdmr
