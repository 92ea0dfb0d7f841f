#pragma once
// Texture module internals shared between its .cpp files and tests.
#include <array>

#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr::texture_detail {

// The pattern of `desc`: channel 0 the height in [0,1]; with_cells adds channel 1, for patterns made of cells
// (bricks, stones, spikes, steps, checker squares) a per-cell value in [0,1) for colour variation, else 0.5.
Image generate_pattern(const ProceduralDesc& desc, bool with_cells);

// The exact piecewise sRGB decode (IEC 61966-2-1), evaluated in double and rounded to float.
float srgb_to_linear(float c);

// srgb_to_linear(k / 255) for every byte k: the sampler's decode table. Built before main by baseline code (a
// kernel's own static initialiser would run AVX code on any CPU; a function-local static would test its guard at
// every fetch).
extern const std::array<float, 256> kSrgbByteToLinear;

// Strength 1 of a from_height normal map: the surface of h in [0,1] is this deep in UV units of one repeat.
inline constexpr double kFromHeightDepth = 1.0 / 16.0;

}  // namespace qdmr::texture_detail
