#pragma once
// The sRGB decode the samplers and the texture module share (apart from texture/internal.hpp, which speaks of
// the scene's procedural patterns: the kernels see only this).
#include <array>

namespace qdmr::texture_detail {

// The exact piecewise sRGB decode (IEC 61966-2-1), evaluated in double and rounded to float.
float srgb_to_linear(float c);

// srgb_to_linear(k / 255) for every byte k: the sampler's decode table. Built before main by baseline code (a
// kernel's own static initialiser would run AVX code on any CPU; a function-local static would test its guard at
// every fetch).
extern const std::array<float, 256> kSrgbByteToLinear;

}  // namespace qdmr::texture_detail
