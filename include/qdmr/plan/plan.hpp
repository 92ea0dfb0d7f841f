#pragma once
// FramePlan: what a scene requires before anything is built — the program variant of each material,
// the textures and derived data to make, the AOVs, and the memory all of it will take.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/format.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "qdmr/texture/texture.hpp"

namespace qdmr {

struct TextureRequest {
  std::string key;           // identical requests share one texture
  TexturePurpose purpose;
  TextureDesc desc;
  LayerDesc layer;           // the layer it belongs to (height for from_height normals, scale/offset)
  std::string where;         // scene field, for messages
  TexelFormat format = TexelFormat::RGBA8;
  bool srgb = false;
  MipReduce reduce = MipReduce::Box;
  int width = 0, height = 0, levels = 0;
  std::uint64_t bytes = 0;   // level 0 and its mip chain
  std::vector<std::string> users;  // material names
};

// Indices into FramePlan::textures of one layer's textures (-1: not needed).
struct LayerPlan {
  int albedo = -1, normal = -1;
  int height = -1;           // box-filtered heights (displacement techniques, height blending)
  int height_max = -1;       // max-quadtree (qdm, hard or qdm_soft shadows, coarse AO)
};

struct MaterialPlan {
  std::string name;
  std::string program;       // the shading program variant
  TechniqueKind technique = TechniqueKind::Normal;
  std::vector<LayerPlan> layers;  // one per material layer
  // Blending (more than one layer): the weights come per vertex or from a weight texture built from the map.
  bool blend = false;
  WeightMode weight_mode = WeightMode::Pixel;
  std::uint64_t weight_bytes = 0;  // pixel mode: RGBA8 weight texture with its max chain
  bool combined_quadtree = false;  // pixel mode, qdm: the precomputed max-quadtree of the blended surface
  std::uint64_t combined_bytes = 0;
  bool ao_map = false;       // baked AO: one map per layer, or one of the blended surface (blend_ao)
  bool blend_ao = false;     // baked AO of a blend: of the combined surface over the weights span
  int ao_resolution = 0;     // blend_ao: the map's side
  std::uint64_t ao_bytes = 0;
  bool cone_map = false;     // csm, rcsm: a cone map of the height's level 0, baked or from the cache
  ConeKind cone_kind = ConeKind::Conservative;
  std::uint64_t cone_bytes = 0;  // one float per level-0 texel
  SamplingDesc sampling;
  LightingDesc lighting;
};

struct MeshPlan {
  std::string object;
  std::string kind;
  std::uint64_t vertices = 0, triangles = 0, bytes = 0;
  bool estimated = false;    // obj: counted from the file, MTL materials resolved when prepared
};

struct FramePlan {
  int width = 0, height = 0;
  std::vector<MaterialPlan> materials;
  std::vector<TextureRequest> textures;
  std::vector<MeshPlan> meshes;
  std::vector<Aov> aovs;
  std::uint64_t framebuffer_bytes = 0, texture_bytes = 0, mesh_bytes = 0, cone_map_bytes = 0, derived_bytes = 0;
  std::uint64_t total_bytes() const {
    return framebuffer_bytes + texture_bytes + mesh_bytes + cone_map_bytes + derived_bytes;
  }

  std::string describe() const;  // human-readable, for `qdmr plan`
  nlohmann::json to_json() const;
};

// Throws qdmr::Error for unreadable texture files (their headers are read to size them).
FramePlan plan_frame(const SceneDesc& scene, const RenderOptions& options);

// Adds the texture requests of one material (shared by planning and preparing) and returns its plan.
MaterialPlan plan_material(const MaterialDesc& material, const std::string& where, std::vector<TextureRequest>& textures);

}  // namespace qdmr
