#include "qdmr/texture/bc3.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "texture/bc3_search.hpp"

namespace qdmr {

Bc3AlphaBlock encode_bc3_alpha(const std::uint8_t texels[16]) {
  return bc3::encode(texels, [](const std::uint8_t* t, const bc3::Candidates& c, int* errors) {
    for (int k = 0; k < c.count; ++k) {
      const bc3::Palette palette = c.palette(k);
      int sum = 0;
      for (int i = 0; i < 16; ++i) {
        int nearest = 255;
        for (const std::uint8_t p : palette) nearest = std::min(nearest, std::abs(int(t[i]) - int(p)));
        sum += nearest * nearest;
      }
      errors[k] = sum;
      if (sum == 0) return k + 1;
    }
    return c.count;
  });
}

void decode_bc3_alpha(const Bc3AlphaBlock& block, std::uint8_t texels[16]) {
  const int a0 = block[0], a1 = block[1];
  bc3::Palette palette{};
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

Bc3Report bc3_roundtrip(std::uint8_t* texels, int width, int height, Bc3Encode encode) {
  if (!encode) encode = &encode_bc3_alpha;
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
      decode_bc3_alpha(encode(source), decoded);
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
