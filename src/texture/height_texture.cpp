#include "texture/height_texture.hpp"

namespace qdmr {

TexelFormat height_format(const TextureDesc& desc, int source_bits) {
  if (desc.compression == Compression::Bc3) return TexelFormat::R8;
  switch (desc.format) {
    case TextureFormatChoice::R8: return TexelFormat::R8;
    case TextureFormatChoice::R16: return TexelFormat::R16;
    case TextureFormatChoice::R32F: return TexelFormat::R32F;
    case TextureFormatChoice::RG8:
    case TextureFormatChoice::RGBA8:
    case TextureFormatChoice::Auto: break;
  }
  return source_bits <= 8 ? TexelFormat::R8 : source_bits <= 16 ? TexelFormat::R16 : TexelFormat::R32F;
}

HeightTexture make_height_texture(const Image& height, const TextureDesc& desc, MipReduce reduce,
                                  MipExtremum extremum, Bc3Encode bc3) {
  HeightTexture result;
  const TexelFormat format = height_format(desc, height.source_bits);
  if (desc.compression != Compression::Bc3) {
    result.texture = make_mip_texture(height, format, false, reduce, extremum);
    return result;
  }
  // Quantise level 0 only, round-trip it through BC3, then build the chain from the decoded texels.
  Texture texture = make_mip_texture(height, TexelFormat::R8, false, reduce, extremum);
  const TextureLevel& level0 = texture.levels[0];
  result.bc3 = bc3_roundtrip(texture.storage.data() + level0.offset, level0.width, level0.height, bc3);
  build_mip_levels(texture, reduce, extremum);
  result.texture = std::move(texture);
  return result;
}

}  // namespace qdmr
