#pragma once
// Per-pixel displacement: a view ray in tangent space traced through the height field by one of the talk's
// techniques (relief, POM, QDM; CSM/RCSM with a cone map), then the surface shaded at the hit as in normal
// mapping. Up to four layers are blended into one surface (blended_surface.hpp) and their colours by the
// material's blend operator. Optionally the exact fp64 reference is traced too, for the error AOVs.
#include <optional>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "shade/blended_surface.hpp"
#include "shade/height_surface.hpp"
#include "program/light_rig.hpp"
#include "shade/lighting_models.hpp"
#include "program/batch.hpp"
#include "program/inputs.hpp"
#include "program/variant.hpp"
#include "shade/shading_math.hpp"
#include "texture/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// A trace variant: the options of program/variant.hpp as compile-time constants of the inner loops.
template <TechniqueKind T, bool Sm3Cells = false, bool FilteredMax = false, QdmLevelUp LevelUp = QdmLevelUp::One>
struct Trace {
  static constexpr TechniqueKind technique = T;
  static constexpr bool sm3_cells = Sm3Cells;
  static constexpr bool filtered_max = FilteredMax;
  static constexpr QdmLevelUp level_up = LevelUp;
  static TraceOptions options() { return {T, Sm3Cells, FilteredMax, LevelUp}; }
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
    simd::Float box_s;       // qdm, csm, rcsm: the hit on the level-0 box surface, before refinement; else s
  };

private:
  struct Layer {
    TextureView albedo, normal;
    std::optional<TextureView> height, height_max, ao;
    SpecularFromAlbedo specular;
  };
  // What shade() computes before the surface is known: the frame, the ray and the depth scale.
  struct Setup;
  // The instantiation of shade_variant for a material's trace options, and the options of the type it runs.
  using ShadeFn = void (DisplacementProgram::*)(const Fragments&, ShadeOutput&) const;
  struct Variant {
    ShadeFn shade;
    TraceOptions options;
  };
  static Variant select(const TraceOptions& options);
  template <class V>
  static Variant variant();

  SingleLayerSurface layer_surface(int i) const;
  template <class V>
  void shade_variant(const Fragments& in, ShadeOutput& out) const;
  template <class V, class Surface>
  void shade_surface(const Fragments& in, const Setup& setup, const Surface& surface, ShadeOutput& out) const;
  template <class V, class Surface>
  Hit trace(const Surface& surface, const Setup& setup, simd::Float& ds) const;
  template <class Surface>
  Hit relief(const Surface& surface, const Ray& ray, const simd::Float& depth_scale, const simd::Float& lod,
             simd::Mask active) const;
  template <class Surface>
  Hit pom(const Surface& surface, const Ray& ray, const simd::Float& depth_scale, const simd::Float& lod,
          const simd::Float& cos_view, simd::Mask active) const;
  template <class V, class Surface>
  Hit qdm(const Surface& surface, const Ray& ray, const simd::Float& depth_scale, const simd::Float& stop_level,
          const simd::Int& cap, simd::Mask active) const;
  template <class Surface>
  simd::Float refine(const Surface& surface, const Ray& ray, const simd::Float& depth_scale, const simd::Float& s_hit,
                     simd::Float& iterations, simd::Mask active) const;
  template <class V>
  Hit cone_step(const Ray& ray, const simd::Float& depth_scale, simd::Mask active) const;
  void cone_texel(const simd::Int& x, const simd::Int& y, simd::Float& height, simd::Float& ratio) const;
  simd::Float bilinear_patch(const Ray& ray, const simd::Float& depth_scale, const simd::Float& s_start,
                             simd::Float& iterations, simd::Mask active) const;
  void displaced_depth(const Fragments& in, const shading::UvDerivatives& d, const shading::TangentFrame& frame,
                       const Ray& ray, const simd::Float& s, ShadeOutput& out) const;
  template <class Surface>
  void light(const Fragments& in, const Setup& setup, const Surface& surface, const Hit& hit, const simd::Float& ds,
             const simd::Float* albedo, const simd::Float& specular, const simd::Float& baked_ao,
             const shading::Vec3& shading_normal, ShadeOutput& out) const;
  void reference_errors(const Ray& ray, const simd::Float& depth_scale, const Hit& hit, const simd::Mask& covered,
                        ShadeOutput& out) const;

  ShadeFn shade_;
  std::vector<Layer> layers_;
  std::optional<TextureView> weights_;
  std::optional<TextureView> combined_;
  int combined_period_ = 0;
  std::optional<TextureView> blend_ao_;
  int blend_ao_scale_ = 1;
  const ConeMap* cones_;
  const HeightField* reference_;
  int reference_scale_;
  const HeightField* surface_;
  SamplerState sampler_;
  LodMode lod_mode_;
  TechniqueDesc technique_;
  LightingDesc lighting_;
  BlendDesc blend_;
  ShadowDesc shadow_;
  AoDesc ao_;
  LightRig lights_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
