// MikkTSpace's essentials (mesh/mikktspace.hpp).
#include "mesh/mikktspace.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>

#include "mesh/builders.hpp"

namespace qdmr::mesh_detail {

namespace {

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

Face face_of(std::span<const glm::vec3> positions, std::span<const glm::vec2> uvs, const std::uint32_t* corner) {
  Face f;
  const glm::vec3 d1 = positions[corner[1]] - positions[corner[0]];
  const glm::vec3 d2 = positions[corner[2]] - positions[corner[0]];
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

// Vertices with equal attributes are one vertex (mikktspace.c welds them): same[v] is the first vertex of v's kind.
// A hash table (+0 and -0 alike, as mikktspace.c's == sees them) filled in vertex order, so the first of a kind is
// the one in the table.
std::vector<std::uint32_t> weld(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                std::span<const glm::vec2> uvs) {
  const std::size_t n = positions.size();
  const auto key = [&](std::uint32_t v) {
    return std::array<float, 8>{positions[v].x + 0.0f, positions[v].y + 0.0f, positions[v].z + 0.0f,
                                normals[v].x + 0.0f,   normals[v].y + 0.0f,   normals[v].z + 0.0f,
                                uvs[v].x + 0.0f,       uvs[v].y + 0.0f};
  };
  const auto hash = [&](std::uint32_t v) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const float f : key(v)) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, sizeof bits);
      h = (h ^ bits) * 0x100000001b3ull;
      h ^= h >> 29;
    }
    return h;
  };
  // Linear probing at most 2/3 full; a hash's slot is its top 32 bits scaled to the capacity.
  const std::size_t capacity = n + n / 2 + 1;
  std::vector<std::uint32_t> table(capacity, 0);  // vertex + 1, 0: empty
  std::vector<std::uint32_t> same(n);
  // Batches: the slots of a batch are asked for before they are probed.
  constexpr std::size_t kBatch = 32;
  std::array<std::size_t, kBatch> slot{};
  for (std::size_t first = 0; first < n; first += kBatch) {
    const std::size_t count = std::min(kBatch, n - first);
    for (std::size_t k = 0; k < count; ++k) {
      slot[k] = std::size_t(((hash(std::uint32_t(first + k)) >> 32) * capacity) >> 32);
      __builtin_prefetch(&table[slot[k]]);
    }
    for (std::size_t k = 0; k < count; ++k) {
      const auto v = std::uint32_t(first + k);
      const std::array<float, 8> mine = key(v);
      for (std::size_t at = slot[k];; at = at + 1 == capacity ? 0 : at + 1) {
        if (table[at] == 0) {
          table[at] = v + 1;
          same[v] = v;
          break;
        }
        if (key(table[at] - 1) == mine) {
          same[v] = table[at] - 1;
          break;
        }
      }
    }
  }
  return same;
}

}  // namespace

