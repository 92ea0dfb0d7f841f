#pragma once
// The level-0 image of each texture slot of a material, made from its TextureDesc: a file, a procedural pattern,
// normals from a height. Their mip chains are a Texture's (mip_texture.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {

enum class TexturePurpose {
  Albedo,  // 3 channels, linear RGB (sRGB files decoded)
  Normal,  // 3 channels, tangent-space unit vector in [-1,1] (DX convention flipped to GL)
  Height,  // 1 channel, h in [0,1] after the layer's scale and offset
  Orm      // 3 channels, linear: occlusion, roughness, metalness (LayerDesc::orm, R from LayerDesc::occlusion if set)
};

const char* purpose_name(TexturePurpose purpose);  // "albedo", "normal", "height", "orm"

// Deterministic procedural height pattern in [0,1], size x size, 1 channel.
Image generate_procedural(const ProceduralDesc& desc);

// Level 0 of one texture slot (an orm texture: `desc` is not read, `where` names the layer). `height` is the layer's height image, needed for Normal from_height (may be
// null otherwise); a procedural albedo is coloured by its own pattern. from_height strength 1 is the normal of
// a surface whose depth range (h from 0 to 1) is 1/16 of a texture repeat. Throws qdmr::Error(where, ...).
Image make_texture(const TextureDesc& desc, TexturePurpose purpose, const LayerDesc& layer, const Image* height,
                   const std::string& where);

// A layer's orm texture before it is built (its files' headers read and checked; `where` names the layer): level
// 0's size, its orm file's, else its occlusion file's, else 1x1 (an occlusion file of another size than the orm
// file is an error), and the most make_texture holds at once building it, its result included.
struct OrmSource {
  int width = 1, height = 1;
  std::uint64_t build_bytes = 0;
};
OrmSource orm_source(const LayerDesc& layer, const std::string& where);

// Level 0 of a layer's height with scale/offset applied; a layer without one is flat at the top (1x1, h = 1).
Image make_layer_height(const LayerDesc& layer, const std::string& where);

// The most memory make_texture holds at once, its result included (not the `height` image passed in), for a slot
// whose level 0 is width x height; `file`: the header of the slot's file (TextureSource::File), else null. For
// memory plans: nothing is read or built.
std::uint64_t make_texture_bytes(const TextureDesc& desc, TexturePurpose purpose, int width, int height,
                                 const ImageHeader* file);

}  // namespace qdmr
