#include "qdmr/texture/bc3.hpp"

#include <tbb/parallel_for.h>
#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace qdmr {
namespace {

using Palette = std::array<std::uint8_t, 8>;
// The 16 texels of a block in one SSE2 register. SSE2 is part of x86-64, so this preparation code stays baseline (not
// in src/kernel/): the same instructions on every CPU and under every --isa; a wider ISA would pay only with a
// search over several blocks per register.
using Texels = xsimd::batch<std::uint8_t, xsimd::sse2>;
static_assert(Texels::size == 16);

// A mode's palette in ascending order, and the block index that selects each entry.
constexpr Palette kIndexOf8 = {1, 7, 6, 5, 4, 3, 2, 0};
constexpr Palette kIndexOf6 = {6, 0, 2, 3, 4, 5, 1, 7};

// 8-value mode, a0 > a1: entry k = index 8-k = (k*a0 + (7-k)*a1) / 7 rounded to nearest.
Palette ascending8(int a0, int a1) {
  Palette q{};
  for (int k = 0; k < 8; ++k) q[std::size_t(k)] = std::uint8_t((k * a0 + (7 - k) * a1 + 3) / 7);
  return q;
}

// 6-value mode, a0 <= a1: 0, a0, the four interpolated values rounded to nearest, a1, 255.
Palette ascending6(int a0, int a1) {
  Palette q{};
  q[0] = 0;
  for (int k = 0; k < 6; ++k) q[std::size_t(k + 1)] = std::uint8_t(((5 - k) * a0 + k * a1 + 2) / 5);
  q[7] = 255;
  return q;
}

// Sum over the 16 texels of the squared distance to the nearest palette entry.
int squared_error(const Texels& texels, const Palette& q) {
  Texels nearest(std::uint8_t(255));
  for (std::uint8_t p : q) {
    const Texels entry(p);
    nearest = xsimd::min(nearest, xsimd::ssub(texels, entry) | xsimd::ssub(entry, texels));  // |t - p|
  }
  alignas(16) std::uint8_t distance[16];
  nearest.store_aligned(distance);
  int sum = 0;
  for (const int d : distance) sum += d * d;
  return sum;
}

struct Candidate {
  int a0 = 0, a1 = 0;
  int error = -1;  // -1: none yet
};

// Endpoints may move inward by up to this many steps. In 8-value mode the move is also limited to range/14, so
// every texel stays within range/14 + 1 of its decoded value (the spacing bound of the plain (max, min) pair).
constexpr int kMaxShrink = 3;

template <class MakePalette>
void search(const Texels& texels, int a0_from, int a0_to, int a1_from, int a1_to, bool eight, MakePalette make,
            Candidate& best) {
  for (int a0 = std::max(a0_from, 0); a0 <= std::min(a0_to, 255); ++a0) {
    for (int a1 = std::max(a1_from, 0); a1 <= std::min(a1_to, 255); ++a1) {
      if ((a0 > a1) != eight) continue;
      const int error = squared_error(texels, make(a0, a1));
      if (best.error < 0 || error < best.error) best = {a0, a1, error};
      if (best.error == 0) return;
    }
  }
}

Bc3AlphaBlock pack(int a0, int a1, const Palette& ascending, const Palette& index_of,
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

}  // namespace

Bc3AlphaBlock encode_bc3_alpha(const std::uint8_t texels[16]) {
  const Texels v = Texels::load_unaligned(texels);
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

  Candidate best8;
  if (lo == hi) {
    best8 = hi > 0 ? Candidate{hi, hi - 1, 0} : Candidate{1, 0, 0};
  } else {
    const int shrink = std::min(kMaxShrink, (hi - lo) / 14);
    search(v, hi - shrink, hi + 1, lo - 1, lo + shrink, true, ascending8, best8);
  }

  Candidate best6;
  if (best8.error > 0 && lo6 <= hi6) {
    const int shrink = std::min(kMaxShrink, (hi6 - lo6) / 10);
    search(v, lo6 - 1, lo6 + shrink, hi6 - shrink, hi6 + 1, false, ascending6, best6);
  }

  if (best6.error >= 0 && best6.error < best8.error)
    return pack(best6.a0, best6.a1, ascending6(best6.a0, best6.a1), kIndexOf6, texels);
  return pack(best8.a0, best8.a1, ascending8(best8.a0, best8.a1), kIndexOf8, texels);
}

void decode_bc3_alpha(const Bc3AlphaBlock& block, std::uint8_t texels[16]) {
  const int a0 = block[0], a1 = block[1];
  Palette palette{};
  palette[0] = block[0];
  palette[1] = block[1];
  if (a0 > a1) {
    for (int i = 2; i < 8; ++i) palette[std::size_t(i)] = std::uint8_t(((8 - i) * a0 + (i - 1) * a1 + 3) / 7);
  } else {
    for (int i = 2; i < 6; ++i) palette[std::size_t(i)] = std::uint8_t(((6 - i) * a0 + (i - 1) * a1 + 2) / 5);
    palette[6] = 0;
    palette[7] = 255;
  }
  std::uint64_t bits = 0;
  for (int b = 0; b < 6; ++b) bits |= std::uint64_t(block[std::size_t(2 + b)]) << (8 * b);
  for (int i = 0; i < 16; ++i) texels[i] = palette[(bits >> (3 * i)) & 7];
}

Bc3Report bc3_roundtrip(std::uint8_t* texels, int width, int height) {
  Bc3Report report;
  if (width <= 0 || height <= 0) return report;
  const int blocks_x = (width + 3) / 4, blocks_y = (height + 3) / 4;
  struct RowError {
    int max = 0;
    std::uint64_t squared = 0;
  };
  std::vector<RowError> rows(std::size_t(blocks_y), RowError{});
  tbb::parallel_for(0, blocks_y, [&](int by) {
    RowError row;  // a local: stores through uint8_t* could alias the vector's element
    std::uint8_t* row_of[4];  // rows past the bottom edge repeat the last one
    for (int y = 0; y < 4; ++y) row_of[y] = texels + std::size_t(std::min(4 * by + y, height - 1)) * std::size_t(width);
    const int rows_here = std::min(4, height - 4 * by);
    for (int x0 = 0; x0 < width; x0 += 4) {
      const int columns_here = std::min(4, width - x0);
      std::uint8_t source[16], decoded[16];
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) source[x + 4 * y] = row_of[y][x0 + std::min(x, columns_here - 1)];
      decode_bc3_alpha(encode_bc3_alpha(source), decoded);
      for (int y = 0; y < rows_here; ++y) {
        for (int x = 0; x < columns_here; ++x) {
          const int error = std::abs(int(decoded[x + 4 * y]) - int(source[x + 4 * y]));
          row.max = std::max(row.max, error);
          row.squared += std::uint64_t(error * error);
          row_of[y][x0 + x] = decoded[x + 4 * y];
        }
      }
    }
    rows[std::size_t(by)] = row;
  });
  int max = 0;
  std::uint64_t squared = 0;
  for (const RowError& row : rows) {
    max = std::max(max, row.max);
    squared += row.squared;
  }
  report.max_error = max;
  report.rms_error = std::sqrt(double(squared) / (double(width) * double(height)));
  report.blocks = std::size_t(blocks_x) * std::size_t(blocks_y);
  return report;
}

}  // namespace qdmr
