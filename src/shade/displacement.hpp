#pragma once
// Per-pixel displacement: a view ray in tangent space traced through the height field by one of the talk's
// techniques (relief, POM, QDM; CSM/RCSM with a cone map), then the surface shaded at the hit as in normal
// mapping. Optionally the exact fp64 reference is traced too, for the error AOVs.
#include <optional>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/study/heightfield.hpp"
#include "shade/lighting.hpp"
#include "shade/program.hpp"
#include "shade/shading_math.hpp"
#include "texture/sampler.hpp"

namespace qdmr {

struct DisplacementInputs {
  const Texture* albedo = nullptr;      // RGBA8 sRGB
  const Texture* normal = nullptr;      // RGBA8, 0.5 + 0.5 n
  const Texture* height = nullptr;      // box-filtered heights (relief, POM, refinement)
  const Texture* height_max = nullptr;  // max-quadtree (QDM); power-of-two sizes
  const ConeMap* cones = nullptr;       // CSM (conservative) / RCSM (relaxed): one ratio per level-0 texel of height
  const HeightField* reference = nullptr;  // level-0 heights in fp64, for error_texels / missed; may be null
  // qdm with bilinear-patch refinement: the fp64 heights solved exactly, and height_max built from
  // bilinear_upper_bound() of them (conservative for the bilinear surface).
  const HeightField* surface = nullptr;
};

class DisplacementProgram final : public ShadingProgram {
public:
  DisplacementProgram(const DisplacementInputs& inputs, const MaterialDesc& material, const LightRig& lights);
  void shade(const Fragments& in, ShadeOutput& out) const override;

  // The view ray in UV/depth space: uv(s) = uv0 + duv * s for depth s in [0, depth_scale].
  struct Ray {
    simd::Float u0, v0, du, dv;
  };
  struct Hit {
    simd::Float s;           // depth of the hit
    simd::Float iterations;  // loop iterations per lane
  };

private:
  simd::Float height_at(const simd::Float& u, const simd::Float& v, const simd::Float& lod) const;
  Hit relief(const Ray& ray, const simd::Float& depth_scale, const simd::Float& lod, simd::Mask active) const;
  Hit pom(const Ray& ray, const simd::Float& depth_scale, const simd::Float& lod, const simd::Float& cos_view,
          simd::Mask active) const;
  Hit qdm(const Ray& ray, const simd::Float& depth_scale, const simd::Float& stop_level, const simd::Int& cap,
          simd::Mask active) const;
  Hit cone_step(const Ray& ray, const simd::Float& depth_scale, simd::Mask active) const;
  void cone_texel(const simd::Int& x, const simd::Int& y, simd::Float& height, simd::Float& ratio) const;
  simd::Float refine(const Ray& ray, const simd::Float& depth_scale, const simd::Float& s_hit, simd::Float& iterations,
                     simd::Mask active) const;
  simd::Float bilinear_patch(const Ray& ray, const simd::Float& depth_scale, const simd::Float& s_start,
                             simd::Float& iterations, simd::Mask active) const;
  void displaced_depth(const Fragments& in, const shading::UvDerivatives& d, const shading::TangentFrame& frame,
                       const Ray& ray, const simd::Float& s, ShadeOutput& out) const;
  void reference_errors(const Ray& ray, const simd::Float& depth_scale, const Hit& hit, const simd::Mask& covered,
                        ShadeOutput& out) const;

  TextureView albedo_, normal_;
  std::optional<TextureView> height_, height_max_;
  const ConeMap* cones_;
  const HeightField* reference_;
  const HeightField* surface_;
  SamplerState sampler_;
  LodMode lod_mode_;
  MathMode math_;
  TechniqueDesc technique_;
  LightingDesc lighting_;
  LightRig lights_;
};

}  // namespace qdmr
