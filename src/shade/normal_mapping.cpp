#include "shade/normal_mapping.hpp"

#include "shade/lighting_models.hpp"
#include "shade/shading_math.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

using namespace shading;

void NormalMappingProgram::shade(const Fragments& in, ShadeOutput& out) const {
  const Float& u = in.varyings[kU];
  const Float& v = in.varyings[kV];
  const UvDerivatives d = UvDerivatives::from(u, v, lod_mode_);
  Float albedo[4];
  const Float albedo_lod = albedo_.lod(d.dudx, d.dvdx, d.dudy, d.dvdy);
  albedo_.sample(u, v, albedo_lod, albedo);
  Float tangent_normal[4];
  normal_.sample(u, v, normal_.same_lod_as(albedo_) ? albedo_lod : normal_.lod(d.dudx, d.dvdx, d.dudy, d.dvdy),
                 tangent_normal);

  const TangentFrame frame = TangentFrame::from(in);
  const Vec3 shading_normal = normalize(frame.to_world({tangent_normal[0] * Float(2.0f) - Float(1.0f),
                                                        tangent_normal[1] * Float(2.0f) - Float(1.0f),
                                                        tangent_normal[2] * Float(2.0f) - Float(1.0f)}));
  shade_lights(shading_normal, frame.n, view_vector(in, lights_),
               SurfaceSample{albedo, specular_from_albedo(albedo, specular_, lighting_.specular), Float(1.0f)}, nullptr,
               lighting_, lights_, out.color);
  out.normal[0] = shading_normal.x;
  out.normal[1] = shading_normal.y;
  out.normal[2] = shading_normal.z;
  out.iterations = out.hit_depth = out.error_texels = out.missed = Float(0.0f);
  out.shadow = out.ao = Float(1.0f);  // no self-shadowing, no AO
  out.hit_u = u;
  out.hit_v = v;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
