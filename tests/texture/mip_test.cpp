#include <gtest/gtest.h>

#include <cmath>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/texture.hpp"

namespace qdmr {
namespace {

// t(x, y) = x + w * y, one channel.
Image ramp(int w, int h) {
  Image img(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y, 0) = float(x + w * y);
  return img;
}

TEST(TextureMip, FourByFour) {
  const MipChain chain = build_mip_chain(ramp(4, 4), TexturePurpose::Height);
  ASSERT_EQ(chain.levels.size(), 3u);
  EXPECT_EQ(chain.levels[1].width, 2);
  EXPECT_EQ(chain.levels[1].texels, (std::vector<float>{2.5f, 4.5f, 10.5f, 12.5f}));
  EXPECT_EQ(chain.levels[2].texels, std::vector<float>{7.5f});
  EXPECT_EQ(chain.bytes(), (16u + 4u + 1u) * sizeof(float));
}

TEST(TextureMip, OddSizesFoldTheLastRowAndColumn) {
  const MipChain three = build_mip_chain(ramp(3, 3), TexturePurpose::Height);
  ASSERT_EQ(three.levels.size(), 2u);
  EXPECT_EQ(three.levels[1].texels, std::vector<float>{4.0f});  // all nine texels, 0..8

  const MipChain five = build_mip_chain(ramp(5, 1), TexturePurpose::Height);
  ASSERT_EQ(five.levels.size(), 3u);
  EXPECT_EQ(five.levels[1].width, 2);
  EXPECT_EQ(five.levels[1].height, 1);
  EXPECT_EQ(five.levels[1].texels, (std::vector<float>{0.5f, 3.0f}));  // {0, 1} and {2, 3, 4}
  EXPECT_EQ(five.levels[2].texels, std::vector<float>{1.75f});

  const MipChain tall = build_mip_chain(ramp(2, 7), TexturePurpose::Height);
  ASSERT_EQ(tall.levels.size(), 3u);
  EXPECT_EQ(tall.levels[1].width, 1);
  EXPECT_EQ(tall.levels[1].height, 3);
  EXPECT_EQ(tall.levels[1].texels, (std::vector<float>{1.5f, 5.5f, 10.5f}));  // rows {0,1}, {2,3}, {4,5,6}
}

TEST(TextureMip, NormalsRenormalised) {
  Image n(2, 2, 3);
  const float a = std::sqrt(0.5f);
  const float texels[] = {a, 0, a, 0, a, a, -a, 0, a, 0, 0, 1};
  std::copy(std::begin(texels), std::end(texels), n.texels.begin());
  const MipChain chain = build_mip_chain(n, TexturePurpose::Normal);
  const Image& top = chain.levels[1];
  const double sx = 0, sy = a, sz = 3 * a + 1, len = std::sqrt(sx * sx + sy * sy + sz * sz);
  EXPECT_NEAR(top.at(0, 0, 0), sx / len, 1e-7);
  EXPECT_NEAR(top.at(0, 0, 1), sy / len, 1e-7);
  EXPECT_NEAR(top.at(0, 0, 2), sz / len, 1e-7);
  // Opposite normals cancel: flat instead of a zero vector.
  Image opposite(2, 1, 3);
  opposite.at(0, 0, 0) = 1, opposite.at(1, 0, 0) = -1;
  EXPECT_EQ(build_mip_chain(opposite, TexturePurpose::Normal).levels[1].texels, (std::vector<float>{0, 0, 1}));
}

TEST(TextureMip, LargeChainSizes) {
  Image img(1000, 600, 3);
  const MipChain chain = build_mip_chain(std::move(img), TexturePurpose::Albedo);
  ASSERT_EQ(chain.levels.size(), 10u);  // 1000 500 250 125 62 31 15 7 3 1
  EXPECT_EQ(chain.levels[9].width, 1);
  EXPECT_EQ(chain.levels[9].height, 1);
  EXPECT_EQ(chain.levels[4].height, 37);  // 600 300 150 75 37
  EXPECT_THROW(build_mip_chain(Image(0, 4, 1), TexturePurpose::Height), Error);
}

}  // namespace
}  // namespace qdmr
