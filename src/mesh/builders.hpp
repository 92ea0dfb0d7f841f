#pragma once
// Private to the mesh module: one builder per MeshKind, and helpers they share.
#include <cstdint>
#include <string>

#include <glm/vec3.hpp>

#include "qdmr/mesh/mesh.hpp"

namespace qdmr::mesh_detail {

MeshData make_plane(const MeshDesc& desc);
MeshData make_box(const MeshDesc& desc);
MeshData make_sphere(const MeshDesc& desc);
MeshData make_grid(const MeshDesc& desc, const std::string& where);
// `where` names the file field ("scene.json: /objects/0/mesh/file").
MeshData load_obj(const MeshDesc& desc, const std::string& where);
// A glTF 2.0 asset (mesh/gltf.cpp); `where` names the field as for load_obj, empty when the asset is the job's
// input itself (`qdmr render model.glb`): messages then start with the asset's file.
MeshData load_gltf(const MeshDesc& desc, const std::string& where, std::uint64_t max_memory_bytes = 0);

// Throws when `triangles` exceeds limits::kMaxTriangles.
void check_triangle_count(std::uint64_t triangles, const std::string& where);

// A unit vector orthogonal to n (n need not be unit; (1,0,0) when n is zero).
glm::vec3 any_orthogonal(const glm::vec3& n);

}  // namespace qdmr::mesh_detail
