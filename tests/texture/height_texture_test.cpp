// Height storage: the format chosen from the source, quantisation, and BC3 feeding the max-quadtree.
#include <gtest/gtest.h>

#include <cmath>

#include "texture/height_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"

namespace qdmr {
namespace {

Image ramp(int w, int h, int source_bits) {
  Image img(w, h, 1);
  img.source_bits = source_bits;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y, 0) = float(x * 7 + y * 13 % 97) / float(w * 7 + 97);
  return img;
}

TEST(HeightTexture, AutoFormatFollowsTheSourceBitDepth) {
  TextureDesc desc;
  EXPECT_EQ(height_format(desc, 8), TexelFormat::R8);
  EXPECT_EQ(height_format(desc, 16), TexelFormat::R16);  // 16-bit heights stay 16-bit
  EXPECT_EQ(height_format(desc, 32), TexelFormat::R32F);
  desc.format = TextureFormatChoice::R8;
  EXPECT_EQ(height_format(desc, 16), TexelFormat::R8);  // unless the scene asks for 8
  desc.format = TextureFormatChoice::Auto;
  desc.compression = Compression::Bc3;
  EXPECT_EQ(height_format(desc, 32), TexelFormat::R8);
}

TEST(HeightTexture, SixteenBitSourcesKeepEverySixteenBitValue) {
  Image img(64, 1, 1);
  img.source_bits = 16;
  for (int x = 0; x < 64; ++x) img.at(x, 0, 0) = float(x * 1021) / 65535.0f;
  const HeightTexture h = make_height_texture(img, TextureDesc{}, MipReduce::Max);
  ASSERT_EQ(h.texture.format, TexelFormat::R16);
  for (int x = 0; x < 64; ++x) EXPECT_EQ(h.texture.texel(0, x, 0, 0), float(x * 1021) / 65535.0f);
  EXPECT_FALSE(h.bc3.has_value());
}

TEST(HeightTexture, Bc3ReportsItsErrorAndTheQuadtreeBoundsTheDecodedTexels) {
  TextureDesc desc;
  desc.compression = Compression::Bc3;
  const Image img = ramp(37, 29, 32);  // odd sizes: partial blocks and 3-tap parents
  const HeightTexture h = make_height_texture(img, desc, MipReduce::Max);
  ASSERT_TRUE(h.bc3.has_value());
  EXPECT_EQ(h.bc3->blocks, std::size_t(10 * 8));
  double max_error = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      max_error = std::max(max_error, std::abs(std::floor(double(h.texture.texel(0, x, y, 0)) * 255.0 + 0.5) -
                                               std::floor(double(img.at(x, y, 0)) * 255.0 + 0.5)));
  EXPECT_DOUBLE_EQ(max_error, h.bc3->max_error);  // the report measures exactly what is stored
  // Every texel of every level is at least the decoded level-0 texels it covers (conservative quadtree).
  for (int level = 1; level < h.texture.level_count(); ++level) {
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        int px = x, py = y;
        for (int l = 1; l <= level; ++l) {
          const int pw = h.texture.levels[std::size_t(l)].width, ph = h.texture.levels[std::size_t(l)].height;
          px = std::min(px / 2, pw - 1);
          py = std::min(py / 2, ph - 1);
        }
        ASSERT_GE(h.texture.texel(level, px, py, 0), h.texture.texel(0, x, y, 0)) << level << " " << x << "," << y;
      }
  }
}

}  // namespace
}  // namespace qdmr
