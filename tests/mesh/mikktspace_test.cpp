// MikkTSpace's essentials (src/mesh/mikktspace.hpp) on cases whose answer is known by hand: a mirrored UV seam
// (the shared vertices split, each side its own tangent and sign) and corners weighted by their angle (with
// vertices of equal attributes welded), where qdmr's area-weighted generator gives other tangents; and the same
// bits for any number of threads.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>

#include "mesh/mikktspace.hpp"
#include "qdmr/mesh/mesh.hpp"

namespace qdmr {
namespace {

// The tangents of every vertex, then of every copy, and the vertex each copy copies.
struct Tangents {
  std::vector<glm::vec4> tangents;
  std::vector<std::uint32_t> copies_of;
};

Tangents mikktspace_tangents(const std::vector<float>& positions, const std::vector<float>& normals,
                             const std::vector<glm::vec2>& uvs, std::vector<std::uint32_t>& indices) {
  std::vector<glm::vec3> p, n;
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3) {
    p.emplace_back(positions[i], positions[i + 1], positions[i + 2]);
    n.emplace_back(normals[i], normals[i + 1], normals[i + 2]);
  }
  Tangents t;
  t.tangents.resize(uvs.size());
  const mesh_detail::MikkTSpaceCopies copies = mesh_detail::mikktspace_tangents(p, n, uvs, indices, t.tangents);
  t.tangents.insert(t.tangents.end(), copies.tangents.begin(), copies.tangents.end());
  t.copies_of = copies.of;
  return t;
}

TEST(MikkTSpace, AMirroredSeamSplitsItsVertices) {
  // Two unit squares side by side in z = 0 facing +z; u runs +x on the left, -x on the right (mirrored), v +y.
  const std::vector<float> positions = {-1, -1, 0, 0, -1, 0, 0, 1, 0, -1, 1, 0, 1, -1, 0, 1, 1, 0};
  const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  const std::vector<glm::vec2> uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {0, 1}};
  std::vector<std::uint32_t> indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  const Tangents t = mikktspace_tangents(positions, normals, uvs, indices);
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
  const Tangents t = mikktspace_tangents(positions, normals, uvs, indices);
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

TEST(MikkTSpace, AnyNumberOfThreadsGivesTheSameBits) {
  // A bumpy 64 x 64 grid whose right half has mirrored UVs (a seam down the middle), with vertices repeated under
  // other indices (welded) and a triangle without UV area: threads split the vertices, each sums its own corners.
  const int size = 64;
  std::vector<float> positions, normals;
  std::vector<glm::vec2> uvs;
  for (int j = 0; j <= size; ++j)
    for (int i = 0; i <= size; ++i) {
      const float x = float(i) / size, y = float(j) / size, z = 0.1f * std::sin(9.0f * x) * std::cos(7.0f * y);
      positions.insert(positions.end(), {x, y, z});
      normals.insert(normals.end(), {-0.9f * std::cos(9.0f * x) * std::cos(7.0f * y), 0.7f * std::sin(9.0f * x) * std::sin(7.0f * y), 1.0f});
      uvs.emplace_back(i <= size / 2 ? x : 1.0f - x, y);
    }
  std::vector<std::uint32_t> indices;
  const auto vertex = [&](int i, int j) { return std::uint32_t(j * (size + 1) + i); };
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i)
      indices.insert(indices.end(), {vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
  for (std::uint32_t v = 0; v < 200; v += 7) {  // copies of vertices v, used by the triangles that used v
    positions.insert(positions.end(), {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]});
    normals.insert(normals.end(), {normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]});
    uvs.push_back(uvs[v]);
    for (std::size_t c = 0; c < indices.size(); c += 2)
      if (indices[c] == v) indices[c] = std::uint32_t(uvs.size() - 1);
  }
  indices.insert(indices.end(), {vertex(3, 3), vertex(4, 4), vertex(3, 3)});
  std::vector<std::vector<std::uint32_t>> rewritten;
  std::vector<Tangents> results;
  for (const int threads : {1, 2, 3, 8}) {
    std::vector<std::uint32_t> copy = indices;
    tbb::task_arena arena(threads);
    results.push_back(arena.execute([&] { return mikktspace_tangents(positions, normals, uvs, copy); }));
    rewritten.push_back(copy);
  }
  EXPECT_GT(results[0].copies_of.size(), 0u);  // the seam splits vertices
  for (std::size_t r = 1; r < results.size(); ++r) {
    EXPECT_EQ(rewritten[r], rewritten[0]);
    EXPECT_EQ(results[r].copies_of, results[0].copies_of);
    ASSERT_EQ(results[r].tangents.size(), results[0].tangents.size());
    EXPECT_EQ(std::memcmp(results[r].tangents.data(), results[0].tangents.data(), results[0].tangents.size() * sizeof(glm::vec4)), 0) << r;
  }
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