MikkTSpaceCopies mikktspace_tangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                     std::span<const glm::vec2> uvs, std::span<std::uint32_t> indices,
                                     std::span<glm::vec4> tangents) {
  const std::size_t n = positions.size(), faces = indices.size() / 3;
  const auto normal = [&](std::uint32_t v) { return unit_or_zero(normals[v]); };
  const std::vector<std::uint32_t> same = weld(positions, normals, uvs);

  // Whether any triangle has mirrored UVs (only then do vertices split, and need mirrored sums).
  const bool any_mirrored = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, faces, 16384), false,
      [&](const tbb::blocked_range<std::size_t>& range, bool mirrored) {
        for (std::size_t f = range.begin(); f != range.end() && !mirrored; ++f) {
          const Face face = face_of(positions, uvs, &indices[3 * f]);
          mirrored = !face.degenerate && !face.preserving;
        }
        return mirrored;
      },
      [](bool a, bool b) { return a || b; });

  // Per vertex kind and orientation: the angle-weighted sum of its corners' directions, the preserving sums in
  // `tangents` (xyz), the mirrored ones beside them. Each thread takes a range of kinds and sums their corners in
  // triangle order. flags: bit 0 / 1 the kind has a preserving / mirrored sum; bits 2-3 the orientation of the
  // vertex's own entry (1 preserving, 2 mirrored, 0 unset).
  std::fill(tangents.begin(), tangents.end(), glm::vec4(0.0f));
  std::vector<glm::vec3> mirrored_sum(any_mirrored ? n : 0, glm::vec3(0.0f));
  std::vector<std::uint8_t> flags(n, 0);
  const std::size_t parts = std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
  tbb::parallel_for(std::size_t(0), parts, [&](std::size_t part) {
    const std::uint32_t lo = std::uint32_t(n * part / parts), hi = std::uint32_t(n * (part + 1) / parts);
    const auto mine = [&](std::uint32_t v) { return same[v] >= lo && same[v] < hi; };
    for (std::size_t f = 0; f < faces; ++f) {
      const std::uint32_t* corner = &indices[3 * f];
      if (!(mine(corner[0]) || mine(corner[1]) || mine(corner[2]))) continue;
      const Face face = face_of(positions, uvs, corner);
      if (face.degenerate) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = corner[k];
        if (!mine(v)) continue;
        const glm::vec3 nv = normal(v);
        const glm::vec3 t = in_plane(face.along_u, nv);
        // The corner's angle between its edges projected onto the normal's plane (a zero edge: pi / 2, as
        // mikktspace.c's zero vectors give), from one square root instead of two normalisations.
        const glm::vec3 p = positions[v];
        const glm::vec3 a = positions[corner[(k + 2) % 3]] - p, b = positions[corner[(k + 1) % 3]] - p;
        const glm::vec3 a_in = a - nv * glm::dot(nv, a), b_in = b - nv * glm::dot(nv, b);
        const double lengths2 = double(glm::dot(a_in, a_in)) * double(glm::dot(b_in, b_in));
        const double cosine = lengths2 > 0.0 && std::isfinite(lengths2) ? double(glm::dot(a_in, b_in)) / std::sqrt(lengths2) : 0.0;
        const float angle = float(deterministic_acos(cosine));
        if (face.preserving) {
          glm::vec3 sum(tangents[same[v]]);
          sum += angle * t;
          tangents[same[v]] = glm::vec4(sum, 0.0f);
        } else {
          mirrored_sum[same[v]] += angle * t;
        }
        flags[same[v]] |= face.preserving ? 1 : 2;
      }
    }
  });

  const auto tangent = [&](std::uint32_t v, int side) {
    const glm::vec3 t = unit_or_zero(side == 0 ? glm::vec3(tangents[same[v]]) : mirrored_sum[same[v]]);
    return glm::vec4(t == glm::vec3(0.0f) ? any_orthogonal(normal(v) == glm::vec3(0.0f) ? glm::vec3(0, 0, 1) : normal(v)) : t,
                     side == 0 ? 1.0f : -1.0f);
  };
  // Each corner takes its vertex kind's sum for its face's orientation (a degenerate face: the preserving sum if
  // its vertex has one, else the mirrored one). A vertex whose corners differ in orientation is copied. Without
  // mirrored triangles every corner takes the preserving sum.
  MikkTSpaceCopies copies;
  if (any_mirrored) {
    std::vector<std::uint32_t> copy(n, 0);  // per vertex, its copy for the other orientation (0: none yet)
    for (std::size_t f = 0; f < faces; ++f) {
      const Face face = face_of(positions, uvs, &indices[3 * f]);
      for (int k = 0; k < 3; ++k) {
        std::uint32_t& v = indices[3 * f + std::size_t(k)];
        const std::uint8_t kind = flags[same[v]];
        const int side = face.degenerate ? ((kind & 1) || !(kind & 2) ? 0 : 1) : face.preserving ? 0 : 1;
        const int own = (flags[v] >> 2) & 3;
        if (own == 0) {
          flags[v] = std::uint8_t(flags[v] | (side + 1) << 2);
        } else if (own != side + 1) {
          if (copy[v] == 0) {
            copy[v] = std::uint32_t(n + copies.of.size());
            copies.of.push_back(v);
            copies.tangents.push_back(tangent(v, side));
          }
          v = copy[v];
        }
      }
    }
  }
  // Each vertex's own tangent (a vertex no corner uses: any). The vertices that are not the first of their kind
  // first: they read the sums of their kind's first vertex, which is then overwritten by its own.
  const auto finish = [&](bool first_of_kind) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t v = range.begin(); v != range.end(); ++v)
        if ((same[v] == v) == first_of_kind) tangents[v] = tangent(std::uint32_t(v), ((flags[v] >> 2) & 3) == 2 ? 1 : 0);
    });
  };
  finish(false);
  finish(true);
  return copies;
}

}  // namespace qdmr::mesh_detail
