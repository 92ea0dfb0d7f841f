#pragma once
// A row of a baked AO map with this ISA's vectors (bake/ao_map.hpp's definition, the same bits as
// bake/ao_texel.hpp's scalar form): Kernel::ao_map_row.
#include "bake/ao_texel.hpp"
#include "core/isa_namespace.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Texels 0 .. bake.map_width - 1 of row j into row, from heights stored as double or as float.
void ao_map_row(const ao::Bake<double>& bake, int j, float* row);
void ao_map_row(const ao::Bake<float>& bake, int j, float* row);

}  // namespace qdmr::QDMR_ISA_NAMESPACE
