// Box-filtered mip chains. Level k+1 is max(1, floor(n/2)) per axis; output texel i averages inputs 2i and
// 2i+1, and the last one also 2i+2 when n is odd (a 3-tap box), so every input texel is used exactly once.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/texture.hpp"

namespace qdmr {
namespace {

struct Taps {
  int first;
  int count;  // 1 (an axis of size 1), 2, or 3 (last texel of an odd axis)
};

Taps taps(int i, int in_size, int out_size) {
  if (in_size == 1) return {0, 1};
  return {2 * i, (i == out_size - 1 && (in_size & 1)) ? 3 : 2};
}

Image downsample(const Image& in, TexturePurpose purpose) {
  const int w = std::max(1, in.width / 2), h = std::max(1, in.height / 2), channels = in.channels;
  Image out(w, h, channels);
  const int grain = std::max(1, 16384 / w);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, grain), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const Taps ty = taps(y, in.height, h);
      for (int x = 0; x < w; ++x) {
        const Taps tx = taps(x, in.width, w);
        const float count = float(tx.count * ty.count);
        float sum[4] = {0, 0, 0, 0};
        for (int j = ty.first; j < ty.first + ty.count; ++j)
          for (int i = tx.first; i < tx.first + tx.count; ++i)
            for (int c = 0; c < channels; ++c) sum[c] += in.at(i, j, c);
        for (int c = 0; c < channels; ++c) out.at(x, y, c) = sum[c] / count;
        if (purpose == TexturePurpose::Normal) {
          const double len2 = double(sum[0]) * sum[0] + double(sum[1]) * sum[1] + double(sum[2]) * sum[2];
          const double inv = len2 > 0.0 ? 1.0 / std::sqrt(len2) : 0.0;
          out.at(x, y, 0) = len2 > 0.0 ? float(sum[0] * inv) : 0.0f;
          out.at(x, y, 1) = len2 > 0.0 ? float(sum[1] * inv) : 0.0f;
          out.at(x, y, 2) = len2 > 0.0 ? float(sum[2] * inv) : 1.0f;
        }
      }
    }
  });
  return out;
}

}  // namespace

std::size_t MipChain::bytes() const {
  std::size_t total = 0;
  for (const Image& level : levels) total += level.bytes();
  return total;
}

MipChain build_mip_chain(Image level0, TexturePurpose purpose) {
  if (level0.width < 1 || level0.height < 1 || level0.channels < 1 || level0.channels > 4)
    throw Error("mip chain", "level 0 must be at least 1x1 with 1 to 4 channels");
  MipChain chain;
  chain.levels.push_back(std::move(level0));
  while (chain.levels.back().width > 1 || chain.levels.back().height > 1)
    chain.levels.push_back(downsample(chain.levels.back(), purpose));
  return chain;
}

}  // namespace qdmr
