// MikkTSpace's essentials (src/mesh/mikktspace.hpp) on cases whose answer is known by hand: a mirrored UV seam
// (the shared vertices split, each side its own tangent and sign) and corners weighted by their angle (with
// vertices of equal attributes welded), where qdmr's area-weighted generator gives other tangents.
#include <gtest/gtest.h>

#include <cmath>

#include "mesh/mikktspace.hpp"
#include "qdmr/mesh/mesh.hpp"

namespace qdmr {
namespace {

using mesh_detail::mikktspace_tangents;

TEST(MikkTSpace, AMirroredSeamSplitsItsVertices) {
  // Two unit squares side by side in z = 0 facing +z; u runs +x on the left, -x on the right (mirrored), v +y.
  const std::vector<float> positions = {-1, -1, 0, 0, -1, 0, 0, 1, 0, -1, 1, 0, 1, -1, 0, 1, 1, 0};
  const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  const std::vector<glm::vec2> uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {0, 1}};
  std::vector<std::uint32_t> indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  const mesh_detail::MikkTSpaceTangents t = mikktspace_tangents(positions, normals, uvs, indices);
  // Vertices 1 and 2 are on the seam: the mirrored corners move to copies 6 and 7.
  EXPECT_EQ(t.copies_of, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(indices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 6, 4, 5, 6, 5, 7}));
  ASSERT_EQ(t.tangents.size(), 8u);
  // Exact: every direction is +-x and every corner's weight positive.
  for (const std::uint32_t v : {0u, 1u, 2u, 3u}) EXPECT_EQ(t.tangents[v], glm::vec4(1, 0, 0, 1)) << v;
  for (const std::uint32_t v : {4u, 5u, 6u, 7u}) EXPECT_EQ(t.tangents[v], glm::vec4(-1, 0, 0, -1)) << v;
  // qdmr's area-weighted generator averages +x and -x at the seam: vertex 1 (in one triangle on the left, two on
  // the right) points -x for both sides.
  MeshData m;
  for (std::size_t v = 0; v < 6; ++v) {
    m.positions.emplace_back(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    m.normals.emplace_back(0, 0, 1);
  }
  m.uvs = uvs;
  m.indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  compute_tangents(m);
  EXPECT_EQ(glm::vec3(m.tangents[1]), glm::vec3(-1, 0, 0));
}

TEST(MikkTSpace, CornersWeighByAngleAndEqualVerticesAreOne) {
  // Corner 0 of triangle A (90 degrees) has +u along +x; corner 3 of triangle B (45 degrees), a copy of vertex 0
  // with equal attributes, has +u along (1, 1) / sqrt 2 (B's UVs: u = x, v = y - x).
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, -1, 1, 0};
  const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  const std::vector<glm::vec2> uvs = {{0, 0}, {1, 0}, {0, 1}, {0, 0}, {-1, 2}};
  std::vector<std::uint32_t> indices = {0, 1, 2, 3, 2, 4};
  const mesh_detail::MikkTSpaceTangents t = mikktspace_tangents(positions, normals, uvs, indices);
  EXPECT_TRUE(t.copies_of.empty());
  const double pi = 3.14159265358979323846, s = std::sqrt(0.5);
  const double x = pi / 2 + pi / 4 * s, y = pi / 4 * s, len = std::hypot(x, y);
  // 1e-6: float arithmetic on unit vectors and the acos polynomial's 1e-7.
  for (const std::uint32_t v : {0u, 3u}) {
    EXPECT_NEAR(t.tangents[v].x, x / len, 1e-6) << v;
    EXPECT_NEAR(t.tangents[v].y, y / len, 1e-6) << v;
    EXPECT_EQ(t.tangents[v].z, 0.0f);
    EXPECT_EQ(t.tangents[v].w, 1.0f);
  }
  // Area weights (both triangles have area 1/2) would give (1 + s, s) normalised: 22.5 degrees, not 14.6.
  EXPECT_GT(std::abs(t.tangents[0].y - float(s / std::hypot(1 + s, s))), 0.1f);
}

TEST(MikkTSpace, DeterministicAcosIsAcos) {
  // 2e-7: the polynomial's error (Cephes asinf, float accuracy), evaluated in double.
  for (int i = -1000; i <= 1000; ++i) {
    const double c = i / 1000.0;
    EXPECT_NEAR(mesh_detail::deterministic_acos(c), std::acos(c), 2e-7) << c;
  }
  EXPECT_EQ(mesh_detail::deterministic_acos(2.0), mesh_detail::deterministic_acos(1.0));
}

}  // namespace
}  // namespace qdmr
