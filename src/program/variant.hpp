#pragma once
// Program variants: the options a material fixes that a displacement program's inner loops would otherwise test
// per iteration are template arguments of the program's trace (kernel/displacement.cpp instantiates every
// combination below, 23 per ISA). The plan derives the options from the material (trace_options) and names the
// variant; the program reports the name of the instantiation it runs, from its template arguments. A test checks
// that the two agree.
#include <string>

#include "qdmr/scene/scene.hpp"

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

// The options of a material, canonical: those its technique ignores are left at their defaults.
TraceOptions trace_options(const MaterialDesc& material);
// "relief", "pom", "csm", "rcsm", "normal", "qdm<int_cells,max_fetch,level_up_one>" (sm3_cells, fp64_walls).
std::string trace_variant_name(const TraceOptions& options);

// The whole variant as `qdmr plan` and the stats name it: the trace variant and the options the program reads
// per batch (blend, shadow, AO, lighting model, texture filter).
std::string program_variant(const MaterialDesc& material, const TraceOptions& trace);
inline std::string program_variant(const MaterialDesc& material) { return program_variant(material, trace_options(material)); }

const char* technique_name(TechniqueKind kind);  // "normal", "relief", "pom", "csm", "rcsm", "qdm"
const char* filter_name(Filter filter);          // "point", "bilinear", "trilinear", ...

}  // namespace qdmr
