#include "qdmr/program/program_key.hpp"

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

const char* level_up_name(QdmLevelUp l) {
  switch (l) {
    case QdmLevelUp::Stay: return "stay";
    case QdmLevelUp::One: return "one";
    case QdmLevelUp::Aligned: return "aligned";
  }
  return "?";
}

}  // namespace

std::string trace_variant_name(const TraceOptions& o) {
  std::string name = technique_name(o.technique);
  if (o.technique == TechniqueKind::Qdm)
    name += std::string("<") +
            (o.math == MathMode::Sm3 ? "sm3_cells" : o.math == MathMode::Exact ? "fp64_walls" : "int_cells") + "," +
            (o.filtered_max ? "filtered_max" : "max_fetch") + ",level_up_" + level_up_name(o.level_up) + ">";
  return name;
}

std::string variant_name(const ProgramKey& key) {
  std::string variant = key.normal_mapping() ? std::string("normal_mapping")
                                             : std::string("displacement:") + trace_variant_name(key.trace);
  if (key.layers > 1)
    variant += std::string(" | blend ") + blend_name(key.blend) + " x" + std::to_string(key.layers) +
               (key.weights == WeightMode::Vertex ? " per vertex" : " per pixel");
  if (key.shadow != ShadowMode::Off) variant += std::string(" | shadow ") + shadow_name(key.shadow);
  if (key.ao != AoMode::Off) variant += std::string(" | ao ") + (key.ao == AoMode::Baked ? "baked" : "frame");
  variant += std::string(" | ") + lighting_name(key.lighting) + " | " + filter_name(key.filter);
  if (key.orm) variant += " | orm";
  return variant;
}

}  // namespace qdmr
