#pragma once
// A height map as a GPU texture holds it: the storage format the scene asks for (auto: by the bit depth of
// the source), quantised, optionally BC3/DXT5-compressed (encoded, then decoded: the decoded values are what
// gets sampled and what the mip chain — e.g. the max-quadtree — is built from, so it stays conservative).
#include <optional>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/bc3.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

// auto: R8 from 8-bit sources, R16 from 16-bit sources and procedural patterns, R32F from float files;
// BC3 always stores R8.
TexelFormat height_format(const TextureDesc& desc, int source_bits);

struct HeightTexture {
  Texture texture;
  std::optional<Bc3Report> bc3;  // the encode error, when compressed
};

// The chain's Max / Min levels by `extremum` (make_mip_texture); BC3 blocks by `bc3` (bc3_roundtrip).
HeightTexture make_height_texture(const Image& height, const TextureDesc& desc, MipReduce reduce,
                                  MipExtremum extremum = nullptr, Bc3Encode bc3 = nullptr);

}  // namespace qdmr
