#pragma once
// The prepare stage: Assets = everything a FramePlan lists, built — meshes, textures with their mip chains and
// the derived data (weight textures, combined surfaces and quadtrees, fp64 height fields, AO and cone maps).
// Read-only while drawing; shared (by content key) with the assets of the next plan, so a re-plan that keeps
// an item's key keeps the item.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/core/stats.hpp"
#include "qdmr/core/zeroed_buffer.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "texture/layer_heights.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

class Kernel;

// An amortized AO map (AoDesc::amortize_frames) as floats, and the frame of the animation it is: the next frame
// copies it and rebakes its share of the rows.
struct AoHistory {
  int frame = 0;
  Image map;
};

// One derived item: the member its kind makes (weight textures, quadtrees, AO maps and bilinear bounds are
// textures; combined surfaces and height fields are fields; cone maps are cones; a combined quadtree also has
// its layers' heights side by side).
struct DerivedAsset {
  std::shared_ptr<const Texture> texture;
  std::shared_ptr<const LayerHeights> layer_heights;  // a combined quadtree's: its walk's level-0 cells, when made
  std::shared_ptr<const ZeroedBuffer<float>> box_values;  // with them: its level 0 (texture/blend_box_values.hpp)
  std::shared_ptr<const HeightField> field;
  std::shared_ptr<const ConeMap> cones;
  std::shared_ptr<const std::vector<float>> twin_texels;  // TwinTexels (texture/twin_texels.hpp)
  std::shared_ptr<const AoHistory> ao_history;  // an AO map amortized over frames: its rows in floats
};

struct Assets {
  std::vector<std::shared_ptr<const MeshData>> meshes;  // parallel to FramePlan::meshes
  std::vector<std::shared_ptr<const Texture>> textures; // parallel to FramePlan::textures
  std::vector<TextureStat> texture_stats;               // parallel to FramePlan::textures
  std::vector<DerivedAsset> derived;                    // parallel to FramePlan::derived
  // FramePlan::items() lines: what this prepare built, and what it took from the previous assets.
  std::vector<std::string> built, reused;
  std::vector<PrepareStep> steps;  // what building each built item took, in plan order

  std::uint64_t texture_bytes() const;
  std::uint64_t mesh_bytes() const;
};

// Textures of dynamic items that the last prepare replaced, held by nothing else, kept for their buffers: the next
// frame's rebuild of a dynamic height refills them (texture/height_family.hpp) instead of allocating and clearing
// new memory (the Renderer keeps them between frames).
struct SpareTextures {
  std::vector<std::shared_ptr<const Texture>> textures;
  // A spare of this layout (with wrap footprints or without), moved out of the list, or an empty texture.
  Texture take(int width, int height, TexelFormat format, bool wrap_footprints);
};

// Builds what the plan lists, in parallel (in the caller's task arena); items whose key is in `previous` are
// shared instead of rebuilt; an AO map amortized over frames continues the previous assets' map of the same item
// (same place in the plans) when that is the previous frame's (else it bakes every row). The per-ISA work (max/min mip chains, a blend's box values) runs on `kernel`, the
// Renderer's, so a forced ISA holds here too: passed, not a process-wide choice, since renderers of different ISAs
// share a process (tests, Python) and the builders run on TBB workers. Cone and AO maps go through the bake cache
// in default_cache_dir(). Dynamic heights' textures are rebuilt together (texture/height_family.hpp) into `spares`
// where they fit. `progress`, when set, is called with the fraction of the plan's items done each time an item is
// built (from the building thread, one call at a time). Throws qdmr::Error on bad input.
Assets prepare(const FramePlan& plan, const Kernel& kernel, const Assets* previous = nullptr,
               const FramePlan* previous_plan = nullptr, const std::function<void(double fraction)>& progress = {},
               SpareTextures* spares = nullptr);

}  // namespace qdmr
