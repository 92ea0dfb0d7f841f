#pragma once
// The first shading program: albedo with tangent-space normal mapping, lit by the material's lighting model
// (lighting_models.hpp) from directional lights plus ambient.
#include <optional>

#include "program/light_rig.hpp"
#include "kernel/batch.hpp"
#include "qdmr/program/program_params.hpp"
#include "kernel/shading_math.hpp"
#include "kernel/sampler.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

class NormalMappingProgram final : public ShadingProgram {
public:
  // albedo: RGBA8 sRGB; normal: RGBA8 holding 0.5 + 0.5 n of tangent-space unit normals.
  // twin_texels: the two maps interleaved (texture/twin_texels.hpp), or null. orm: RGBA8 linear occlusion,
  // roughness and metalness sampled beside the albedo (ProgramKey::orm), or null. sampler: the key's modes (the
  // height fetch unread), sampler_params the LOD bias and clamp.
  NormalMappingProgram(const std::string& variant, const Texture& albedo, const Texture& normal, const float* twin_texels,
                       const Texture* orm, const OrmParams& orm_params, const SamplerModes& sampler,
                       const SamplerParams& sampler_params, LightingModel lighting_model, const LightingParams& lighting,
                       const SpecularFromAlbedo& specular, const LightRig& lights)
      : ShadingProgram(variant, kBaseVaryingCount),
        textures_(albedo, normal, SamplerState::from(sampler, sampler_params), twin_texels), lod_mode_(sampler.lod),
        lighting_model_(lighting_model), lighting_(lighting), specular_(specular), orm_params_(orm_params),
        lights_(lights) {
    if (orm) orm_.emplace(*orm, SamplerState::from(sampler, sampler_params));
  }
  BatchGrouping grouping() const override { return {2, 2 * simd::kLanes}; }
  void shade(const Fragments* const* in, ShadeOutput* const* out, int n) const override;

private:
  // The stages of a batch (batch_scheduler.hpp): the LODs, the polygon's frame, the samples, the lighting; no trace.
  // Orm: the ORM texture is sampled and applied (orm_ is set); both are instantiated, shade() picks one.
  template <bool Orm>
  class Stages;
  struct Samples;
  // Inline (defined in normal_mapping.cpp, its only user): out of line, each call of a pair's setup passed its
  // batches' values through the stack.
  inline shading::UvDerivatives derivatives(const Fragments& in) const;
  inline bool magnified(const shading::UvDerivatives& d) const;
  simd::Float albedo_lod(const shading::UvDerivatives& d) const;
  void albedo_lods(const shading::UvDerivatives& a, const shading::UvDerivatives& b, simd::Float& lod_a,
                   simd::Float& lod_b) const;
  inline simd::Float normal_lod(const shading::UvDerivatives& d, const simd::Float& albedo_lod) const;
  inline simd::Float orm_lod(const shading::UvDerivatives& d, const simd::Float& albedo_lod) const;
  // Lights a batch whose frame, shading normal and view vector are computed.
  template <bool Orm>
  void light(const Samples& samples, const shading::TangentFrame& frame, const shading::Vec3& shading_normal,
             const shading::Vec3& view, ShadeOutput& out) const;

  TwinSampler textures_;  // albedo first, normal map second
  LodMode lod_mode_;
  LightingModel lighting_model_;
  LightingParams lighting_;
  SpecularFromAlbedo specular_;
  std::optional<TextureSampler> orm_;
  OrmParams orm_params_;
  LightRig lights_;
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
