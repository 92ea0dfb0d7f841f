#pragma once
// The scalar reference sampler: qdmr's documented sampling behaviour written plainly, one sample at a time,
// over Texture::texel() (which throws on any out-of-range texel). It shares no code with the SIMD sampler
// (src/kernel/sampler.cpp); the tests require the two to agree bit for bit in every lane.
//
// The behaviour (docs/sampling.md):
//  - non-finite u or v: level-0 texel (0, 0);
//  - u reduced exactly to one period first: wrap u - floor(u), mirror u - 2 floor(u / 2), clamp to [-1, 2];
//  - LOD l = lod + bias (NaN: the last level), clamped to [min_lod, max_lod] then [0, last]; hw8/hw6
//    precision keeps 8/6 fractional bits (rounded down);
//  - point/bilinear: level 0; *MipPoint: level floor(l + 0.5); trilinear and point-mip-linear: levels
//    floor(l) and floor(l) + 1 (at most the last), blended by the fraction of l;
//  - texel centres at (i + 0.5) / size; hw precision converts texel coordinates to fixed point with 8/6
//    fractional bits, rounding down, for both the index and the bilinear weight;
//  - math: the texel coordinate u * size (- 0.5 for bilinear taps) is floored as computed in fp32 (sm3) or
//    exactly (sm4, exact); without hw precision the weight is the fp32 coordinate minus the index.
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/mip_texture.hpp"

namespace qdmr {

// Every channel (texture.channels() of them) of the sample at (u, v) with an explicit LOD; out[c] for
// c >= channels is left untouched. Only filter, address, precision, math, lod_bias, min_lod and max_lod of
// `settings` are used.
void reference_sample(const Texture& texture, const SamplingDesc& settings, float u, float v, float lod, float out[4]);

// LOD of a pixel footprint from UV derivatives: log2 of the longer of the two footprint axes in level-0 texels
// (0.5 log2 of its square, detmath::log2); -64 for a zero or denormal footprint, the last level when a squared
// length is not finite.
float reference_lod(const Texture& texture, float dudx, float dvdx, float dudy, float dvdy);

}  // namespace qdmr
