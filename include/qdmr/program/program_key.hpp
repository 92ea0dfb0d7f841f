#pragma once
// What fixes the code a material's shading program runs, as the plan hands it to the kernel (Kernel::make_program):
// which program (normal mapping or displacement), which instantiation of the trace (the options its inner loops
// would otherwise test per iteration are template arguments: kernel/displacement.cpp instantiates every trace
// variant, 23 per ISA), and the modes the program branches on per batch. Printed, it is the variant `qdmr plan`
// and the stats name. The numbers the program reads are its ProgramParams (program_params.hpp); the plan makes
// both from a material (MaterialPlan::key, MaterialPlan::params).
#include <string>

#include "qdmr/core/sampling.hpp"
#include "qdmr/core/material_modes.hpp"

namespace qdmr {

struct TraceOptions {
  TechniqueKind technique = TechniqueKind::Normal;
  // qdm: sm4 steps integer cells, sm3 finds them again from the fp32 position after a crossing (SM3 emulation),
  // exact steps integer cells and computes wall crossings in fp64.
  MathMode math = MathMode::Sm4;
  bool filtered_max = false;  // qdm: LinearMipMapLinear over the max chain (height_fetch trilinear)
  QdmLevelUp level_up = QdmLevelUp::One;  // qdm
  bool operator==(const TraceOptions&) const = default;
};

// The sampler states a material fixes (its scene `sampling` and the technique's height fetch): what the samplers'
// code is specialised for (kernel/sampler.hpp's SamplerKey adds the texture's format and sRGB flag, which the
// texture itself carries). The LOD bias and clamp are numbers, ProgramParams::sampler.
struct SamplerModes {
  Filter filter = Filter::Trilinear;
  AddressMode address = AddressMode::Wrap;
  SamplePrecision precision = SamplePrecision::Exact;  // filter weights and LOD fraction
  LodMode lod = LodMode::PerQuad;
  // Texel addresses floor the fp32 texel coordinate (sm3 math), not the exact one (sm4 and exact math, which the
  // samplers do not tell apart; QDM's walk does: TraceOptions::math).
  bool fp32_texels = false;
  // The displacement program's height fetch (point, bilinear or the filter above); normal mapping reads no heights.
  HeightFetch heights = HeightFetch::Bilinear;
  bool operator==(const SamplerModes&) const = default;
};

// Canonical: what a program ignores is left at its default (the QDM options of other techniques, the blend of one
// layer, the height fetch of normal mapping), so equal keys mean the same program.
struct ProgramKey {
  TraceOptions trace;
  int layers = 1;                               // 1 .. 4
  BlendOperator blend = BlendOperator::Height;  // more than one layer
  WeightMode weights = WeightMode::Pixel;       // more than one layer
  ShadowMode shadow = ShadowMode::Off;
  AoMode ao = AoMode::Off;
  LightingModel lighting = LightingModel::BlinnPhong;
  SamplerModes sampler;
  // A single layer's occlusion-roughness-metal texture is sampled beside the albedo (LayerDesc::orm).
  bool orm = false;
  // Normal mapping runs its own program; every other key a displacement program.
  bool normal_mapping() const { return trace.technique == TechniqueKind::Normal && layers == 1; }
  bool operator==(const ProgramKey&) const = default;
};

// "relief", "pom", "csm", "rcsm", "normal", "qdm<int_cells,max_fetch,level_up_one>" (sm3_cells, fp64_walls).
std::string trace_variant_name(const TraceOptions& options);
// The key printed: "normal_mapping" or "displacement:<trace variant>", then " | "-separated blend, shadow, AO,
// lighting model, sampler modes and "orm" when set, e.g. "displacement:pom | shadow hard | blinn_phong | trilinear".
// The sampler modes are the filter, then each state that is not its default: "clamp" or "mirror", "hw8" or "hw6",
// "per_pixel_lod", "sm3_texels", "point_heights" or "trilinear_heights" (the second and last not for QDM, whose
// trace variant already says sm3_cells and filtered_max), e.g. "bilinear clamp hw8".
std::string variant_name(const ProgramKey& key);

const char* technique_name(TechniqueKind kind);  // "normal", "relief", "pom", "csm", "rcsm", "qdm"
const char* filter_name(Filter filter);          // "point", "bilinear", "trilinear", ...

}  // namespace qdmr
