#pragma once
// Assets: everything a frame's plan asks to build — meshes, textures with their mip chains, and one
// shading program per material — made once, read-only while drawing.
#include <memory>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/study/heightfield.hpp"
#include "raster/geometry.hpp"
#include "shade/lighting.hpp"
#include "shade/program.hpp"

namespace qdmr {

struct Assets {
  std::vector<MeshData> meshes;                 // one per scene object
  std::vector<std::uint32_t> object_material;   // frame material of each object (unused for obj with MTL)
  std::vector<std::vector<std::uint32_t>> object_mtl_materials;  // obj: MTL material id -> frame material
  std::vector<MaterialPlan> materials;          // frame materials: the scene's, then those of MTL files
  std::vector<TextureRequest> requests;
  std::vector<Texture> textures;                // parallel to requests
  std::vector<TextureStat> texture_stats;       // parallel to requests
  std::vector<std::unique_ptr<ShadingProgram>> programs;  // parallel to materials
  std::vector<std::unique_ptr<HeightField>> reference_fields;  // fp64 heights (error AOVs, bilinear patches)
  std::vector<std::unique_ptr<Texture>> derived_textures;      // bilinear-bound quadtrees
  std::vector<std::unique_ptr<ConeMap>> cone_maps;             // csm, rcsm: baked or from the cache

  std::vector<DrawItem> draw_items() const;     // model matrices left as identity
  std::uint64_t texture_bytes() const;
  std::uint64_t mesh_bytes() const;
};

// Builds meshes and textures in parallel (in the caller's task arena), and cone maps through the cache in
// default_cache_dir(). Throws qdmr::Error on bad input.
Assets prepare_assets(const SceneDesc& scene, const LightRig& lights, const RenderOptions& options);

}  // namespace qdmr
