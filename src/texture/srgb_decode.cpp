#include "texture/srgb_decode.hpp"

#include <cmath>
#include <cstddef>

namespace qdmr::texture_detail {

float srgb_to_linear(float c) {
  const double v = c;
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

const std::array<float, 256> kSrgbByteToLinear = [] {
  std::array<float, 256> table{};
  for (int k = 0; k < 256; ++k) table[std::size_t(k)] = srgb_to_linear(float(k) / 255.0f);
  return table;
}();

}  // namespace qdmr::texture_detail
