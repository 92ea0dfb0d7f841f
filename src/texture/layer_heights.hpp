#pragma once
// The level-0 heights of a blend's layers side by side, four floats per texel (layer i in float i, 0 where there
// are fewer layers): a QDM walk over a blend reads every layer's height at a level-0 cell with one 16-byte load per
// lane, one cache line where the layers' own chains take one each. The floats are the layers' decoded heights
// (Texture::linear of their max chains), so the walk's results keep their bits.
#include <cstdint>
#include <vector>

#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

struct LayerHeights {
  int width = 0, height = 0;
  std::vector<float> texels;  // 4 per texel, row by row
};

// What interleave_layer_heights() keeps for 1 to 4 max chains of w x h texels whose formats are `formats`: 16 bytes
// per texel, when each chain keeps a decoded copy (linear_copy_bytes); else 0 (the walk fetches each layer's
// chain).
std::uint64_t layer_heights_bytes(int width, int height, const std::vector<TexelFormat>& formats);

// The interleaved level 0 of these max chains, or nothing (width 0) where layer_heights_bytes() is 0 for them or
// their sizes differ.
LayerHeights interleave_layer_heights(const std::vector<const Texture*>& max_chains);

}  // namespace qdmr
