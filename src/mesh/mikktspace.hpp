#pragma once
// Tangents the way glTF 2.0 asks for them when an asset has none: MikkTSpace (Morten Mikkelsen's reference
// implementation, mikktspace.c, as Blender and the glTF tools use it). Debian packages no MikkTSpace library, so
// its essentials are written here (a packaged library should do this; docs/scene-format.md says what differs):
//   - per triangle, the direction of +u (dP/du) from its UV derivatives, and its UV orientation (the sign of the
//     UV area); triangles whose UV area is zero are degenerate and take their vertices' result;
//   - per corner, that direction projected onto the plane of the corner's normal and normalised, weighted by the
//     corner's angle (between its two edges projected onto that plane);
//   - vertices identified by their attributes (position, normal, UV equal), not by their index, as mikktspace.c
//     does, and their corners grouped by UV orientation: the corners of one vertex and one orientation share one
//     tangent (the normalised sum), w = +1 where the UV orientation is preserved, -1 where it is mirrored;
//   - a vertex used by corners of both orientations (a mirrored UV seam) is split: the mirrored corners get a copy.
// Not done: mikktspace.c's grouping by edge-connected fans (corners of one vertex and orientation that are not
// connected through shared edges share a tangent here) and its angular split threshold (off by default there too).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "qdmr/core/isa.hpp"

namespace qdmr::mesh_detail {

// The vertices a mirrored UV seam splits: copy k of a mesh of n vertices is vertex n + k, a copy of vertex of[k]
// with the tangent tangents[k].
struct MikkTSpaceCopies {
  std::vector<std::uint32_t> of;
  std::vector<glm::vec4> tangents;
};

// positions and normals per vertex (normals need not be unit length), uvs one per vertex (qdmr's: v up),
// `indices` 3 per triangle, rewritten where a corner moves to a copy of its vertex; `tangents` (one per vertex) is
// written. The weld and the work over triangles run on threads, each summing the corners of its own vertices in
// triangle order (the triangles' directions and their corners' angles four or eight triangles at a time in SIMD
// lanes, rounded as the scalar formulas): the same bits for any thread count. Working memory beside the result: 4 bytes
// a vertex (its kind), 1 (flags); welding hashes in `tangents` before they are written; where UVs are mirrored 16
// more (the mirrored sums, the copies).
// The corners' arithmetic runs in SSE2's four lanes, or AVX2's eight where the CPU has them and `isa` (Auto: the
// one the draw would take) allows them (mesh/corner_batch.hpp): the same bits either way.
MikkTSpaceCopies mikktspace_tangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                     std::span<const glm::vec2> uvs, std::span<std::uint32_t> indices,
                                     std::span<glm::vec4> tangents, Isa isa = Isa::Auto);

// The most parts (the vertices' shares, one a thread of the caller's arena) a call of mikktspace_tangents has
// split its work into since the last take; taking it resets it. A seam for tests: the threads a load ran on.
std::size_t take_mikktspace_parts_seen();

// acos from +, *, / and sqrt only (Cephes' asinf polynomial, in double): the same bits on every machine, where
// libm's acos may take an FMA variant on some CPUs. Accurate to about 1e-7; x is clamped to [-1, 1].
inline double deterministic_acos(double x) {
  x = std::clamp(x, -1.0, 1.0);
  const double half_pi = 1.57079632679489661923;
  // asin(a) for 0 <= a <= 0.5: a + a z P(z), z = a^2 (Cephes asinf).
  const auto asin_small = [](double a) {
    const double z = a * a;
    return a + a * z * ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z +
                        1.6666752422e-1);
  };
  const double a = std::abs(x);
  // asin(a) = pi/2 - 2 asin(sqrt((1 - a) / 2)) above 0.5.
  const double asin_a = a <= 0.5 ? asin_small(a) : half_pi - 2.0 * asin_small(std::sqrt((1.0 - a) * 0.5));
  return x < 0.0 ? half_pi + asin_a : half_pi - asin_a;
}

}  // namespace qdmr::mesh_detail
