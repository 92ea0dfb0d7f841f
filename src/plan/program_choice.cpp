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
  key.filter = material.sampling.filter;
  return key;
}

TraceParams trace_params(const TechniqueDesc& t) {
  return {t.depth_scale,  t.write_depth,  t.exact_hits,    t.linear_steps,   t.binary_steps, t.min_steps,
          t.max_steps,    t.lod_threshold, t.lod_fade,     t.max_iterations, t.refinement,   t.height_fetch,
          t.lod_stop,     t.min_iterations, t.fade_start,  t.fade_end};
}

LightingParams lighting_params(const LightingDesc& l) { return {l.specular, l.shininess, l.roughness}; }

ShadowParams shadow_params(const ShadowDesc& s) {
  return {s.strength, s.max_iterations, s.samples, s.length, s.profile, s.penumbra, s.tap_weights, s.bias};
}

AoParams ao_params(const AoDesc& a) { return {a.directions, a.jitter, a.seed, a.radius, a.coarse, a.strength}; }

ProgramParams program_params(const MaterialDesc& material) {
  ProgramParams p;
  p.trace = trace_params(material.technique);
  p.sampling = material.sampling;
  p.lighting = lighting_params(material.lighting);
  for (const LayerDesc& layer : material.layers) p.specular.push_back(layer.specular);
  p.shadow = shadow_params(material.shadow);
  p.ao = ao_params(material.ao);
  if (material.layers.size() > 1) p.blend = {material.blend.width, material.blend.weights.scale};
  return p;
}

}  // namespace qdmr
