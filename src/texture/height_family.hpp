#pragma once
// A dynamic height's textures rebuilt together, every frame: the heights as stored (R8 or R16, no BC3) with their
// decoded copy, their Box and Max chains, level 0's wrap footprints and from_height normals with their BoxNormal
// chain. One pass over level 0's rows makes the codes, the decoded copy and every texture's level 0 from them;
// then each chain's levels, each in parallel over rows on HeightRows (a kernel's vectors). Each texture has the
// bits the generic builders give it (make_height_texture, add_linear_copy, add_wrap_footprints, the from_height
// slot): only the way there differs. A texture handed in with its buffers from an earlier frame of the same
// layout is refilled in place: no allocation, no pages to clear.
#include <string>
#include <vector>

#include "qdmr/scene/scene.hpp"
#include "texture/height_rows.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

struct HeightFamilyMember {
  bool normals = false;         // from_height normals (RGBA8, BoxNormal); else heights
  MipReduce reduce = MipReduce::Box;  // heights: Box or Max
  bool wrap_footprints = false;       // heights: keep level 0's wrap footprints
  float normal_strength = 1.0f;       // normals: their layer's normal_strength
  Texture texture;  // in: an earlier frame's texture whose buffers to reuse, or empty; out: the texture
};

// Whether the family builds heights stored as `format` (R8 or R16 with a decoded copy, no BC3) of this size.
bool height_family_stores(const TextureDesc& height, TexelFormat format, int width, int height_texels);

// Builds every member from `layer`'s heights (its height slot, transformed by its scale and offset) stored as
// `format` (height_family_stores must hold; at least one member is heights). Throws qdmr::Error(where, ...)
// as make_layer_height does.
void build_height_family(const LayerDesc& layer, TexelFormat format, const std::string& where,
                         std::vector<HeightFamilyMember>& members, const HeightRows& rows, MipExtremum extremum);

// The baseline's rows (the same bits as every kernel's).
const HeightRows& baseline_height_rows();

}  // namespace qdmr
