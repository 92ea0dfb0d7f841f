#include "program/variant.hpp"

namespace qdmr {

const char* filter_name(Filter f) {
  switch (f) {
    case Filter::Point: return "point";
    case Filter::Bilinear: return "bilinear";
    case Filter::Trilinear: return "trilinear";
    case Filter::PointMipPoint: return "point_mip_point";
    case Filter::PointMipLinear: return "point_mip_linear";
    case Filter::LinearMipPoint: return "linear_mip_point";
  }
  return "?";
}

const char* technique_name(TechniqueKind k) {
  switch (k) {
    case TechniqueKind::Normal: return "normal";
    case TechniqueKind::Relief: return "relief";
    case TechniqueKind::Pom: return "pom";
    case TechniqueKind::Csm: return "csm";
    case TechniqueKind::Rcsm: return "rcsm";
    case TechniqueKind::Qdm: return "qdm";
  }
  return "?";
}

namespace {

const char* lighting_name(LightingModel m) { return m == LightingModel::CookTorrance ? "cook_torrance" : "blinn_phong"; }

const char* shadow_name(ShadowMode m) {
  switch (m) {
    case ShadowMode::Off: return "off";
    case ShadowMode::Hard: return "hard";
    case ShadowMode::Horizon: return "horizon";
    case ShadowMode::QdmSoft: return "qdm_soft";
  }
  return "?";
}

const char* blend_name(BlendOperator op) {
  switch (op) {
    case BlendOperator::Alpha: return "alpha";
    case BlendOperator::Height: return "height";
    case BlendOperator::HeightWidth: return "height_width";
  }
  return "?";
}

}  // namespace

std::string program_variant(const MaterialDesc& material) {
  const TechniqueKind kind = material.technique.kind;
  const std::size_t layer_count = material.layers.size();
  const bool blend = layer_count > 1;
  std::string variant = kind == TechniqueKind::Normal && !blend ? std::string("normal_mapping")
                                                                : std::string("displacement:") + technique_name(kind);
  if (blend)
    variant += std::string(" | blend ") + blend_name(material.blend.op) + " x" + std::to_string(layer_count) +
               (material.blend.weights.mode == WeightMode::Vertex ? " per vertex" : " per pixel");
  if (material.shadow.mode != ShadowMode::Off) variant += std::string(" | shadow ") + shadow_name(material.shadow.mode);
  if (material.ao.mode != AoMode::Off) variant += std::string(" | ao ") + (material.ao.mode == AoMode::Baked ? "baked" : "frame");
  variant += std::string(" | ") + lighting_name(material.lighting.model) + " | " + filter_name(material.sampling.filter);
  return variant;
}

}  // namespace qdmr
