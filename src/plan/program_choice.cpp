#include "plan/program_choice.hpp"

namespace qdmr {

ProgramKey program_key(const MaterialDesc& material) {
  ProgramKey key;
  key.trace.technique = material.technique.kind;
  if (key.trace.technique == TechniqueKind::Qdm) {
    key.trace.math = material.sampling.math;
    key.trace.filtered_max = material.technique.height_fetch == HeightFetch::Trilinear;
    key.trace.level_up = material.technique.level_up;
  }
  key.layers = int(material.layers.size());
  if (key.layers > 1) {
    key.blend = material.blend.op;
    key.weights = material.blend.weights.mode;
  }
  key.shadow = material.shadow.mode;
  key.ao = material.ao.mode;
  key.lighting = material.lighting.model;
  key.orm = key.layers == 1 && material.layers.front().has_orm();
  key.sampler = sampler_modes(material.sampling, key.normal_mapping() ? HeightFetch::Bilinear
                                                                       : material.technique.height_fetch);
  return key;
}

SamplerModes sampler_modes(const SamplingDesc& s, HeightFetch heights) {
  return {.filter = s.filter,
          .address = s.address,
          .precision = s.precision,
          .lod = s.lod,
          .fp32_texels = s.math == MathMode::Sm3,
          .heights = heights};
}

SamplerParams sampler_params(const SamplingDesc& s) {
  return {.lod_bias = s.lod_bias, .min_lod = s.min_lod, .max_lod = s.max_lod};
}

// Named, in declaration order: the compiler checks every field against its name.
TraceParams trace_params(const TechniqueDesc& t) {
  return {.depth_scale = t.depth_scale,
          .write_depth = t.write_depth,
          .exact_hits = t.exact_hits,
          .linear_steps = t.linear_steps,
          .binary_steps = t.binary_steps,
          .min_steps = t.min_steps,
          .max_steps = t.max_steps,
          .lod_threshold = t.lod_threshold,
          .lod_fade = t.lod_fade,
          .max_iterations = t.max_iterations,
          .refinement = t.refinement,
          .lod_stop = t.lod_stop,
          .min_iterations = t.min_iterations,
          .fade_start = t.fade_start,
          .fade_end = t.fade_end};
}

LightingParams lighting_params(const LightingDesc& l) {
  return {.specular = l.specular, .shininess = l.shininess, .roughness = l.roughness};
}

ShadowParams shadow_params(const ShadowDesc& s) {
  return {.strength = s.strength,
          .max_iterations = s.max_iterations,
          .samples = s.samples,
          .length = s.length,
          .profile = s.profile,
          .penumbra = s.penumbra,
          .tap_weights = s.tap_weights,
          .bias = s.bias};
}

AoParams ao_params(const AoDesc& a) {
  return {.directions = a.directions,
          .jitter = a.jitter,
          .seed = a.seed,
          .radius = a.radius,
          .coarse = a.coarse,
          .strength = a.strength};
}

ProgramParams program_params(const MaterialDesc& material) {
  ProgramParams p;
  p.trace = trace_params(material.technique);
  p.sampler = sampler_params(material.sampling);
  p.lighting = lighting_params(material.lighting);
  for (const LayerDesc& layer : material.layers) p.specular.push_back(layer.specular);
  if (material.layers.size() == 1 && material.layers.front().has_orm())
    p.orm = {.metallic = material.layers.front().metallic,
             .occlusion_strength = material.layers.front().occlusion_strength};
  p.shadow = shadow_params(material.shadow);
  p.ao = ao_params(material.ao);
  if (material.layers.size() > 1)
    p.blend = {.width = material.blend.width, .weights_scale = material.blend.weights.scale};
  return p;
}

}  // namespace qdmr
