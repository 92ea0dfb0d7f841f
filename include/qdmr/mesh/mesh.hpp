#pragma once
// MeshData: indexed triangles with per-vertex tangent frames, built from a MeshDesc.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "qdmr/scene/scene.hpp"

namespace qdmr {

struct MeshData {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;    // unit length
  std::vector<glm::vec4> tangents;   // xyz: unit tangent along +u, orthogonal to the normal; w: +-1, bitangent = w * cross(n, t)
  std::vector<glm::vec2> uvs;
  std::vector<glm::vec4> blend_weights;  // per vertex, layers 0..3; filled for blended materials with per-vertex weights
  std::vector<std::uint32_t> indices;             // 3 per triangle, counter-clockwise front faces
  std::vector<std::uint32_t> triangle_materials;  // obj, gltf: per triangle, an index into `materials`; empty otherwise
  std::vector<MaterialDesc> materials;            // obj, gltf: the file's materials (named as the file names them)
  std::vector<std::filesystem::path> bump_maps;   // obj: per entry of `materials`, its bump map (empty if none)
  std::vector<CameraDesc> cameras;                // gltf: the drawn nodes' perspective cameras, in qdmr's frame
  std::vector<std::string> notes;                 // gltf: what was derived or ignored, for the plan's warnings
  std::size_t degenerate_faces = 0;               // obj: faces of 4 or more corners without area, dropped

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return indices.size() / 3; }
};

// Builds a primitive or loads an OBJ (with MTL through tinyobjloader). `where` names the scene field for
// messages ("scene.json: /objects/2/mesh"). Throws qdmr::Error on unreadable files, NaN/infinite data,
// out-of-range indices. Degenerate triangles are kept (the rasterizer culls them) but their tangents are ignored.
// OBJ faces of any number of corners are triangulated (concave ones by ear clipping); larger faces without area
// are dropped and counted in degenerate_faces.
// Grid: the height map spans the whole grid once (sampled at the vertex UV divided by uv_scale), so
// uv_scale tiles the material without repeating the relief. OBJ: UVs are multiplied by uv_scale; MTL
// map_Kd -> albedo, disp -> height with technique pom, else bump/map_Bump -> height for normals only,
// norm -> normal map (else normals from the height), paths made absolute against the MTL file's folder; faces
// without a material use an appended constant white "default" material. glTF: see mesh/gltf.cpp and
// docs/scene-format.md ("glTF 2.0 assets").
// max_memory_bytes (0: none) bounds a glTF mesh's drawn copies before they are read (load_scene).
MeshData build_mesh(const MeshDesc& desc, const std::string& where, std::uint64_t max_memory_bytes = 0);

// Per-vertex tangent frames from positions, normals and UVs (accumulated per triangle, Gram-Schmidt
// orthogonalised). Vertices whose UVs give no direction get any tangent orthogonal to the normal.
void compute_tangents(MeshData& mesh);

}  // namespace qdmr
