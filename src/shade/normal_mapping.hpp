#pragma once
// The first shading program: albedo with tangent-space normal mapping, Blinn-Phong from directional
// lights plus ambient.
#include "shade/lighting.hpp"
#include "shade/program.hpp"
#include "texture/sampler.hpp"

namespace qdmr {

struct SurfaceTextures {
  const MipChain* albedo = nullptr;  // 3 channels, linear RGB
  const MipChain* normal = nullptr;  // 3 channels, tangent-space unit vectors
  SamplerState sampler;
};

class NormalMappingProgram final : public ShadingProgram {
public:
  NormalMappingProgram(SurfaceTextures textures, const LightingDesc& lighting, const LightRig& lights)
      : textures_(textures), lighting_(lighting), lights_(lights) {}
  void shade(const Fragments& in, ShadeOutput& out) const override;

private:
  SurfaceTextures textures_;
  LightingDesc lighting_;
  LightRig lights_;
};

}  // namespace qdmr
