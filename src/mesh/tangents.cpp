// compute_tangents: per-triangle UV derivatives, area-weighted per vertex, Gram-Schmidt against the normal.
#include <cmath>

#include <glm/geometric.hpp>

#include "mesh/builders.hpp"

namespace qdmr {

namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

void compute_tangents(MeshData& mesh) {
  const std::size_t n = mesh.positions.size();
  std::vector<glm::vec3> along_u(n, glm::vec3(0.0f));
  std::vector<glm::vec3> along_v(n, glm::vec3(0.0f));
  const bool have_uvs = mesh.uvs.size() == n;

  for (std::size_t t = 0; have_uvs && t + 2 < mesh.indices.size(); t += 3) {
    const std::uint32_t i[3] = {mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
    if (i[0] >= n || i[1] >= n || i[2] >= n) continue;
    const glm::vec3 e1 = mesh.positions[i[1]] - mesh.positions[i[0]];
    const glm::vec3 e2 = mesh.positions[i[2]] - mesh.positions[i[0]];
    const glm::vec2 d1 = mesh.uvs[i[1]] - mesh.uvs[i[0]];
    const glm::vec2 d2 = mesh.uvs[i[2]] - mesh.uvs[i[0]];
    const float det = d1.x * d2.y - d2.x * d1.y;
    // Skip UV slivers (angle below ~1e-6 rad): their direction is float rounding noise.
    if (!(std::abs(det) > 1e-6f * glm::length(d1) * glm::length(d2))) continue;
    const float sign = det > 0.0f ? 1.0f : -1.0f;
    // dP/du and dP/dv up to the common factor 1/det.
    glm::vec3 du = (e1 * d2.y - e2 * d1.y) * sign;
    glm::vec3 dv = (e2 * d1.x - e1 * d2.x) * sign;
    const float area2 = glm::length(glm::cross(e1, e2));
    const float lu = glm::length(du), lv = glm::length(dv);
    if (!(area2 > 0.0f) || !(lu > 0.0f) || !(lv > 0.0f) || !std::isfinite(area2 * lu * lv)) continue;
    du *= area2 / lu;
    dv *= area2 / lv;
    for (const std::uint32_t v : i) {
      along_u[v] += du;
      along_v[v] += dv;
    }
  }

  mesh.tangents.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const glm::vec3 nrm = mesh.normals.size() == n ? mesh.normals[v] : glm::vec3(0, 0, 1);
    glm::vec3 t = along_u[v] - nrm * glm::dot(nrm, along_u[v]);
    const float len = glm::length(t);
    // A tangent almost parallel to the normal carries no usable direction.
    if (len > 1e-4f * glm::length(along_u[v]) && finite(t / len))
      t /= len;
    else
      t = mesh_detail::any_orthogonal(nrm);
    const float w = glm::dot(glm::cross(nrm, t), along_v[v]) < 0.0f ? -1.0f : 1.0f;
    mesh.tangents[v] = glm::vec4(t, w);
  }
}

}  // namespace qdmr
