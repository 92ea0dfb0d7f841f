#pragma once
// The numbers a material's shading program reads, resolved by the plan (plan/program_choice.cpp) from the scene's
// MaterialDesc; the modes that choose the program's code are its ProgramKey (program/program_key.hpp). Only what
// programs read is here: file names, seeds of preparation and bake resolutions stay with the scene.
#include <cstdint>
#include <vector>

#include "qdmr/core/material_modes.hpp"

namespace qdmr {

// The technique's speed/accuracy knobs (scene.hpp's TechniqueDesc documents each). Depth is in UV units of one
// texture repeat.
struct TraceParams {
  float depth_scale = 0.05f;
  bool write_depth = false;
  bool exact_hits = false;
  int linear_steps = 32, binary_steps = 6;  // relief; binary_steps also refines cone stepping
  int min_steps = 8, max_steps = 48;        // pom
  float lod_threshold = 4.0f, lod_fade = 1.0f;  // pom: the LOD fade to normal mapping
  int max_iterations = 128;                 // csm, rcsm, qdm
  QdmRefinement refinement = QdmRefinement::Linear;
  bool lod_stop = false;
  int min_iterations = 0;
  float fade_start = 0.0f, fade_end = 0.0f;  // depth scale fading to 0 with view distance
};

// The sampler's numbers (scene.hpp's SamplingDesc documents each); its modes are the key's (SamplerModes).
struct SamplerParams {
  float lod_bias = 0.0f;
  float min_lod = 0.0f, max_lod = 16.0f;  // LOD clamp, in levels
};

struct LightingParams {
  float specular = 0.25f;   // Blinn-Phong reflectance scale, Cook-Torrance F0
  float shininess = 32.0f;  // Blinn-Phong
  float roughness = 0.5f;   // Cook-Torrance
};

// The factors of an ORM texture (ProgramKey::orm; LayerDesc documents them).
struct OrmParams {
  float metallic = 1.0f;
  float occlusion_strength = 1.0f;
};

// Self-shadowing (scene.hpp's ShadowDesc documents each); the mode is the key's.
struct ShadowParams {
  float strength = 8.0f;
  int max_iterations = 64;
  int samples = 16;
  float length = 0.0f;
  ProfileOperator profile = ProfileOperator::Max;
  float penumbra = 1.0f;
  std::vector<float> tap_weights{1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  float bias = 0.0f;
};

// Ambient occlusion traced per pixel (AoMode::Frame: the directions and taps of bake/ao_pattern.hpp), and the
// strength a baked map is applied with.
struct AoParams {
  int directions = 8;
  bool jitter = false;
  std::uint32_t seed = 1;
  float radius = 0.05f;
  bool coarse = true;
  float strength = 1.0f;
};

struct BlendParams {
  float width = 0.2f;          // height_width: transition width in height units
  float weights_scale = 1.0f;  // texture repeats the per-pixel weight map spans
};

struct ProgramParams {
  TraceParams trace;
  SamplerParams sampler;
  LightingParams lighting;
  std::vector<SpecularFromAlbedo> specular;  // per layer
  OrmParams orm;                             // ProgramKey::orm
  ShadowParams shadow;
  AoParams ao;
  BlendParams blend;
};

}  // namespace qdmr
