#pragma once
// A material's program as the plan chooses it: the key that fixes the program's code and the numbers it reads
// (qdmr/program/), resolved from the scene's MaterialDesc. What a program ignores is left at its default in
// both (the QDM options of other techniques, the blend of a single layer).
#include "qdmr/program/program_key.hpp"
#include "qdmr/program/program_params.hpp"
#include "qdmr/scene/scene.hpp"

namespace qdmr {

ProgramKey program_key(const MaterialDesc& material);
ProgramParams program_params(const MaterialDesc& material);

// The material's sampling split into the key's modes (with the technique's height fetch, or bilinear where no
// heights are read) and the parameters' numbers.
SamplerModes sampler_modes(const SamplingDesc& sampling, HeightFetch heights);
SamplerParams sampler_params(const SamplingDesc& sampling);

// The parts of program_params, each from its part of the material.
TraceParams trace_params(const TechniqueDesc& technique);
LightingParams lighting_params(const LightingDesc& lighting);
ShadowParams shadow_params(const ShadowDesc& shadow);
AoParams ao_params(const AoDesc& ao);

}  // namespace qdmr
