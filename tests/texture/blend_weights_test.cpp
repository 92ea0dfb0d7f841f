// Blend weight maps: the strongest layer normalised to 1, vertex sampling, and the weight texture rasterized
// from vertex weights.
#include <gtest/gtest.h>

#include <algorithm>

#include "qdmr/mesh/mesh.hpp"
#include "texture/blend_weights.hpp"

namespace qdmr {
namespace {

TEST(BlendWeights, NoiseAndTerrainMapsGiveTheStrongestLayerWeightOne) {
  WeightsDesc noise;
  noise.resolution = 64;
  WeightsDesc terrain;
  terrain.source = WeightSource::Terrain;
  terrain.height.source = TextureSource::Procedural;
  terrain.height.procedural.size = 64;
  terrain.relief = 0.5f;
  for (const WeightsDesc& desc : {noise, terrain}) {
    const Image map = make_weight_map(desc, 4, "test");
    ASSERT_EQ(map.channels, 4);
    for (int y = 0; y < map.height; ++y)
      for (int x = 0; x < map.width; ++x) {
        float top = 0.0f;
        for (int c = 0; c < 4; ++c) {
          EXPECT_GE(map.at(x, y, c), 0.0f);
          top = std::max(top, map.at(x, y, c));
        }
        ASSERT_EQ(top, 1.0f) << x << "," << y;
      }
  }
  // Two layers: channels 2 and 3 stay empty.
  const Image two = make_weight_map(noise, 2, "test");
  for (int y = 0; y < two.height; ++y)
    for (int x = 0; x < two.width; ++x) ASSERT_EQ(two.at(x, y, 2) + two.at(x, y, 3), 0.0f);
}

// A map that is a linear ramp in u between texel centres: bilinear sampling and triangle interpolation are exact.
Image ramp(int size) {
  Image map(size, size, 4);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      map.at(x, y, 0) = float(x) / float(size);
      map.at(x, y, 1) = float(y) / float(size);
    }
  return map;
}

TEST(BlendWeights, VertexWeightsSampleTheMapAtUvOverScale) {
  const Image map = ramp(8);
  // uv (2, 1) over scale 4 is map UV (0.5, 0.25): texel coordinates (4, 2), between centres 3.5 and 4.5.
  const std::vector<glm::vec4> w = vertex_weights(map, {{2.0f, 1.0f}}, 4.0f);
  EXPECT_FLOAT_EQ(w[0].x, 3.5f / 8.0f);
  EXPECT_FLOAT_EQ(w[0].y, 1.5f / 8.0f);
}

TEST(BlendWeights, RasterizedVertexWeightsInterpolateOverTheTriangles) {
  MeshDesc grid;
  grid.kind = MeshKind::Grid;
  grid.resolution = 4;
  grid.uv_scale = {2.0f, 2.0f};
  const MeshData mesh = build_mesh(grid, "test");
  // Weights linear in the mesh's uv: any triangle reproduces them exactly at every covered texel centre.
  std::vector<glm::vec4> weights;
  for (const glm::vec2& uv : mesh.uvs) weights.push_back({uv.x / 2.0f, uv.y / 2.0f, 0.0f, 0.0f});
  Image texture(16, 16, 4);
  for (float& t : texture.texels) t = -1.0f;  // uncovered texels would keep this
  rasterize_vertex_weights(mesh.uvs, mesh.indices, weights, 2.0f, texture);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      // 1e-6: the barycentric interpolation in double of float vertex weights, stored as float.
      EXPECT_NEAR(texture.at(x, y, 0), (x + 0.5) / 16.0, 1e-6) << x << "," << y;
      EXPECT_NEAR(texture.at(x, y, 1), (y + 0.5) / 16.0, 1e-6) << x << "," << y;
    }
}

}  // namespace
}  // namespace qdmr
