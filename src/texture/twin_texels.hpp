#pragma once
// An albedo map and a normal map of one size that are sampled together (TwinSampler), interleaved per texel: the
// albedo's decoded rgb (floats 0-2, from its Texture::linear copy) and the normal map's RGBA8 code (float 3, its
// four bytes), for every texel of the chain at the albedo's float index. A twin sample then reads one 16-byte
// texel per tap for both maps (one cache line where the two chains take two), and the same floats and codes as
// the two chains hold, so the same bits.
#include <cstdint>
#include <vector>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

// Whether a material's sampling lets its TwinSampler share addresses (the states sampler.cpp instantiates twins
// for: bilinear or trilinear with wrap addressing, exact or 8-bit precision), so its interleaved texels are read.
bool twin_sampling(const SamplingDesc& sampling);

// What interleave_twin_texels() keeps for an albedo chain of width x height: as much as its decoded copy (16 bytes
// per texel; 0 where the chain is too large to keep one, and then makes none).
std::uint64_t twin_texels_bytes(int width, int height);

// The interleaved texels, or nothing (empty) unless the albedo is RGBA8 sRGB with its decoded copy and the normal
// map RGBA8 (not sRGB) with the same levels.
std::vector<float> interleave_twin_texels(const Texture& albedo, const Texture& normal);

}  // namespace qdmr
