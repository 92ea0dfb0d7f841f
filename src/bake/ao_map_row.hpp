#pragma once
// The kernels' entry points for a baked AO map's rows (bake/ao_map.hpp bakes with them), apart from the map's
// scene-facing functions: the kernels see this, not the scene's AoDesc.
#include <type_traits>

#include "bake/ao_texel.hpp"

namespace qdmr {

// Row j of a map (map width floats into row) by a kernel's vectors (Kernel::ao_map_row, which preparation passes
// so that `--isa` holds there too), one function per stored height type. Every row function gives the definition's
// bits; a null one (the default) bakes by the definition texel by texel (scalar, baseline x86-64).
template <class T>
using AoRowOf = void (*)(const ao::Bake<T>& bake, int j, float* row);
struct AoMapRow {
  AoRowOf<double> f64 = nullptr;
  AoRowOf<float> f32 = nullptr;

  template <class T>
  AoRowOf<T> of() const {
    if constexpr (std::is_same_v<T, float>) return f32;
    else return f64;
  }
};

}  // namespace qdmr
