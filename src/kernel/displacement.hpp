#pragma once
// Per-pixel displacement: a view ray in tangent space traced through the height field by one of the talk's
// techniques (one file each: relief.hpp, pom.hpp, qdm.hpp, cone_step.hpp, then refine.hpp), then the surface
// shaded at the hit as in normal mapping. Up to four layers are blended into one surface (blended_surface.hpp)
// and their colours by the material's blend operator. Optionally the exact fp64 reference is traced too, for the error AOVs.
#include <array>
#include <optional>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/texture/heightfield.hpp"
#include "kernel/blended_surface.hpp"
#include "kernel/height_surface.hpp"
#include "program/light_rig.hpp"
#include "kernel/lighting_models.hpp"
#include "kernel/batch.hpp"
#include "program/inputs.hpp"
#include "qdmr/program/program_key.hpp"
#include "qdmr/program/program_params.hpp"
#include "kernel/shading_math.hpp"
#include "kernel/trace_ray.hpp"
#include "kernel/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// A trace variant: the TraceOptions of a ProgramKey as compile-time constants of the inner loops.
template <TechniqueKind T, MathMode Math = MathMode::Sm4, bool FilteredMax = false,
          QdmLevelUp LevelUp = QdmLevelUp::One>
struct Trace {
  static constexpr TechniqueKind technique = T;
  static constexpr MathMode math = Math;
  static constexpr bool filtered_max = FilteredMax;
  static constexpr QdmLevelUp level_up = LevelUp;
  static TraceOptions options() { return {T, Math, FilteredMax, LevelUp}; }
};

class DisplacementProgram final : public ShadingProgram {
public:
  DisplacementProgram(const DisplacementInputs& inputs, const ProgramKey& key, const ProgramParams& params,
                      const LightRig& lights);
  // QDM, relief and POM take pairs (blends: up to LaneCompaction::kMaxBatches sparse batches); the others one.
  BatchGrouping grouping() const override;
  void shade(const Fragments* const* in, ShadeOutput* const* out, int n) const override;

  using Ray = trace::Ray;
  using Hit = trace::Hit;

private:
  struct Layer {
    TwinSampler textures;  // albedo first, normal map second
    std::optional<HeightLayerTextures> height;  // and its max chain
    std::optional<TextureSampler> ao;          // bilinear
    SpecularFromAlbedo specular;
    std::optional<TextureSampler> orm;         // occlusion, roughness, metalness (ProgramKey::orm)
  };
  // What shade() computes before the surface is known: the frame, the ray and its depth range (the only one).
  struct Setup;
  // The instantiation of shade_variant for a material's trace options, and the options of the type it runs.
  using ShadeFn = void (DisplacementProgram::*)(const Fragments* const*, ShadeOutput* const*, int) const;
  struct Variant {
    ShadeFn shade;
    TraceOptions options;
  };
  // QDM's lowest level and iteration cap per lane.
  struct QdmBudget {
    simd::Float stop_level;
    simd::Int cap;
  };
  static Variant select(const TraceOptions& options);
  template <class V>
  static Variant variant();
  DisplacementProgram(const DisplacementInputs& inputs, const ProgramKey& key, const ProgramParams& params,
                      const LightRig& lights, const Variant& variant);

  SingleLayerSurface layer_surface(int i) const;
  // A blend's layers (the last one repeated past the layer count) and its surface for one batch.
  using LayerSurfaces = std::array<SingleLayerSurface, BlendedSurface::kMaxLayers>;
  LayerSurfaces layer_surfaces() const;
  BlendedSurface blended_surface(const LayerSurfaces& layers, const Fragments& in, const Setup& setup) const;
  Setup setup_for(const Fragments& in) const;
  // The techniques whose batches are shaded in pairs (grouping()).
  static constexpr bool pairs_technique(TechniqueKind k) {
    return k == TechniqueKind::Qdm || k == TechniqueKind::Relief || k == TechniqueKind::Pom;
  }
  // The stages of a batch (batch_scheduler.hpp) over one layer's surface or a blend's: setup_for, the trace (and,
  // for QDM and one layer's relief, trace_pair), surface_at_hit, light_hit, the displaced depth; run by
  // shade_in_stages for the instantiation V.
  template <class V, class Surface>
  class Stages;
  struct SurfaceAtHit;
  template <class V>
  void shade_variant(const Fragments* const* in, ShadeOutput* const* out, int n) const;
  template <class Surface>
  void surface_at_hit(const Setup& setup, const Surface& surface, const Hit& hit, SurfaceAtHit& at) const;
  template <class V, class Surface>
  void walk_pair(const Surface& surface_a, const Setup& setup_a, Hit& hit_a, const Surface& surface_b,
                 const Setup& setup_b, Hit& hit_b) const;
  template <class V, class Surface>
  void light_hit(const Fragments& in, const Setup& setup, const Surface& surface, const SurfaceAtHit& at,
                 ShadeOutput& out) const;
  QdmBudget qdm_budget(const Setup& setup) const;
  template <class V, class Surface>
  Hit trace(const Surface& surface, const Setup& setup) const;
  // A QDM walk's hit on the box surface, refined on the filtered one as the technique asks.
  template <class Surface>
  Hit refine_qdm_hit(const Surface& surface, const Setup& setup, Hit hit) const;
  void refine_qdm_hits(const SingleLayerSurface& surface, const Setup& setup_a, Hit& hit_a, const Setup& setup_b,
                       Hit& hit_b) const;
  void displaced_depth(const Fragments& in, const shading::UvDerivatives& d, const shading::TangentFrame& frame,
                       const Ray& ray, const simd::Float& s, ShadeOutput& out) const;
  template <class Surface>
  void light(const Fragments& in, const Setup& setup, const Surface& surface, const Hit& hit,
             const simd::Float* albedo, const simd::Float& specular, const simd::Float& baked_ao,
             const simd::Float* roughness, const simd::Float* occlusion, const shading::Vec3& shading_normal,
             ShadeOutput& out) const;
  // Calls per_lane(lane, ray in the reference's UV, its hit) for each covered lane.
  template <class PerLane>
  void trace_reference(const Ray& ray, const simd::Float& depth_scale, const simd::Mask& covered,
                       PerLane per_lane) const;
  void reference_errors(const Ray& ray, const simd::Float& depth_scale, const Hit& hit, const simd::Mask& covered,
                        ShadeOutput& out) const;
  Hit exact_hit(const Ray& ray, const simd::Float& depth_scale, const Hit& traced, const simd::Mask& covered) const;

  ShadeFn shade_;
  std::vector<Layer> layers_;
  std::optional<TextureSampler> weights_;
  std::optional<TextureSampler> combined_;
  int combined_period_u_ = 0, combined_period_v_ = 0;
  const LayerHeights* layer_heights_ = nullptr;  // with combined_ only
  const float* box_values_ = nullptr;            // with layer_heights_ only
  std::optional<TextureSampler> blend_ao_;
  int blend_ao_scale_ = 1;
  const ConeMap* cones_;
  const HeightField* reference_;
  int reference_scale_;
  ReferenceMemo* reference_memo_;
  std::uint64_t reference_id_;
  const HeightField* surface_;
  SamplerState sampler_;
  ProgramKey key_;
  TraceParams trace_;
  LightingParams lighting_;
  OrmParams orm_params_;
  BlendParams blend_;
  ShadowParams shadow_;
  AoParams ao_;
  LightRig lights_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
