#include "texture/layer_heights.hpp"

namespace qdmr {

std::uint64_t layer_heights_bytes(int width, int height, const std::vector<TexelFormat>& formats) {
  if (formats.empty() || formats.size() > 4) return 0;
  for (TexelFormat f : formats)
    if (linear_copy_bytes(width, height, f, false) == 0) return 0;
  return std::uint64_t(width) * std::uint64_t(height) * 4 * sizeof(float);
}

LayerHeights interleave_layer_heights(const std::vector<const Texture*>& max_chains) {
  if (max_chains.empty() || max_chains.size() > 4) return {};
  const int w = max_chains[0]->width(), h = max_chains[0]->height();
  for (const Texture* t : max_chains)
    if (t->width() != w || t->height() != h || t->linear.empty() || t->channels() != 1) return {};
  LayerHeights out{w, h, std::vector<float>(std::size_t(w) * std::size_t(h) * 4, 0.0f)};
  const std::size_t texels = std::size_t(w) * std::size_t(h);
  for (std::size_t i = 0; i < max_chains.size(); ++i) {
    const Texture& chain = *max_chains[i];
    const float* level0 = chain.linear.data() + chain.levels[0].offset / std::size_t(bytes_per_texel(chain.format));
    for (std::size_t t = 0; t < texels; ++t) out.texels[t * 4 + i] = level0[t];
  }
  return out;
}

}  // namespace qdmr
