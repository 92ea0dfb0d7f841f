#pragma once
// The lighting models of a material (ProgramKey::lighting), lit by a LightRig, per lane:
//   color = albedo * (ambient * ao + sum_i radiance_i * visibility_i * n.l_i) + sum_i radiance_i * visibility_i * spec_i
// with n.l_i = max(dot(shading normal, l_i), 0) and spec_i gated to 0 when the light is below the polygon
// (dot(geometric normal, l_i) <= 0). The diffuse term is Lambert with the 1/pi folded into the radiance
// (radiance 1 head-on lights a white surface to 1), so both specular terms carry the same factor pi.
//   Blinn-Phong:   spec = max(n.h, 0)^shininess * specular * min(8 n.l, 1)    (as the programs computed it before Cook-Torrance)
//   Cook-Torrance: spec = pi * D * Vis * F * n.l, the GGX microfacet BRDF with
//     alpha = roughness^2, D = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2),
//     Vis = G / (4 n.l n.v) = 0.5 / (n.l sqrt((n.v)^2 (1 - alpha^2) + alpha^2) + n.v sqrt((n.l)^2 (1 - alpha^2) + alpha^2))
//           (height-correlated Smith, Heitz 2014), F = F0 + (1 - F0) (1 - v.h)^5 (Schlick), F0 = specular,
//     where n.v, n.h and v.h are clamped to >= 0. Single scattering: the specular energy never exceeds 1.
// Lane-wise IEEE only; pow through detmath.
#include "core/simd.hpp"
#include "qdmr/program/program_params.hpp"
#include "program/light_rig.hpp"
#include "kernel/shading_math.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE::shading {

struct SurfaceSample {
  const Float* albedo;      // 3 channels, linear RGB
  Float specular;           // Blinn-Phong: highlight scale; Cook-Torrance: F0 (reflectance at normal incidence)
  Float ambient_occlusion;  // multiplies the ambient light; 1 = open
  const Float* roughness = nullptr;  // Cook-Torrance: per lane (apply_orm), or null for LightingParams::roughness
};

// What an ORM sample (R occlusion, G roughness, B metalness; ProgramKey::orm) makes of a surface, per lane: metalness
// m = B * metallic scales the albedo by 1 - m and moves the specular (F0) from `specular`, the dielectric's, towards
// the albedo's Rec. 709 luminance: F0 = specular + (luminance - specular) m (a scalar F0: qdmr's specular light is
// untinted); roughness = max(G * lighting_roughness, 0.02) (GGX's alpha^2 must stay > 0); the ambient occlusion
// `occlusion` = 1 + occlusion_strength (R - 1). With (1, 1, 1) and metallic 0 every value is the one it replaces, bit for bit.
struct OrmSurface {
  Float albedo[3], specular, roughness, occlusion;
};
OrmSurface apply_orm(const Float* orm, const OrmParams& params, float lighting_roughness, const Float* albedo,
                     const Float& specular);

// light_visibility: one factor per directional light of the rig (1 = lit, 0 = shadowed), or nullptr for all lit.
// LightingParams::specular is not read: the caller puts it (or specular_from_albedo) into surface.specular.
void shade_lights(const Vec3& shading_normal, const Vec3& geometric_normal, const Vec3& view, const SurfaceSample& surface,
                  const Float* light_visibility, LightingModel model, const LightingParams& lighting, const LightRig& lights,
                  Float* color);

// The specular reflectance of SpecularFromAlbedo: scale * pow(x, power) with x the Rec. 709 luminance
// 0.2126 r + 0.7152 g + 0.0722 b of the albedo clamped to [0, 1], or 1 - that when inverted (x = 0 gives 0).
// `fallback` (the material's LightingParams::specular) when coeffs.enabled is false.
Float specular_from_albedo(const Float* albedo, const SpecularFromAlbedo& coeffs, float fallback);

}  // namespace qdmr::QDMR_ISA_NAMESPACE::shading
