#pragma once
// The plan stage: FramePlan = what a loaded scene requires before anything is built — the program variant of
// each material, the meshes, textures and derived data to make (each with a content key), the AOVs, and the
// memory all of it will take. prepare() builds exactly what the plan lists and nothing else; `qdmr plan`
// prints it.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/aov.hpp"
#include "qdmr/program/program_key.hpp"
#include "qdmr/program/program_params.hpp"
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/format.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "qdmr/texture/texture_level0.hpp"

namespace qdmr {

struct PlanOptions {
  std::vector<Aov> aovs;  // error_texels and missed make displacement programs trace the exact reference
};

struct TextureRequest {
  std::string key;           // content key: identical requests share one texture (and survive re-planning)
  TexturePurpose purpose;
  TextureDesc desc;
  LayerDesc layer;           // the layer it belongs to (height for from_height normals, scale/offset)
  std::string where;         // scene field, for messages
  TexelFormat format = TexelFormat::RGBA8;
  bool srgb = false;
  MipReduce reduce = MipReduce::Box;
  int width = 0, height = 0, levels = 0;
  std::uint64_t bytes = 0;   // level 0 and its mip chain, with the decoded copy and wrap footprints it keeps
  // Heights some material fetches bilinearly with wrap addressing: the texture keeps level 0's wrap footprints
  // (Texture::wrap_footprints, where wrap_footprint_bytes allows).
  bool wrap_footprints = false;
  // What its build allocates on top of `bytes` and frees again, at the most: the decoded file, level 0 in floats,
  // the heights behind from_height normals.
  std::uint64_t working_bytes = 0;
  std::vector<std::string> users;  // material names
  // Its content changes from frame to frame (a time-dependent procedural, heights handed over by the program, or
  // normals from such heights): rebuilt every frame of a sequence.
  bool dynamic = false;
  // Heights and from_height normals: the content key of the layer's heights they are made from, else empty.
  // prepare makes the level 0 (and box chain) once for every texture of a build group made from it.
  std::string height_key;
  // What that shared level 0 and box chain hold while their group is built (0 without a height_key).
  std::uint64_t shared_height_bytes = 0;
};

// The textures built together: those made from one layer's heights (one height_key) share its level 0 and box chain,
// made once for the group; any other texture is a group of its own. In the order of each group's first texture.
std::vector<std::vector<std::size_t>> texture_build_groups(const std::vector<TextureRequest>& textures);

// prepare() builds at most this many texture build groups at once (each texture with every thread), so that their
// working memory is bounded whatever the number of threads.
inline constexpr std::size_t kTexturesBuiltAtOnce = 2;

// Data derived from textures, meshes and material settings, built after them.
enum class DerivedKind {
  WeightTexture,     // blends per pixel: RGBA8 weight texture with a max chain (from the weight map or the vertices)
  CombinedSurface,   // blends: fp64 blended box surface over the weights span (reference, combined tree, AO)
  CombinedQuadtree,  // qdm over a per-pixel blend: the max-quadtree of the combined surface
  BlendAoMap,        // baked AO of a blend's combined surface
  HeightField,       // fp64 level 0 of a stored height map (exact reference, cone bake, bilinear patches, layer AO)
  LayerAoMap,        // baked AO of one layer's heights
  ConeMap,           // csm, rcsm
  BilinearBound,     // qdm with bilinear-patch refinement: max-quadtree of the 3x3 maxima
  TwinTexels,        // a layer's albedo and normal map interleaved per texel (texture/twin_texels.hpp)
};
const char* derived_kind_name(DerivedKind kind);

struct DerivedPlan {
  DerivedKind kind;
  std::string key;      // content key: equal keys build equal data
  std::string where;    // scene field, for messages
  std::vector<int> inputs;  // derived items it is made from (built before it)
  int texture = -1;     // the texture it is made from (HeightField: the heights; TwinTexels: the albedo), else -1
  int second_texture = -1;  // TwinTexels: the normal map
  int material = -1;    // the first material that asked for it
  int side = 0;         // ao maps: the map's width
  std::uint64_t bytes = 0;  // what it keeps
  // What its build allocates on top of `bytes` and frees again: a cone bake, the baker's grid of doubles and max
  // hierarchy (qdmr::cone_bake_bytes less the map); an AO bake, the map in floats and the max pyramid of coarse
  // taps (qdmr::ao_bake_bytes). 0 for the other kinds.
  std::uint64_t working_bytes = 0;
  bool dynamic = false;  // made from a dynamic texture or item: rebuilt every frame of a sequence
};

// Indices into FramePlan::textures and FramePlan::derived of one layer (-1: not needed).
struct LayerPlan {
  int albedo = -1, normal = -1;
  int height = -1;           // box-filtered heights (displacement techniques, height blending)
  int height_max = -1;       // max-quadtree (qdm, hard or qdm_soft shadows, coarse AO)
  int field = -1;            // derived HeightField of the height (layer 0: reference, cones; any: baked AO)
  int ao = -1;               // derived LayerAoMap
  int twin = -1;             // derived TwinTexels
  int orm = -1;              // occlusion, roughness, metalness (ProgramKey::orm)
};

struct MaterialPlan {
  std::string name;
  std::string where;         // the scene field it comes from (an OBJ's MTL material: the object's mesh file)
  MaterialDesc desc;         // what the scene says; preparation reads it
  ProgramKey key;            // what the shading program runs, and what it reads: the kernel makes the program
  ProgramParams params;      // from these (Kernel::make_program), never from desc
  std::string variant;       // the key printed (variant_name): the program reports the instantiation it runs
  TechniqueKind technique = TechniqueKind::Normal;
  std::vector<LayerPlan> layers;  // one per material layer
  bool blend = false;        // more than one layer
  WeightMode weight_mode = WeightMode::Pixel;
  bool reference = false;    // error AOVs: trace the exact reference (layer 0's field, or the combined surface)
  bool cone_map = false;
  ConeKind cone_kind = ConeKind::Conservative;
  // Indices into FramePlan::derived, -1 when not needed.
  int weights = -1, combined_surface = -1, combined_quadtree = -1, blend_ao = -1, cones = -1, bilinear_bound = -1;
  int weights_scale = 1;     // whole repeats the combined surface spans
  std::vector<std::size_t> objects;  // objects drawn with it
};

struct MeshPlan {
  std::string object;
  std::string kind;
  std::string key;           // content key (with the vertex weights it carries)
  std::uint64_t vertices = 0, triangles = 0, bytes = 0;
  std::uint64_t degenerate_faces = 0;        // obj: faces without area, dropped (mesh.hpp)
  std::uint32_t material = 0;                // frame material of its triangles (no MTL materials)
  std::vector<std::uint32_t> mtl_materials;  // obj with MTL materials: frame material per mesh-local material
  int vertex_weights = -1;   // per-vertex blend weights of this frame material are stored in the mesh, else -1
  std::vector<std::string> notes;  // gltf: what was derived or ignored (MeshData::notes), printed as warnings
  bool dynamic = false;      // displaced by a time-dependent height map: rebuilt every frame of a sequence
};

// The private memory the image library (OpenImageIO and the ~260 libraries it brings) takes once a process has
// read its first image file: relocated data and the library's own state, held until the process ends. Measured
// on Debian 12 with OpenImageIO 2.4 (`bench/image_module_memory.sh`): 40.2 MiB of private dirty memory, counted
// with some room. The libraries' code (another ~77 MiB resident) is file pages the kernel can drop and reload.
inline constexpr std::uint64_t kImageModuleBytes = std::uint64_t(48) << 20;

struct FramePlan {
  SceneDesc scene;           // the loaded scene: camera, lights and transforms for draw
  PlanOptions options;
  int width = 0, height = 0;
  std::vector<MaterialPlan> materials;   // the materials objects use, in first-use order
  std::vector<TextureRequest> textures;
  std::vector<DerivedPlan> derived;      // in build order (inputs first)
  std::vector<MeshPlan> meshes;          // one per scene object
  std::vector<Aov> aovs;
  std::uint64_t framebuffer_bytes = 0, texture_bytes = 0, mesh_bytes = 0, derived_bytes = 0;
  // The procedural patterns (procedural_key) the weight maps, meshes and textures ask for more than once: prepare
  // keeps each the first time it is made (texture/pattern_reuse.hpp) until the textures are built, holding
  // reused_pattern_bytes.
  std::vector<std::string> reused_patterns;
  std::uint64_t reused_pattern_bytes = 0;
  // The working memory of the kTexturesBuiltAtOnce texture build groups whose builds need the most, and the
  // reused patterns.
  std::uint64_t texture_working_bytes = 0;
  // The most working memory held at once: texture_working_bytes, or the largest DerivedPlan::working_bytes
  // (derived data is built one item at a time, after the textures). Counted on top of everything kept.
  std::uint64_t working_bytes = 0;
  // kImageModuleBytes when building the frame reads an image file (a texture, height or weight map) through the
  // image module (a PFM file or a TIFF OpenImageIO converts; the others are read in process), else 0.
  std::uint64_t image_module_bytes = 0;
  // The estimate --max-memory is checked against: everything kept, plus the most working memory held at once.
  std::uint64_t total_bytes() const {
    return framebuffer_bytes + texture_bytes + mesh_bytes + derived_bytes + working_bytes + image_module_bytes;
  }

  // Everything prepare() builds, one line per item ("texture <key>", "mesh <key>", "<derived kind> <key>"),
  // in build order; Assets::built lists the same lines as they are made.
  std::vector<std::string> items() const;
  // The items() lines of the dynamic items: what each frame of a sequence rebuilds. Empty for a still scene.
  std::vector<std::string> dynamic_items() const;
  std::string describe() const;  // human-readable, for `qdmr plan`
  nlohmann::json to_json() const;
};

// Throws qdmr::Error for settings that cannot be built (texture headers are read to size them).
FramePlan plan_frame(const SceneDesc& scene, const PlanOptions& options = {});


}  // namespace qdmr
