// MikkTSpace's essentials (src/mesh/mikktspace.hpp) on cases whose answer is known by hand: a mirrored UV seam
// (the shared vertices split, each side its own tangent and sign) and corners weighted by their angle (with
// vertices of equal attributes welded), where qdmr's area-weighted generator gives other tangents; and the same
// bits for any number of threads.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "mesh/builders.hpp"
#include "mesh/mikktspace.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/mesh/mesh.hpp"

namespace qdmr {
namespace {

// The tangents of every vertex, then of every copy, and the vertex each copy copies.
struct Tangents {
  std::vector<glm::vec4> tangents;
  std::vector<std::uint32_t> copies_of;
};

Tangents mikktspace_tangents(const std::vector<float>& positions, const std::vector<float>& normals,
                             const std::vector<glm::vec2>& uvs, std::vector<std::uint32_t>& indices, Isa isa = Isa::Auto) {
  std::vector<glm::vec3> p, n;
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3) {
    p.emplace_back(positions[i], positions[i + 1], positions[i + 2]);
    n.emplace_back(normals[i], normals[i + 1], normals[i + 2]);
  }
  Tangents t;
  t.tangents.resize(uvs.size());
  const mesh_detail::MikkTSpaceCopies copies = mesh_detail::mikktspace_tangents(p, n, uvs, indices, t.tangents, isa);
  t.tangents.insert(t.tangents.end(), copies.tangents.begin(), copies.tangents.end());
  t.copies_of = copies.of;
  return t;
}

// The same tangents the slow way, written from the rules in mesh/mikktspace.hpp and not from its code: a map welds
// the vertices, every corner's weighted direction is computed alone with glm's scalar operations, each vertex kind
// sums its corners in triangle order, and the corners then take their sums (copies for mirrored UV seams).
// mikktspace_tangents batches, hashes and threads all of this: it must give these bits.
Tangents slow_tangents(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                       const std::vector<glm::vec2>& uvs, std::vector<std::uint32_t>& indices) {
  const std::size_t n = positions.size();
  const auto unit_or_zero = [](const glm::vec3& v) {
    const float len = glm::length(v);
    return std::abs(len) > std::numeric_limits<float>::min() && std::isfinite(len) ? v / len : glm::vec3(0.0f);
  };
  // Weld: a vertex's kind is the first vertex with its attributes (+0 and -0 alike).
  std::map<std::array<std::uint32_t, 8>, std::uint32_t> first;
  std::vector<std::uint32_t> same(n);
  for (std::uint32_t v = 0; v < n; ++v) {
    const float key[8] = {positions[v].x + 0.0f, positions[v].y + 0.0f, positions[v].z + 0.0f, normals[v].x + 0.0f,
                          normals[v].y + 0.0f,   normals[v].z + 0.0f,   uvs[v].x + 0.0f,       uvs[v].y + 0.0f};
    std::array<std::uint32_t, 8> bits{};
    std::memcpy(bits.data(), key, sizeof key);
    same[v] = first.emplace(bits, v).first->second;
  }
  struct Face {
    glm::vec3 along_u{0.0f};
    bool preserving = false, degenerate = true;
  };
  const auto face_of = [&](const std::uint32_t* c) {
    Face f;
    const glm::vec3 d1 = positions[c[1]] - positions[c[0]], d2 = positions[c[2]] - positions[c[0]];
    const glm::vec2 t21 = uvs[c[1]] - uvs[c[0]], t31 = uvs[c[2]] - uvs[c[0]];
    const float area = t21.x * t31.y - t21.y * t31.x;
    f.preserving = area > 0.0f;
    const glm::vec3 os = t31.y * d1 - t21.y * d2;
    const float len = glm::length(os);
    if (std::abs(area) > std::numeric_limits<float>::min() && std::abs(len) > std::numeric_limits<float>::min() &&
        std::isfinite(len)) {
      f.along_u = os * ((f.preserving ? 1.0f : -1.0f) / len);
      f.degenerate = false;
    }
    return f;
  };
  // A corner's direction (+u in the plane of its normal) times its angle (between its edges in that plane).
  const auto corner = [&](const std::uint32_t* c, int k, const glm::vec3& along_u) {
    const glm::vec3 nrm = unit_or_zero(normals[c[k]]);
    const auto in_plane = [&](const glm::vec3& v) { return v - nrm * glm::dot(nrm, v); };
    const glm::vec3 t = unit_or_zero(in_plane(along_u));
    const glm::vec3 p = positions[c[k]];
    const glm::vec3 a = in_plane(positions[c[(k + 2) % 3]] - p), b = in_plane(positions[c[(k + 1) % 3]] - p);
    const double lengths2 = double(glm::dot(a, a)) * double(glm::dot(b, b));
    const double cosine = lengths2 > 0.0 && lengths2 <= std::numeric_limits<double>::max()
                              ? double(glm::dot(a, b)) / std::sqrt(lengths2) : 0.0;
    return float(mesh_detail::deterministic_acos(cosine)) * t;
  };
  std::vector<glm::vec3> sums[2] = {std::vector<glm::vec3>(n, glm::vec3(0.0f)), std::vector<glm::vec3>(n, glm::vec3(0.0f))};
  std::vector<int> sides(n, 0);  // per kind: bit 0 a preserving corner, bit 1 a mirrored one
  bool any_mirrored = false;
  for (std::size_t f = 0; 3 * f < indices.size(); ++f) {
    const std::uint32_t* c = &indices[3 * f];
    const Face face = face_of(c);
    if (face.degenerate) continue;
    any_mirrored |= !face.preserving;
    for (int k = 0; k < 3; ++k) {
      sums[face.preserving ? 0 : 1][same[c[k]]] += corner(c, k, face.along_u);
      sides[same[c[k]]] |= face.preserving ? 1 : 2;
    }
  }
  const auto tangent = [&](std::uint32_t v, int side) {
    const glm::vec3 t = unit_or_zero(sums[side][same[v]]), nrm = unit_or_zero(normals[v]);
    return glm::vec4(t == glm::vec3(0.0f) ? mesh_detail::any_orthogonal(nrm == glm::vec3(0.0f) ? glm::vec3(0, 0, 1) : nrm) : t,
                     side == 0 ? 1.0f : -1.0f);
  };
  // Each vertex takes the side of its first corner (preserving when unused); a corner of the other side moves to
  // the vertex's copy. A degenerate face's corner: the preserving side if its kind has one, else the mirrored.
  Tangents out;
  std::vector<int> own(n, -1);
  std::vector<std::uint32_t> copy(n, 0);
  for (std::size_t f = 0; any_mirrored && 3 * f < indices.size(); ++f) {
    const Face face = face_of(&indices[3 * f]);
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& v = indices[3 * f + std::size_t(k)];
      const int side = face.degenerate ? ((sides[same[v]] & 1) || !(sides[same[v]] & 2) ? 0 : 1) : face.preserving ? 0 : 1;
      if (own[v] < 0) {
        own[v] = side;
      } else if (own[v] != side) {
        if (copy[v] == 0) {
          copy[v] = std::uint32_t(n + out.copies_of.size());
          out.copies_of.push_back(v);
          out.tangents.push_back(tangent(v, side));
        }
        v = copy[v];
      }
    }
  }
  std::vector<glm::vec4> own_tangents;
  for (std::uint32_t v = 0; v < n; ++v) own_tangents.push_back(tangent(v, own[v] == 1 ? 1 : 0));
  out.tangents.insert(out.tangents.begin(), own_tangents.begin(), own_tangents.end());
  return out;
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

TEST(MikkTSpace, TheSameBitsAsTheSlowPathOnRandomMeshes) {
  // Random meshes on a coarse lattice, so that vertices repeat (welded), triangles fold onto lines and points, UVs
  // collapse or mirror, normals are zero, +0 meets -0; some meshes have no mirrored triangle (no copies), some
  // vertices no corner. Every bit of the tangents, the rewritten indices and the copies must match.
  std::mt19937 random(55);
  const auto lattice = [&](int steps) { return float(int(random() % unsigned(2 * steps + 1)) - steps) / float(steps); };
  int with_copies = 0, welded = 0;
  // 1 to 3 threads with the corners in SSE2's four lanes; with AVX2's eight where the CPU has them.
  std::vector<std::pair<int, Isa>> runs = {{1, Isa::Sse42}, {2, Isa::Sse42}, {3, Isa::Sse42}};
  const std::vector<Isa> usable = usable_isas();
  if (std::find(usable.begin(), usable.end(), Isa::Avx2) != usable.end())
    runs.insert(runs.end(), {{1, Isa::Avx2}, {2, Isa::Avx2}, {3, Isa::Avx2}});
  else
    std::printf("no AVX2 on this CPU or in this build: the corners' eight lanes are not checked\n");
  for (int mesh = 0; mesh < 300; ++mesh) {
    const std::size_t vertices = 3 + random() % 200, triangles = 1 + random() % 300;
    const bool mirrors = mesh % 3 != 0;  // else every triangle keeps its UV orientation
    std::vector<glm::vec3> positions, normals;
    std::vector<glm::vec2> uvs;
    for (std::size_t v = 0; v < vertices; ++v) {
      if (v > 0 && random() % 5 == 0) {  // a vertex again under another index, some of its zeros as -0
        const std::size_t of = random() % v;
        const auto signed_zeros = [&](auto x) {
          for (int c = 0; c < x.length(); ++c)
            if (x[c] == 0.0f && random() % 2) x[c] = -x[c];
          return x;
        };
        positions.push_back(signed_zeros(positions[of]));
        normals.push_back(signed_zeros(normals[of]));
        uvs.push_back(signed_zeros(uvs[of]));
        continue;
      }
      positions.emplace_back(lattice(4), lattice(4), lattice(2));
      // A quarter of the meshes have unit normals (of length 1 in float: their divisions are skipped where four
      // corners of a batch have them), the others normals of any length.
      glm::vec3 unit_normal(0.0f);
      unit_normal[int(random() % 3)] = random() % 2 ? 1.0f : -1.0f;
      normals.push_back(random() % 8 == 0 ? glm::vec3(0.0f)
                        : mesh % 4 == 1   ? unit_normal
                                          : glm::vec3(lattice(3), lattice(3), lattice(3) + 1.5f));
      uvs.emplace_back(lattice(4), lattice(4));
    }
    std::vector<std::uint32_t> indices;
    for (std::size_t t = 0; t < triangles; ++t) {
      std::uint32_t c[3];
      for (auto& i : c) i = std::uint32_t(random() % vertices);
      if (!mirrors) {  // keep the UV area >= 0: swap two corners of a mirrored one
        const glm::vec2 a = uvs[c[1]] - uvs[c[0]], b = uvs[c[2]] - uvs[c[0]];
        if (a.x * b.y - a.y * b.x < 0.0f) std::swap(c[1], c[2]);
      }
      indices.insert(indices.end(), {c[0], c[1], c[2]});
    }
    std::vector<float> flat_positions, flat_normals;
    for (std::size_t v = 0; v < vertices; ++v) {
      flat_positions.insert(flat_positions.end(), {positions[v].x, positions[v].y, positions[v].z});
      flat_normals.insert(flat_normals.end(), {normals[v].x, normals[v].y, normals[v].z});
    }
    std::vector<std::uint32_t> slow_indices = indices;
    const Tangents slow = slow_tangents(positions, normals, uvs, slow_indices);
    with_copies += !slow.copies_of.empty();
    for (const auto& run : runs) {
      const int threads = run.first;  // not a structured binding: clang 14 lets no lambda capture one
      const Isa isa = run.second;
      std::vector<std::uint32_t> fast_indices = indices;
      tbb::task_arena arena(threads);
      const Tangents fast =
          arena.execute([&] { return mikktspace_tangents(flat_positions, flat_normals, uvs, fast_indices, isa); });
      ASSERT_EQ(fast_indices, slow_indices) << "mesh " << mesh << ", " << threads << " threads, " << isa_name(isa);
      ASSERT_EQ(fast.copies_of, slow.copies_of) << "mesh " << mesh;
      ASSERT_EQ(fast.tangents.size(), slow.tangents.size()) << "mesh " << mesh;
      for (std::size_t v = 0; v < slow.tangents.size(); ++v)
        ASSERT_EQ(std::memcmp(&fast.tangents[v], &slow.tangents[v], sizeof(glm::vec4)), 0)
            << "mesh " << mesh << ", " << threads << " threads, " << isa_name(isa) << ", vertex " << v << ": " << fast.tangents[v].x << " "
            << fast.tangents[v].y << " " << fast.tangents[v].z << " " << fast.tangents[v].w << " against "
            << slow.tangents[v].x << " " << slow.tangents[v].y << " " << slow.tangents[v].z << " " << slow.tangents[v].w;
    }
    std::map<std::array<float, 3>, int> distinct;
    for (const glm::vec3& p : positions) ++distinct[{p.x, p.y, p.z}];
    welded += distinct.size() < positions.size();
  }
  // The cases the test is for did happen.
  EXPECT_GT(with_copies, 100);
  EXPECT_GT(welded, 200);
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
