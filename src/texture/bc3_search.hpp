#pragma once
// The search of BC3 alpha encoding (encode_bc3_alpha, qdmr/texture/bc3.hpp), shared by its definition
// (texture/bc3.cpp, one candidate at a time) and the kernels' encoders (kernel/bc3_encode.cpp, several candidates per
// vector): the candidate endpoint pairs of both modes in one order, the first with the least squared error wins,
// so every encoder that computes the same integer errors makes the same blocks.
#include <algorithm>
#include <array>
#include <cstdint>

#include "qdmr/texture/bc3.hpp"

namespace qdmr::bc3 {

using Palette = std::array<std::uint8_t, 8>;

// A mode's palette in ascending order, and the block index that selects each entry.
inline constexpr Palette kIndexOf8 = {1, 7, 6, 5, 4, 3, 2, 0};
inline constexpr Palette kIndexOf6 = {6, 0, 2, 3, 4, 5, 1, 7};

// 8-value mode, a0 > a1: entry k = index 8-k = (k*a0 + (7-k)*a1) / 7 rounded to nearest.
inline Palette ascending8(int a0, int a1) {
  Palette q{};
  for (int k = 0; k < 8; ++k) q[std::size_t(k)] = std::uint8_t((k * a0 + (7 - k) * a1 + 3) / 7);
  return q;
}

// 6-value mode, a0 <= a1: 0, a0, the four interpolated values rounded to nearest, a1, 255.
inline Palette ascending6(int a0, int a1) {
  Palette q{};
  q[0] = 0;
  for (int k = 0; k < 6; ++k) q[std::size_t(k + 1)] = std::uint8_t(((5 - k) * a0 + k * a1 + 2) / 5);
  q[7] = 255;
  return q;
}

// Endpoints may move inward by up to this many steps. In 8-value mode the move is also limited to range/14, so
// every texel stays within range/14 + 1 of its decoded value (the spacing bound of the plain (max, min) pair).
inline constexpr int kMaxShrink = 3;
// The most candidates one mode tries: (kMaxShrink + 2)^2 endpoint pairs.
inline constexpr int kMaxCandidates = (kMaxShrink + 2) * (kMaxShrink + 2);

// A mode's endpoint pairs to try, in order; each palette is made when its error is computed.
struct Candidates {
  bool eight = true;  // the 8-value mode (else the 6-value one)
  int count = 0;
  std::array<std::uint8_t, kMaxCandidates> a0, a1;  // the first `count` are set
  Palette palette(int k) const {
    return eight ? ascending8(a0[std::size_t(k)], a1[std::size_t(k)]) : ascending6(a0[std::size_t(k)], a1[std::size_t(k)]);
  }
};

struct Best {
  int a0 = 0, a1 = 0;
  int error = -1;  // -1: none yet
};

// The pairs a0 in [a0_from, a0_to], a1 in [a1_from, a1_to] (clamped to 0-255) of the mode, in the search's order.
inline Candidates candidates(int a0_from, int a0_to, int a1_from, int a1_to, bool eight) {
  Candidates c;
  c.eight = eight;
  for (int a0 = std::max(a0_from, 0); a0 <= std::min(a0_to, 255); ++a0)
    for (int a1 = std::max(a1_from, 0); a1 <= std::min(a1_to, 255); ++a1) {
      if ((a0 > a1) != eight) continue;
      c.a0[std::size_t(c.count)] = std::uint8_t(a0);
      c.a1[std::size_t(c.count)] = std::uint8_t(a1);
      ++c.count;
    }
  return c;
}

// The first candidate with the least error among the first `count` (errors[k] of candidate k).
inline Best first_least(const Candidates& c, const int* errors, int count) {
  Best best;
  for (int k = 0; k < count; ++k)
    if (best.error < 0 || errors[k] < best.error) best = {c.a0[std::size_t(k)], c.a1[std::size_t(k)], errors[k]};
  return best;
}

inline Bc3AlphaBlock pack(int a0, int a1, const Palette& ascending, const Palette& index_of,
                          const std::uint8_t texels[16]) {
  std::uint64_t bits = 0;
  for (int i = 0; i < 16; ++i) {
    const int twice = 2 * texels[i];
    int k = 0;  // the nearest entry: the number of midpoints below the texel
    for (int j = 0; j < 7; ++j) k += twice > ascending[std::size_t(j)] + ascending[std::size_t(j + 1)];
    bits |= std::uint64_t(index_of[std::size_t(k)]) << (3 * i);
  }
  Bc3AlphaBlock block{std::uint8_t(a0), std::uint8_t(a1)};
  for (int b = 0; b < 6; ++b) block[std::size_t(2 + b)] = std::uint8_t(bits >> (8 * b));
  return block;
}

// The block of `texels`: `errors(texels, candidates, out)` writes, in order, each candidate palette's sum over the
// 16 texels of the squared distance to its nearest entry, and returns how many it wrote: it may stop after the first
// 0 (no later candidate can then win).
template <class Errors>
Bc3AlphaBlock encode(const std::uint8_t texels[16], Errors&& errors) {
  int lo = 255, hi = 0, lo6 = 255, hi6 = 0;
  for (int i = 0; i < 16; ++i) {
    const int t = texels[i];
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    if (t != 0 && t != 255) {
      lo6 = std::min(lo6, t);
      hi6 = std::max(hi6, t);
    }
  }
  std::array<int, kMaxCandidates> error;  // the first ones `errors` wrote

  Best best8;
  if (lo == hi) {
    best8 = hi > 0 ? Best{hi, hi - 1, 0} : Best{1, 0, 0};
  } else {
    const int shrink = std::min(kMaxShrink, (hi - lo) / 14);
    const Candidates c = candidates(hi - shrink, hi + 1, lo - 1, lo + shrink, true);
    best8 = first_least(c, error.data(), errors(texels, c, error.data()));
  }

  Best best6;
  if (best8.error > 0 && lo6 <= hi6) {
    const int shrink = std::min(kMaxShrink, (hi6 - lo6) / 10);
    const Candidates c = candidates(lo6 - 1, lo6 + shrink, hi6 - shrink, hi6 + 1, false);
    best6 = first_least(c, error.data(), errors(texels, c, error.data()));
  }

  if (best6.error >= 0 && best6.error < best8.error)
    return pack(best6.a0, best6.a1, ascending6(best6.a0, best6.a1), kIndexOf6, texels);
  return pack(best8.a0, best8.a1, ascending8(best8.a0, best8.a1), kIndexOf8, texels);
}

}  // namespace qdmr::bc3
