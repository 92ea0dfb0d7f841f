#pragma once
// The name of a material's shading program variant: what `qdmr plan` lists and what the program made for the
// material reports (RenderStats::materials) — one function, so the two cannot drift apart.
#include <string>

#include "qdmr/scene/scene.hpp"

namespace qdmr {

std::string program_variant(const MaterialDesc& material);

const char* technique_name(TechniqueKind kind);  // "normal", "relief", "pom", "csm", "rcsm", "qdm"
const char* filter_name(Filter filter);          // "point", "bilinear", "trilinear", ...

}  // namespace qdmr
