#include "texture/blend_box_values.hpp"

#include <string>

#include "qdmr/core/error.hpp"

namespace qdmr {

std::uint64_t blend_box_values_bytes(int width, int height, int repeats, std::uint64_t layer_heights_bytes) {
  if (layer_heights_bytes == 0 || width != height || repeats < 1) return 0;
  const std::uint64_t period = std::uint64_t(width) * std::uint64_t(repeats);
  return period * period * sizeof(float);
}

std::size_t blend_box_value_count(const BlendBoxSource& source) {
  const LayerHeights& heights = *source.heights;
  return std::size_t(blend_box_values_bytes(heights.width, heights.height, source.repeats,
                                            heights.texels.size() * sizeof(float)) /
                     sizeof(float));
}

HeightView<float> box_value_view(const ZeroedBuffer<float>& values, const LayerHeights& heights, int repeats) {
  const int period = heights.width * repeats;
  if (period <= 0 || values.size() != std::size_t(period) * std::size_t(period))
    throw Error("box values", "the values do not fill a period of " + std::to_string(period) + " squared");
  return {period, period, AddressMode::Wrap, values.data()};
}

}  // namespace qdmr
