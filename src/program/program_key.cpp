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

// The filter, then each sampler state that is not its default (variant_name in program_key.hpp).
std::string sampler_name(const ProgramKey& key) {
  const SamplerModes& s = key.sampler;
  std::string name = filter_name(s.filter);
  if (s.address != AddressMode::Wrap) name += s.address == AddressMode::Clamp ? " clamp" : " mirror";
  if (s.precision != SamplePrecision::Exact) name += s.precision == SamplePrecision::Hw8 ? " hw8" : " hw6";
  if (s.lod == LodMode::PerPixel) name += " per_pixel_lod";
  // QDM's trace variant already says sm3_cells and filtered_max.
  const bool qdm = key.trace.technique == TechniqueKind::Qdm;
  if (s.fp32_texels && !qdm) name += " sm3_texels";
  if (s.heights == HeightFetch::Point) name += " point_heights";
  if (s.heights == HeightFetch::Trilinear && !qdm) name += " trilinear_heights";
  return name;
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
  variant += std::string(" | ") + lighting_name(key.lighting) + " | " + sampler_name(key);
  if (key.orm) variant += " | orm";
  return variant;
}

}  // namespace qdmr
