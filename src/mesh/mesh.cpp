// build_mesh: parameter checks shared by every kind, then the kind's builder.
#include <cmath>
#include <sstream>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "mesh/builders.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"

namespace qdmr {
namespace mesh_detail {

void check_triangle_count(std::uint64_t triangles, const std::string& where) {
  if (triangles > limits::kMaxTriangles) {
    std::ostringstream s;
    s << triangles << " triangles exceed the limit of " << limits::kMaxTriangles;
    throw Error(where, s.str());
  }
}

glm::vec3 any_orthogonal(const glm::vec3& n) {
  // The axis least aligned with n gives the best-conditioned projection.
  const glm::vec3 a = glm::abs(n);
  const glm::vec3 axis = (a.x <= a.y && a.x <= a.z) ? glm::vec3(1, 0, 0)
                         : (a.y <= a.z)             ? glm::vec3(0, 1, 0)
                                                    : glm::vec3(0, 0, 1);
  const float nn = glm::dot(n, n);
  if (!(nn > 0.0f) || !std::isfinite(nn)) return {1.0f, 0.0f, 0.0f};
  const glm::vec3 t = axis - n * (glm::dot(n, axis) / nn);
  return glm::normalize(t);
}

}  // namespace mesh_detail

namespace {

bool positive(float x) { return std::isfinite(x) && x > 0.0f; }

void check_size(const MeshDesc& desc, bool both, const std::string& where) {
  if (!positive(desc.size.x) || (both && !positive(desc.size.y)))
    throw Error(where + "/size", both ? "both components must be positive and finite"
                                      : "the first component must be positive and finite");
}

}  // namespace

MeshData build_mesh(const MeshDesc& desc, const std::string& where, std::uint64_t max_memory_bytes) {
  if (!std::isfinite(desc.uv_scale.x) || !std::isfinite(desc.uv_scale.y) || desc.uv_scale.x == 0.0f ||
      desc.uv_scale.y == 0.0f)
    throw Error(where + "/uv_scale", "both components must be finite and non-zero");
  switch (desc.kind) {
    case MeshKind::Plane:
      check_size(desc, true, where);
      return mesh_detail::make_plane(desc);
    case MeshKind::Box:
      check_size(desc, false, where);
      return mesh_detail::make_box(desc);
    case MeshKind::Sphere:
      check_size(desc, false, where);
      if (desc.segments < 4)
        throw Error(where + "/segments", "must be at least 4 (got " + std::to_string(desc.segments) + ")");
      // Rings = segments / 2; each ring holds 2 * segments triangles (pole rings half that).
      mesh_detail::check_triangle_count(std::uint64_t(desc.segments) * std::uint64_t(desc.segments),
                                        where + "/segments");
      return mesh_detail::make_sphere(desc);
    case MeshKind::Grid:
      check_size(desc, true, where);
      if (desc.resolution < 1)
        throw Error(where + "/resolution", "must be at least 1 (got " + std::to_string(desc.resolution) + ")");
      if (!std::isfinite(desc.height)) throw Error(where + "/height", "must be finite");
      mesh_detail::check_triangle_count(2 * std::uint64_t(desc.resolution) * std::uint64_t(desc.resolution),
                                        where + "/resolution");
      return mesh_detail::make_grid(desc, where);
    case MeshKind::Obj:
      return mesh_detail::load_obj(desc, where + "/file");
    case MeshKind::Gltf:
      return mesh_detail::load_gltf(desc, where.empty() ? where : where + "/file", max_memory_bytes);
  }
  throw Error(where, "unknown mesh kind");
}

}  // namespace qdmr
