#include "texture/twin_texels.hpp"

#include <cstring>

namespace qdmr {

bool twin_sampling(const SamplingDesc& sampling) {
  return sampling.address == AddressMode::Wrap && sampling.precision != SamplePrecision::Hw6 &&
         (sampling.filter == Filter::Bilinear || sampling.filter == Filter::Trilinear);
}

std::uint64_t twin_texels_bytes(int width, int height) {
  return linear_copy_bytes(width, height, TexelFormat::RGBA8, true);  // as many floats as the decoded copy
}

std::vector<float> interleave_twin_texels(const Texture& albedo, const Texture& normal) {
  if (albedo.format != TexelFormat::RGBA8 || !albedo.srgb || albedo.linear.empty() ||
      normal.format != TexelFormat::RGBA8 || normal.srgb || albedo.levels.size() != normal.levels.size())
    return {};
  for (std::size_t k = 0; k < albedo.levels.size(); ++k) {
    const TextureLevel &a = albedo.levels[k], &n = normal.levels[k];
    if (a.width != n.width || a.height != n.height || a.offset != n.offset) return {};
  }
  std::vector<float> out(albedo.linear.size());
  const std::size_t texels = out.size() / 4;
  if (normal.storage.size() < texels * 4) return {};
  for (std::size_t i = 0; i < texels; ++i) {
    std::memcpy(&out[4 * i], &albedo.linear[4 * i], 3 * sizeof(float));
    std::memcpy(&out[4 * i + 3], &normal.storage[4 * i], 4);
  }
  return out;
}

}  // namespace qdmr
