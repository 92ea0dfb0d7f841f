// MikkTSpace's essentials (mesh/mikktspace.hpp).
#include "mesh/mikktspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "mesh/builders.hpp"

namespace qdmr::mesh_detail {

namespace {

glm::vec3 at3(const std::vector<float>& v, std::uint32_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }

bool not_zero(float x) { return std::abs(x) > std::numeric_limits<float>::min(); }

glm::vec3 unit_or_zero(const glm::vec3& v) {
  const float len = glm::length(v);
  return not_zero(len) && std::isfinite(len) ? v / len : glm::vec3(0.0f);
}

// The component of v in the plane whose normal is n (unit), normalised (zero when v is along n).
glm::vec3 in_plane(const glm::vec3& v, const glm::vec3& n) { return unit_or_zero(v - n * glm::dot(n, v)); }

// A triangle's +u direction (unit, or zero) and UV orientation, as mikktspace.c's InitTriInfo computes them.
struct Face {
  glm::vec3 along_u{0.0f};
  bool preserving = false;  // UV area > 0
  bool degenerate = true;   // no usable UV derivative
};

Face face_of(const std::vector<float>& positions, const std::vector<glm::vec2>& uvs, const std::uint32_t* corner) {
  Face f;
  const glm::vec3 d1 = at3(positions, corner[1]) - at3(positions, corner[0]);
  const glm::vec3 d2 = at3(positions, corner[2]) - at3(positions, corner[0]);
  const glm::vec2 t21 = uvs[corner[1]] - uvs[corner[0]], t31 = uvs[corner[2]] - uvs[corner[0]];
  const float area = t21.x * t31.y - t21.y * t31.x;
  f.preserving = area > 0.0f;
  const glm::vec3 os = t31.y * d1 - t21.y * d2;
  const float len = glm::length(os);
  if (not_zero(area) && not_zero(len) && std::isfinite(len)) {
    f.along_u = os * ((f.preserving ? 1.0f : -1.0f) / len);
    f.degenerate = false;
  }
  return f;
}

}  // namespace

MikkTSpaceTangents mikktspace_tangents(const std::vector<float>& positions, const std::vector<float>& normals,
                                       const std::vector<glm::vec2>& uvs, std::vector<std::uint32_t>& indices) {
  // Working memory, beside the result: 4 bytes a vertex (its kind), 12 (the preserving sums), 1 (flags) and 1 a
  // triangle; 8 bytes a vertex while welding; 16 more a vertex where UVs are mirrored.
  const std::size_t n = uvs.size();
  const auto normal = [&](std::uint32_t v) { return unit_or_zero(at3(normals, v)); };
  // Vertices with equal attributes are one vertex (mikktspace.c welds them): `same[v]` is the first of v's kind.
  // Sorted by a 32-bit hash of the attributes (+0 and -0 alike, as mikktspace.c's == sees them), then compared in
  // full.
  std::vector<std::uint32_t> same(n);
  {
    const auto key = [&](std::uint32_t v) {
      return std::array<float, 8>{positions[3 * v] + 0.0f, positions[3 * v + 1] + 0.0f, positions[3 * v + 2] + 0.0f,
                                  normals[3 * v] + 0.0f, normals[3 * v + 1] + 0.0f, normals[3 * v + 2] + 0.0f,
                                  uvs[v].x + 0.0f, uvs[v].y + 0.0f};
    };
    std::vector<std::uint64_t> order(n);  // hash << 32 | vertex
    for (std::uint32_t v = 0; v < n; ++v) {
      std::uint64_t h = 0xcbf29ce484222325ull;
      for (const float f : key(v)) {
        std::uint32_t bits = 0;
        std::memcpy(&bits, &f, sizeof bits);
        h = (h ^ bits) * 0x100000001b3ull;
        h ^= h >> 29;
      }
      order[v] = (h >> 32) << 32 | v;
    }
    std::sort(order.begin(), order.end());
    const auto vertex_at = [&](std::size_t k) { return std::uint32_t(order[k] & 0xffffffffu); };
    for (std::size_t run = 0; run < n;) {
      std::size_t end = run + 1;
      while (end < n && order[end] >> 32 == order[run] >> 32) ++end;
      for (std::size_t k = run; k < end; ++k) {  // equal hashes: the first earlier vertex with equal attributes
        const std::uint32_t v = vertex_at(k);
        same[v] = v;
        for (std::size_t j = run; j < k; ++j)
          if (same[vertex_at(j)] == vertex_at(j) && key(vertex_at(j)) == key(v)) {
            same[v] = vertex_at(j);
            break;
          }
      }
      run = end;
    }
  }
  // Per vertex kind and orientation: the angle-weighted sum of its corners' directions (the mirrored sums only
  // once a mirrored triangle comes). flags: bit 0 / 1 the kind has a preserving / mirrored sum; bits 2-3 the
  // orientation of the vertex's own entry (1 preserving, 2 mirrored, 0 unset).
  std::vector<glm::vec3> preserving_sum(n, glm::vec3(0.0f)), mirrored_sum;
  std::vector<std::uint8_t> flags(n, 0);
  std::vector<std::uint8_t> face_state(indices.size() / 3);  // bit 0 preserving, bit 1 degenerate
  for (std::size_t f = 0; f < face_state.size(); ++f) {
    const std::uint32_t* corner = &indices[3 * f];
    const Face face = face_of(positions, uvs, corner);
    face_state[f] = std::uint8_t((face.preserving ? 1 : 0) | (face.degenerate ? 2 : 0));
    if (face.degenerate) continue;
    if (!face.preserving && mirrored_sum.empty()) mirrored_sum.assign(n, glm::vec3(0.0f));
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = corner[k];
      const glm::vec3 nv = normal(v);
      const glm::vec3 t = in_plane(face.along_u, nv);
      // The corner's angle between its edges projected onto the normal's plane (a zero edge: pi / 2, as
      // mikktspace.c's zero vectors give), from one square root instead of two normalisations.
      const glm::vec3 p = at3(positions, v);
      const glm::vec3 a = at3(positions, corner[(k + 2) % 3]) - p, b = at3(positions, corner[(k + 1) % 3]) - p;
      const glm::vec3 a_in = a - nv * glm::dot(nv, a), b_in = b - nv * glm::dot(nv, b);
      const double lengths2 = double(glm::dot(a_in, a_in)) * double(glm::dot(b_in, b_in));
      const double cosine = lengths2 > 0.0 && std::isfinite(lengths2) ? double(glm::dot(a_in, b_in)) / std::sqrt(lengths2) : 0.0;
      const float angle = float(deterministic_acos(cosine));
      (face.preserving ? preserving_sum : mirrored_sum)[same[v]] += angle * t;
      flags[same[v]] |= face.preserving ? 1 : 2;
    }
  }
  // Each corner takes its vertex kind's sum for its face's orientation (a degenerate face: the preserving sum if
  // its vertex has one, else the mirrored one). A vertex whose corners differ in orientation is copied.
  MikkTSpaceTangents out;
  out.tangents.resize(n);
  std::vector<std::uint32_t> copy;  // per vertex, its copy for the other orientation (0: none yet)
  const auto tangent = [&](std::uint32_t v, int side) {
    const glm::vec3 t = unit_or_zero(side == 0 ? preserving_sum[same[v]] : mirrored_sum[same[v]]);
    return glm::vec4(t == glm::vec3(0.0f) ? any_orthogonal(normal(v) == glm::vec3(0.0f) ? glm::vec3(0, 0, 1) : normal(v)) : t,
                     side == 0 ? 1.0f : -1.0f);
  };
  for (std::size_t f = 0; f < face_state.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& v = indices[3 * f + std::size_t(k)];
      const std::uint8_t kind = flags[same[v]];
      const int side = (face_state[f] & 2) ? ((kind & 1) || !(kind & 2) ? 0 : 1) : ((face_state[f] & 1) ? 0 : 1);
      const int own = (flags[v] >> 2) & 3;
      if (own == 0) {
        flags[v] = std::uint8_t(flags[v] | (side + 1) << 2);
        out.tangents[v] = tangent(v, side);
      } else if (own != side + 1) {
        if (copy.empty()) copy.assign(n, 0);
        if (copy[v] == 0) {
          copy[v] = std::uint32_t(n + out.copies_of.size());
          out.copies_of.push_back(v);
          out.tangents.push_back(tangent(v, side));
        }
        v = copy[v];
      }
    }
  for (std::size_t v = 0; v < n; ++v)
    if (((flags[v] >> 2) & 3) == 0) out.tangents[v] = tangent(std::uint32_t(v), 0);  // no corner: any tangent
  return out;
}

}  // namespace qdmr::mesh_detail
