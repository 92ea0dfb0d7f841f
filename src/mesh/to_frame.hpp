#pragma once
// A glTF primitive's vertices moved into qdmr's frame (mesh/gltf.cpp's add_smooth), in double as glm computes it.
#include <cstddef>
#include <span>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace qdmr::mesh_detail {

// One vertex, in place: the position by `world` (glm's dmat4 x dvec4(p, 1)); the normal by `normal_matrix`, over its
// length, or (0, 0, 1) where that length is 0 or not finite; the tangent's xyz by world's upper 3x3, over its length,
// or any_orthogonal(the new normal) where that is 0 or not finite; its w -1 where (w < 0) differs from `mirrored`,
// else +1. Each result rounded to float.
void to_frame_one(glm::vec3& position, glm::vec3& normal, glm::vec4& tangent, const glm::dmat4& world,
                  const glm::dmat3& normal_matrix, bool mirrored);

// to_frame_one on every vertex of the three arrays (one size), on threads, two vertices at a time in SSE2's double
// lanes (each lane takes glm's operations in their order: a column sum (a + b) + c, (a + b) + (c + d) for dmat4;
// a length the square root of (x x + y y) + z z; a vector over a scalar three divisions): the same bits.
void to_frame(std::span<glm::vec3> positions, std::span<glm::vec3> normals, std::span<glm::vec4> tangents,
              const glm::dmat4& world, const glm::dmat3& normal_matrix, bool mirrored);

}  // namespace qdmr::mesh_detail
