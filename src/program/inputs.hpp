#pragma once
// What a displacement program reads, made by prepare and handed to the draw kernel that builds the program:
// textures, derived data and the exact reference of one material. ISA-independent.
#include <cstdint>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "texture/layer_heights.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

class ReferenceMemo;

struct LayerInputs {
  const Texture* albedo = nullptr;      // RGBA8 sRGB
  const Texture* normal = nullptr;      // RGBA8, 0.5 + 0.5 n
  const Texture* height = nullptr;      // box-filtered heights (techniques, height blending)
  const Texture* height_max = nullptr;  // max-quadtree (QDM, shadows, AO); power-of-two sizes
  const Texture* ao = nullptr;          // baked AO of this layer's heights (R16), when the material bakes AO
  const float* twin_texels = nullptr;   // albedo and normal map interleaved (texture/twin_texels.hpp), or null
  const Texture* orm = nullptr;         // RGBA8 linear: occlusion, roughness, metalness (ProgramKey::orm), or null
};

struct DisplacementInputs {
  std::vector<LayerInputs> layers;        // 1 .. 4
  const Texture* weights = nullptr;       // blending per pixel: RGBA8 weight texture with a max chain
  const Texture* combined = nullptr;      // blending per pixel: the precomputed combined quadtree (optional)
  int combined_period_u = 0, combined_period_v = 0;  // its periods in level-0 texels (layers' size x repeats)
  const LayerHeights* layer_heights = nullptr;  // with it: the layers' level-0 heights side by side (optional)
  const float* box_values = nullptr;      // with those: the tree's level 0 over the period (blend_box_values)
  const Texture* blend_ao = nullptr;      // baked AO of a blend's combined surface over the weights span (R16)
  int blend_ao_scale = 1;                 // ... sampled at UV / this (the whole number of repeats it spans)
  const ConeMap* cones = nullptr;         // CSM (conservative) / RCSM (relaxed): one ratio per level-0 texel of height
  const HeightField* reference = nullptr; // level-0 heights in fp64, for error_texels / missed; may be null
  int reference_scale = 1;                // texture repeats the reference spans (a blend's combined surface)
  ReferenceMemo* reference_memo = nullptr;  // remembers the reference's hits across frames, when set
  std::uint64_t reference_id = 0;           // ... under this id (ReferenceMemo::field_id of the reference)
  // qdm with bilinear-patch refinement: the fp64 heights solved exactly, and height_max built from
  // bilinear_upper_bound() of them (conservative for the bilinear surface).
  const HeightField* surface = nullptr;
};

}  // namespace qdmr
