// MaxChainCells (kernel/height_surface.hpp): QDM's paired walks read the decoded max chain through it instead of
// SingleLayerSurface::cell_max. Within the chain's levels it must give cell_max's bits for every cell, wrapping far
// out on both sides, on square and oblong chains (whose coarse levels are one texel wide or high); it must decline
// chains it cannot read (formats without a decoded copy, chains without one).
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>

#include "kernel/height_surface.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "texture/sampler_test_util.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::Int;
using simd::kLanes;
using test::bits;

Texture max_chain(int width, int height, TexelFormat format) {
  Image img(width, height, 1);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) img.at(x, y, 0) = float((x * 7 + y * 13) % 31) / 30.0f;
  Texture chain = make_mip_texture(img, format, false, MipReduce::Max);
  add_linear_copy(chain);  // the decoded copy the walks read (none for R32F)
  return chain;
}

TEST(MaxChainCells, ReadsWhatCellMaxReads) {
  for (const TexelFormat format : {TexelFormat::R8, TexelFormat::R16})
    for (const auto& [width, height] : {std::pair{16, 16}, std::pair{32, 4}, std::pair{2, 64}}) {
      const Texture heights = max_chain(width, height, format);
      const Texture chain = max_chain(width, height, format);
      const HeightLayerTextures textures(heights, &chain, SamplerState{}, HeightFetch::Bilinear);
      const SingleLayerSurface surface(textures);
      const MaxChainCells& cells = surface.max_chain_cells();
      const float* texels = cells.texels();
      ASSERT_NE(texels, nullptr) << int(format) << " " << width << "x" << height;
      alignas(64) std::int32_t level[kLanes], x[kLanes], y[kLanes];
      alignas(64) float got[kLanes], expected[kLanes];
      for (int round = 0; round < 256; ++round) {
        for (int l = 0; l < kLanes; ++l) {
          level[l] = (round + l) % chain.level_count();
          x[l] = (round * 5 + l * 11) % 143 - 71;
          y[l] = (round * 3 + l * 17) % 151 - 75;
        }
        const Int lv = Int::load_aligned(level), xv = Int::load_aligned(x), yv = Int::load_aligned(y);
        cells.at(texels, lv, xv, yv).store_aligned(got);
        surface.cell_max<false>(lv, xv, yv).store_aligned(expected);
        for (int l = 0; l < kLanes; ++l)
          ASSERT_EQ(bits(got[l]), bits(expected[l]))
              << int(format) << " " << width << "x" << height << " level " << level[l] << " cell " << x[l] << ","
              << y[l];
      }
    }
}

TEST(MaxChainCells, DeclinesChainsItCannotRead) {
  const Texture heights = max_chain(16, 16, TexelFormat::R32F);
  const Texture float_chain = max_chain(16, 16, TexelFormat::R32F);
  const HeightLayerTextures float_textures(heights, &float_chain, SamplerState{}, HeightFetch::Bilinear);
  EXPECT_EQ(SingleLayerSurface(float_textures).max_chain_cells().texels(), nullptr);
  Texture chain = max_chain(16, 16, TexelFormat::R16);
  const HeightLayerTextures textures(heights, &chain, SamplerState{}, HeightFetch::Bilinear);
  EXPECT_NE(SingleLayerSurface(textures).max_chain_cells().texels(), nullptr);
  chain.linear.clear();  // as beyond kLinearCopyMaxBytes: the sampler reads the R16 texels, so must the walks
  EXPECT_EQ(SingleLayerSurface(textures).max_chain_cells().texels(), nullptr);
}

}  // namespace
}  // namespace qdmr
