// texture/layer_heights: the layers' level-0 heights side by side, what a blended QDM walk reads at its level-0
// cells instead of each layer's chain, and what the plan counts for them.
#include <gtest/gtest.h>

#include "texture/layer_heights.hpp"

namespace qdmr {
namespace {

Texture max_chain(int w, int h, TexelFormat format, int seed) {
  Image image(w, h, 1);
  for (std::size_t i = 0; i < image.texels.size(); ++i) image.texels[i] = float((i * 37 + std::size_t(seed) * 11) % 101) / 100.0f;
  Texture t = make_mip_texture(image, format, false, MipReduce::Max);
  add_linear_copy(t);
  return t;
}

TEST(LayerHeights, HoldEachLayersDecodedLevelZeroInItsFloat) {
  const Texture a = max_chain(8, 4, TexelFormat::R16, 1), b = max_chain(8, 4, TexelFormat::R8, 2),
                c = max_chain(8, 4, TexelFormat::R16, 3);
  const LayerHeights lh = interleave_layer_heights({&a, &b, &c});
  ASSERT_EQ(lh.width, 8);
  ASSERT_EQ(lh.height, 4);
  ASSERT_EQ(lh.texels.size(), std::size_t(8 * 4 * 4));
  const Texture* layers[] = {&a, &b, &c};
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) {
      const std::size_t t = std::size_t(y * 8 + x) * 4;
      for (int i = 0; i < 3; ++i)  // the bits the walk's per-layer fetch reads (the decoded copy, as texel() decodes)
        EXPECT_EQ(lh.texels[t + std::size_t(i)], layers[i]->texel(0, x, y, 0)) << x << "," << y << " layer " << i;
      EXPECT_EQ(lh.texels[t + 3], 0.0f);
    }
  EXPECT_EQ(layer_heights_bytes(8, 4, {TexelFormat::R16, TexelFormat::R8, TexelFormat::R16}),
            lh.texels.size() * sizeof(float));
}

TEST(LayerHeights, NoneWithoutDecodedCopiesOrOfMixedSizes) {
  const Texture a = max_chain(8, 4, TexelFormat::R16, 1), f = max_chain(8, 4, TexelFormat::R32F, 2),
                small = max_chain(4, 4, TexelFormat::R16, 3);
  EXPECT_EQ(interleave_layer_heights({&a, &f}).width, 0);  // R32F keeps no decoded copy
  EXPECT_EQ(layer_heights_bytes(8, 4, {TexelFormat::R16, TexelFormat::R32F}), 0u);
  EXPECT_EQ(interleave_layer_heights({&a, &small}).width, 0);
  EXPECT_EQ(interleave_layer_heights({}).width, 0);
  EXPECT_EQ(layer_heights_bytes(8, 4, {}), 0u);
}

}  // namespace
}  // namespace qdmr
