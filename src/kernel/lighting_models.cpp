#include "kernel/lighting_models.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::shading {
namespace {

// pi * D * Vis * F * n.l of the header, for one light. Roughness: one float for the batch, or a Float per lane (the
// same operations, lane by lane).
template <class Roughness>
Float cook_torrance(const Float& n_dot_l, const Float& n_dot_v, const Float& n_dot_h, const Float& v_dot_h,
                    const Float& f0, const Roughness& roughness) {
  const Float one(1.0f);
  const Roughness alpha = roughness * roughness;
  const Float a2(alpha * alpha), one_minus_a2(Roughness(1.0f) - alpha * alpha);
  const Float d_root = n_dot_h * n_dot_h * (a2 - one) + one;  // >= alpha^2 > 0
  const Float d = a2 / (d_root * d_root);                     // pi * D
  const Float lambda_v = n_dot_l * xsimd::sqrt(n_dot_v * n_dot_v * one_minus_a2 + a2);
  const Float lambda_l = n_dot_v * xsimd::sqrt(n_dot_l * n_dot_l * one_minus_a2 + a2);
  // Both dot products 0 (a grazing view of a light on the horizon): no highlight instead of 0 / 0.
  const Float vis = Float(0.5f) / xsimd::max(lambda_v + lambda_l, Float(1e-30f));
  const Float m = one - v_dot_h;
  const Float m2 = m * m;
  const Float fresnel = f0 + (one - f0) * (m2 * m2 * m);
  return d * vis * fresnel * n_dot_l;
}

// Blinn-Phong's highlight: detmath::pow_uniform(x, shininess), its branch chosen by the caller once per batch.
// WholeShininess (the usual shininess): pow_uniform's products, and no general pow in the function, whose constants
// the compiler set up before the light loop for every batch (about 20 instructions a batch, spilled).
template <bool WholeShininess>
Float highlight(const Float& x, float shininess) {
  if constexpr (WholeShininess)
    return xsimd::select(x > Float(0.0f), detmath::pow_whole(x, unsigned(shininess)), Float(0.0f));
  else
    return detmath::pow_uniform(x, shininess);
}

template <bool WholeShininess, class Roughness>
void shade_lights_with(const Vec3& shading_normal, const Vec3& geometric_normal, const Vec3& view,
                       const SurfaceSample& surface, const Float* light_visibility, LightingModel model,
                       const LightingParams& lighting, const Roughness& roughness, const LightRig& lights, Float* color) {
  const Float zero(0.0f);
  // The sums in named values, not arrays: GCC kept arrays of them on the stack, stored and reloaded at every batch.
  Vec3 diffuse{Float(lights.ambient.x) * surface.ambient_occlusion, Float(lights.ambient.y) * surface.ambient_occlusion,
               Float(lights.ambient.z) * surface.ambient_occlusion};
  Vec3 specular{zero, zero, zero};
  const bool cook_torrance_model = model == LightingModel::CookTorrance;
  const Float n_dot_v = xsimd::max(dot(shading_normal, view), zero);
  for (std::size_t i = 0; i < lights.directional.size(); ++i) {
    const LightRig::Directional& light = lights.directional[i];
    const Vec3 l{Float(light.direction.x), Float(light.direction.y), Float(light.direction.z)};
    Float n_dot_l = xsimd::max(dot(shading_normal, l), zero);
    const Vec3 h = normalize(add(l, view));
    const Float facing = xsimd::select(dot(geometric_normal, l) > zero, Float(1.0f), zero);
    Float spec = cook_torrance_model
                     ? cook_torrance(n_dot_l, n_dot_v, xsimd::max(dot(shading_normal, h), zero),
                                     xsimd::max(dot(view, h), zero), surface.specular, roughness) *
                           facing
                     : highlight<WholeShininess>(xsimd::max(dot(shading_normal, h), zero), lighting.shininess) *
                           surface.specular * facing * xsimd::min(n_dot_l * Float(8.0f), Float(1.0f));
    if (light_visibility) {
      n_dot_l = n_dot_l * light_visibility[i];
      spec = spec * light_visibility[i];
    }
    const Float red(light.radiance.x), green(light.radiance.y), blue(light.radiance.z);
    diffuse = {diffuse.x + n_dot_l * red, diffuse.y + n_dot_l * green, diffuse.z + n_dot_l * blue};
    specular = {specular.x + spec * red, specular.y + spec * green, specular.z + spec * blue};
  }
  color[0] = surface.albedo[0] * diffuse.x + specular.x;
  color[1] = surface.albedo[1] * diffuse.y + specular.y;
  color[2] = surface.albedo[2] * diffuse.z + specular.z;
}

}  // namespace

void shade_lights(const Vec3& shading_normal, const Vec3& geometric_normal, const Vec3& view, const SurfaceSample& surface,
                  const Float* light_visibility, LightingModel model, const LightingParams& lighting, const LightRig& lights,
                  Float* color) {
  if (surface.roughness && model == LightingModel::CookTorrance)
    shade_lights_with<false>(shading_normal, geometric_normal, view, surface, light_visibility, model, lighting,
                             *surface.roughness, lights, color);
  else if (model == LightingModel::BlinnPhong && detmath::is_product_exponent(lighting.shininess))
    shade_lights_with<true>(shading_normal, geometric_normal, view, surface, light_visibility, model, lighting,
                            lighting.roughness, lights, color);
  else
    shade_lights_with<false>(shading_normal, geometric_normal, view, surface, light_visibility, model, lighting,
                             lighting.roughness, lights, color);
}

OrmSurface apply_orm(const Float* orm, const OrmParams& params, float lighting_roughness, const Float* albedo,
                     const Float& specular) {
  const Float one(1.0f);
  OrmSurface s;
  const Float metal = orm[2] * Float(params.metallic);
  const Float luminance = Float(0.2126f) * albedo[0] + Float(0.7152f) * albedo[1] + Float(0.0722f) * albedo[2];
  for (int c = 0; c < 3; ++c) s.albedo[c] = albedo[c] * (one - metal);
  s.specular = specular + (luminance - specular) * metal;
  s.roughness = xsimd::max(orm[1] * Float(lighting_roughness), Float(0.02f));
  s.occlusion = one + Float(params.occlusion_strength) * (orm[0] - one);
  return s;
}

Float specular_from_albedo(const Float* albedo, const SpecularFromAlbedo& coeffs, float fallback) {
  if (!coeffs.enabled) return Float(fallback);
  const Float one(1.0f);
  const Float luminance = Float(0.2126f) * albedo[0] + Float(0.7152f) * albedo[1] + Float(0.0722f) * albedo[2];
  const Float clamped = xsimd::min(xsimd::max(luminance, Float(0.0f)), one);
  const Float x = coeffs.invert ? one - clamped : clamped;
  return Float(coeffs.scale) * detmath::pow_uniform(x, coeffs.power);
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE::shading
