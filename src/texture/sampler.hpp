#pragma once
// Sampling a mip chain for a batch of lanes (private: SIMD types of this build).
// Texel centres at (i + 0.5) / N; row 0 at v = 0. Results are bit-identical between SSE and AVX2 builds.
#include "core/simd.hpp"
#include "qdmr/scene/scene.hpp"
#include "qdmr/texture/texture.hpp"

namespace qdmr {

struct SamplerState {
  Filter filter = Filter::Trilinear;
  AddressMode address = AddressMode::Wrap;
  float lod_bias = 0.0f;
};

// LOD in level-0 texels from UV derivatives, GL formula: log2(max(|d(uv*size)/dx|, |d(uv*size)/dy|)).
// Computed with IEEE basic operations only (no libm), so every build gives the same bits.
simd::Float lod_from_derivatives(const MipChain& chain, const simd::Float& dudx, const simd::Float& dvdx,
                                 const simd::Float& dudy, const simd::Float& dvdy);

// Samples every channel of `chain` (1..4) at (u, v) with one LOD per lane (bias added here);
// out[c] receives channel c. Lanes with non-finite coordinates return level-0 texel (0,0).
void sample(const MipChain& chain, const SamplerState& state, const simd::Float& u, const simd::Float& v,
            const simd::Float& lod, simd::Float* out);

}  // namespace qdmr
